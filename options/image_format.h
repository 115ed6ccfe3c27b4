// The image formats of a render: decided once, from the API's `format` or the
// CLI's file extension, and carried as an enum to the encoder.
#pragma once

#include <cstdint>
#include <string>

namespace nurbsrt {

// The image formats, decided once from the API's `format` or the CLI's file
// extension; `other`: a file extension the CLI hands to OpenImageIO as it is.
enum class ImageFormat : uint8_t { png, jpeg, tiff, exr, other };
// By extension, with or without its dot, any case: png, jpg/jpeg, tif/tiff, exr.
ImageFormat image_format_of_extension(std::string extension);

struct OutputFormat {
    ImageFormat kind = ImageFormat::png;
    std::string name;          // png, jpeg, tiff, exr
    std::string extension;     // .png, .jpg, .tif, .exr
    std::string content_type;  // image/png, ...
};
// The API's output format of each kind (not `other`).
OutputFormat output_format(ImageFormat kind);

}  // namespace nurbsrt
