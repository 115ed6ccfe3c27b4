// Image files are written by a module loaded on first use, libnurbsrt_image.so
// (renderer/output/image_writer/), not by code linked into the programs: Debian 12
// builds OpenImageIO against ~260 shared libraries (OpenCV with its video I/O,
// FFmpeg, DCMTK, OpenVDB, ...), whose relocation would add a large share of a
// second to every nurbsrt process's start, before main. Commands that write no
// image (info, convert, a service before its first render) do not pay it. The
// module lives beside the executable, as nurbsrt-worker does, or on the library
// search path.
#pragma once

#include <cstddef>
#include <string>

namespace nurbsrt {

struct RenderImage;

// What the module's entry point answers.
enum ImageWriteStatus : int { kImageWritten = 0, kImageFormatUnsupported = 1, kImageIoError = 2 };

// The module's file name and its entry point, looked up by name (C linkage). The
// version suffix changes with the entry point's signature or RenderImage's layout.
inline constexpr const char* kImageModuleFile = "libnurbsrt_image.so";
inline constexpr const char* kImageWriteSymbol = "nurbsrt_write_image_v1";
inline constexpr const char* kImageEncodeSymbol = "nurbsrt_encode_image_v1";
inline constexpr const char* kImageLabelSymbol = "nurbsrt_draw_label_v1";

// The path the module will be loaded from: beside the executable, else the
// first directory of LD_LIBRARY_PATH or of the system's library directories
// that holds it. Throws Error(internal) naming the file and where it was looked
// for when none does. Cheap (a few stat calls, nothing loaded): a program that
// will write an image calls it before its other work, so that an install
// without the module fails at once, not after an import or at the first
// render; the loading itself still overlaps that work (ImageWriterPreload).
std::string locate_image_module();

// Loads the module on a thread of its own while the program goes on: a program
// that will write an image creates one early, so that the loading overlaps its
// other work. Errors surface at write_image (render.h), which loads it
// otherwise. The destructor waits for the loading to end: a process must not
// exit while the loader runs the constructors of the module's libraries in
// another thread (exit's destructors under them crashed a service stopped
// right after its start, in libproj's initializer, 4 times in 30). One per
// process at a time.
class ImageWriterPreload {
public:
    ImageWriterPreload();
    ~ImageWriterPreload();
    ImageWriterPreload(const ImageWriterPreload&) = delete;
    ImageWriterPreload& operator=(const ImageWriterPreload&) = delete;
};

}  // namespace nurbsrt

// Writes `image` to `path` as write_image (render.h) describes; on failure a
// NUL-terminated message of at most message_size bytes. Never throws.
extern "C" int nurbsrt_write_image_v1(const nurbsrt::RenderImage* image, const char* path, char* message,
                                      size_t message_size);
// Encodes `image` as a file of format `format_name` (an extension: png, tif, ...)
// would hold it, and hands the bytes to `sink` once; on failure sink is not
// called and the message is set as above. Never throws.
// Draws `text` into image->rgba with its top-left corner at pixel (x, y),
// `size` pixels high, in colour rgb (linear) at full alpha, with a font of the
// system's (DejaVu Sans, Debian's fonts-dejavu-core). Never throws.
extern "C" int nurbsrt_draw_label_v1(nurbsrt::RenderImage* image, int x, int y, int size, const char* text,
                                     const float rgb[3], char* message, size_t message_size);
extern "C" int nurbsrt_encode_image_v1(const nurbsrt::RenderImage* image, const char* format_name,
                                       void (*sink)(void* context, const void* bytes, size_t size), void* context,
                                       char* message, size_t message_size);
