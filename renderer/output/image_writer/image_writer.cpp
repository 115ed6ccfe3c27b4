// The image writer module, libnurbsrt_image.so: every image file nurbsrt writes
// goes through OpenImageIO here. It is a module of its own, loaded on first use
// (renderer/image_module.h says why), with two entry points of C linkage: to a
// file, and into memory (a service answer, with no file to write and read back).
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "renderer/image_module.h"
#include "renderer/render.h"
#include "core/ascii.h"

namespace nurbsrt {
namespace {

using namespace OIIO;

// The 8-bit sRGB code (IEC 61966-2-1 transfer function) of a linear value in
// [0, 1], without a pow per channel (which took ~70 ms of an 800x600 PNG's
// encoding): code c is chosen when x lies at or above the linear value whose
// encoding is exactly halfway between codes c-1 and c, i.e. the result is
// round(255 encode(x)). A 4096-bin table gives the code at each bin's start; a
// bin spans less than one code (the steepest slope, 12.92 x 255 codes per unit
// near black, is 0.8 codes per bin), so at most one boundary needs checking.
class Srgb8 {
public:
    Srgb8() {
        auto decode = [](double y) { return y <= 0.04045 ? y / 12.92 : std::pow((y + 0.055) / 1.055, 2.4); };
        for (int c = 1; c < 256; ++c) bound_[c] = static_cast<float>(decode((c - 0.5) / 255.0));
        bound_[0] = 0.0f;
        bound_[256] = 2.0f;  // above every clamped input
        int c = 0;
        for (int b = 0; b < kBins; ++b) {
            const float x = static_cast<float>(b) / kBins;
            while (bound_[c + 1] <= x) ++c;
            bin_[b] = static_cast<uint8_t>(c);
        }
    }
    uint8_t operator()(float x) const {
        x = std::clamp(x, 0.0f, 1.0f);  // NaN stays NaN here and gives 0 below
        if (!(x > 0.0f)) return 0;
        int c = bin_[std::min(static_cast<int>(x * kBins), kBins - 1)];
        if (bound_[c + 1] <= x) ++c;
        return static_cast<uint8_t>(c);
    }

private:
    static constexpr int kBins = 4096;
    float bound_[257];
    uint8_t bin_[kBins];
};

// PNG rows unfiltered: the renders are flat background and smooth shading, where
// zlib alone compresses better than after libpng's adaptive filters, and in half
// the time.
constexpr int kPngFilterNone = 8;  // libpng's PNG_FILTER_NONE

// zlib level 3 for PNG and TIFF, not the default 6: the encoding is a service
// answer's largest cost after the frame, and level 3 halves it for files ~40 %
// larger. Level 1 saves little more and loses more size.
constexpr int kZlibLevel = 3;

// OpenImageIO compresses a TIFF's strips in parallel only when its thread pool
// has two workers or more (TIFFOutput::write_scanlines), and it sizes the pool
// one below its "threads" (the calling thread takes part): on 2 cores, never.
// One more thread than cores gives the pool a worker per core (PNG, one zlib
// stream, stays serial).
void size_thread_pool() {
    static const bool sized = [] {
        OIIO::attribute("threads", static_cast<int>(std::max(1u, std::thread::hardware_concurrency())) + 1);
        return true;
    }();
    (void)sized;
}

// The lower-cased extension of a file name ("" without one).
std::string extension_of(const std::string& name) {
    const size_t dot_pos = name.rfind('.');
    return dot_pos == std::string::npos ? "" : ascii_lower(std::string_view(name).substr(dot_pos + 1));
}

// An image as OpenImageIO takes it: its spec and its pixels in that layout.
struct Encodable {
    ImageSpec spec;
    std::vector<uint8_t> pixels;
};

// EXR: every AOV as a channel of its own (RenderImage's AOVs).
Encodable exr_pixels(const RenderImage& img) {
    const size_t npx = static_cast<size_t>(img.width) * img.height;
    Encodable e;
    e.spec = ImageSpec(img.width, img.height, 12, TypeDesc::FLOAT);
    e.spec.channelnames = {"R", "G", "B", "A", "Z", "face", "N.X", "N.Y", "N.Z", "u", "v", "iterations"};
    e.spec.channelformats = {TypeDesc::FLOAT, TypeDesc::FLOAT,  TypeDesc::FLOAT, TypeDesc::FLOAT,
                             TypeDesc::FLOAT, TypeDesc::UINT32, TypeDesc::FLOAT, TypeDesc::FLOAT,
                             TypeDesc::FLOAT, TypeDesc::FLOAT,  TypeDesc::FLOAT, TypeDesc::UINT32};
    e.spec.alpha_channel = 3;
    e.spec.z_channel = 4;
    struct Px {
        float r, g, b, a, z;
        uint32_t face;
        float nx, ny, nz, u, v;
        uint32_t iterations;
    };
    static_assert(sizeof(Px) == 48);
    const bool has_n = img.normal.size() == 3 * npx, has_uv = img.u.size() == npx && img.v.size() == npx;
    const bool has_it = img.iterations.size() == npx;
    e.pixels.resize(npx * sizeof(Px));
    Px* buf = reinterpret_cast<Px*>(e.pixels.data());
    for (size_t k = 0; k < npx; ++k)
        buf[k] = {img.rgba[4 * k],
                  img.rgba[4 * k + 1],
                  img.rgba[4 * k + 2],
                  img.rgba[4 * k + 3],
                  img.z[k],
                  img.face[k],
                  has_n ? img.normal[3 * k] : 0.0f,
                  has_n ? img.normal[3 * k + 1] : 0.0f,
                  has_n ? img.normal[3 * k + 2] : 0.0f,
                  has_uv ? img.u[k] : 0.0f,
                  has_uv ? img.v[k] : 0.0f,
                  has_it ? img.iterations[k] : 0u};
    return e;
}

// Display formats: 8 bits per channel, colour sRGB-encoded, alpha linear.
Encodable display_pixels(const RenderImage& img, const std::string& ext) {
    const size_t npx = static_cast<size_t>(img.width) * img.height;
    const int nch = ext == "jpg" || ext == "jpeg" ? 3 : 4;
    Encodable e;
    e.spec = ImageSpec(img.width, img.height, nch, TypeDesc::UINT8);
    if (ext == "png") {
        e.spec.attribute("png:filter", kPngFilterNone);
        e.spec.attribute("png:compressionLevel", kZlibLevel);
    }
    if (ext == "tif" || ext == "tiff") e.spec.attribute("compression", "zip:" + std::to_string(kZlibLevel));
    // The colour of a pixel is independent of its alpha (a background r,g,b,a is
    // that colour at that opacity), PNG's and TIFF's own convention: without this
    // OpenImageIO takes the data as premultiplied and divides the colour by alpha
    // (a 50 % grey background at alpha 0.5 came out white).
    if (nch == 4) e.spec.attribute("oiio:UnassociatedAlpha", 1);
    static const Srgb8 srgb8;
    e.pixels.resize(npx * nch);
    uint8_t* out = e.pixels.data();
    const float* in = img.rgba.data();
    for (size_t k = 0; k < npx; ++k, in += 4, out += nch) {
        // A run of equal pixels (the background, about half of a render) costs a
        // comparison and a copy instead of three table lookups.
        if (k > 0 && std::memcmp(in, in - 4, 4 * sizeof(float)) == 0) {
            std::memcpy(out, out - nch, nch);
            continue;
        }
        for (int c = 0; c < 3; ++c) out[c] = srgb8(in[c]);
        // round(255 a) without lround's call: a is clamped, so a + 0.5 truncates right.
        if (nch == 4) out[3] = static_cast<uint8_t>(std::clamp(in[3], 0.0f, 1.0f) * 255.0f + 0.5f);
    }
    return e;
}

// Writes `img` as the format of extension `ext`, to the file `path` or, when
// `proxy` is set, into it (OpenImageIO then takes `path` only for its format).
int encode(const RenderImage& img, const std::string& path, Filesystem::IOProxy* proxy, std::string& message) {
    size_thread_pool();
    const std::string ext = extension_of(path);
    auto out = ImageOutput::create(path, proxy);
    if (!out || (proxy && !out->supports("ioproxy"))) {
        message = "cannot write image format of '" + path + "'";
        return kImageFormatUnsupported;
    }
    const Encodable e = ext == "exr" ? exr_pixels(img) : display_pixels(img, ext);
    const TypeDesc layout = ext == "exr" ? TypeDesc::UNKNOWN : TypeDesc::UINT8;
    if (out->open(path, e.spec) && out->write_image(layout, e.pixels.data()) && out->close()) return kImageWritten;
    message = "cannot write '" + path + "': " + out->geterror();
    return kImageIoError;
}

// Copies a message into the caller's buffer, NUL-terminated and truncated.
void copy_message(const std::string& text, char* message, size_t message_size) {
    if (message_size == 0) return;
    const size_t n = std::min(text.size(), message_size - 1);
    std::memcpy(message, text.data(), n);
    message[n] = '\0';
}

}  // namespace
}  // namespace nurbsrt

extern "C" int nurbsrt_write_image_v1(const nurbsrt::RenderImage* image, const char* path, char* message,
                                      size_t message_size) {
    std::string text;
    int status = nurbsrt::kImageIoError;
    try {
        status = nurbsrt::encode(*image, path, nullptr, text);
    } catch (const std::exception& e) {  // no exception crosses the module's C boundary
        text = std::string("cannot write '") + path + "': " + e.what();
    }
    nurbsrt::copy_message(text, message, message_size);
    return status;
}

extern "C" int nurbsrt_encode_image_v1(const nurbsrt::RenderImage* image, const char* format_name,
                                       void (*sink)(void* context, const void* bytes, size_t size), void* context,
                                       char* message, size_t message_size) {
    std::string text;
    int status = nurbsrt::kImageIoError;
    try {
        std::vector<unsigned char> bytes;
        OIIO::Filesystem::IOVecOutput proxy(bytes);
        status = nurbsrt::encode(*image, std::string("image.") + format_name, &proxy, text);
        if (status == nurbsrt::kImageWritten) sink(context, bytes.data(), bytes.size());
    } catch (const std::exception& e) {  // no exception crosses the module's C boundary
        text = std::string("cannot encode a ") + format_name + " image: " + e.what();
    }
    nurbsrt::copy_message(text, message, message_size);
    return status;
}

extern "C" int nurbsrt_draw_label_v1(nurbsrt::RenderImage* image, int x, int y, int size, const char* text,
                                     const float rgb[3], char* message, size_t message_size) {
    std::string why;
    int status = nurbsrt::kImageIoError;
    try {
        // The frame's own float RGBA, drawn into in place (ImageBuf over caller memory).
        OIIO::ImageSpec spec(image->width, image->height, 4, OIIO::TypeDesc::FLOAT);
        OIIO::ImageBuf buf(spec, image->rgba.data());
        const float colour[4] = {rgb[0], rgb[1], rgb[2], 1.0f};
        if (OIIO::ImageBufAlgo::render_text(buf, x, y + size, text, size, "DejaVuSans", colour,
                                            OIIO::ImageBufAlgo::TextAlignX::Left,
                                            OIIO::ImageBufAlgo::TextAlignY::Baseline))
            status = nurbsrt::kImageWritten;
        else
            why = "cannot draw a label: " + buf.geterror();
    } catch (const std::exception& e) {  // no exception crosses the module's C boundary
        why = std::string("cannot draw a label: ") + e.what();
    }
    nurbsrt::copy_message(why, message, message_size);
    return status;
}
