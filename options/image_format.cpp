#include "options/image_format.h"
#include "core/ascii.h"

#include <cctype>

namespace nurbsrt {

ImageFormat image_format_of_extension(std::string ext) {
    if (!ext.empty() && ext[0] == '.') ext.erase(0, 1);
    ext = ascii_lower(ext);
    if (ext == "png") return ImageFormat::png;
    if (ext == "jpg" || ext == "jpeg") return ImageFormat::jpeg;
    if (ext == "tif" || ext == "tiff") return ImageFormat::tiff;
    if (ext == "exr") return ImageFormat::exr;
    return ImageFormat::other;
}

OutputFormat output_format(ImageFormat kind) {
    switch (kind) {
        case ImageFormat::jpeg:
            return {kind, "jpeg", ".jpg", "image/jpeg"};
        case ImageFormat::tiff:
            return {kind, "tiff", ".tif", "image/tiff"};
        case ImageFormat::exr:
            return {kind, "exr", ".exr", "image/x-exr"};
        default:
            return {ImageFormat::png, "png", ".png", "image/png"};
    }
}

}  // namespace nurbsrt
