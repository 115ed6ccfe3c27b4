// The image writer module, libnurbsrt_image.so: every image file nurbsrt writes
// goes through OpenImageIO here. It is a module of its own, loaded on first use
// (renderer/image_module.h says why), with one entry point of C linkage.
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "renderer/image_module.h"
#include "renderer/render.h"

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
// the time (800x600 renders of three models: 21-69 KB instead of 25-69 KB,
// 49-130 ms instead of 103-225 ms, at zlib's default level 6).
constexpr int kPngFilterNone = 8;  // libpng's PNG_FILTER_NONE

// The status of a written file, with OpenImageIO's message when it failed.
int finish(bool ok, ImageOutput& out, const std::string& path, std::string& message) {
    if (ok) return kImageWritten;
    message = "cannot write '" + path + "': " + out.geterror();
    return kImageIoError;
}

// write_image (render.h), answering a status of image_module.h and a message.
int write(const RenderImage& img, const std::string& path, std::string& message) {
    const size_t dot_pos = path.rfind('.');
    std::string ext = dot_pos == std::string::npos ? "" : path.substr(dot_pos + 1);
    for (char& ch : ext) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    auto out = ImageOutput::create(path);
    if (!out) {
        message = "cannot write image format of '" + path + "'";
        return kImageFormatUnsupported;
    }
    const size_t npx = static_cast<size_t>(img.width) * img.height;
    if (ext == "exr") {
        ImageSpec spec(img.width, img.height, 12, TypeDesc::FLOAT);
        spec.channelnames = {"R", "G", "B", "A", "Z", "face", "N.X", "N.Y", "N.Z", "u", "v", "iterations"};
        spec.channelformats = {TypeDesc::FLOAT, TypeDesc::FLOAT, TypeDesc::FLOAT, TypeDesc::FLOAT,
                               TypeDesc::FLOAT, TypeDesc::UINT32, TypeDesc::FLOAT, TypeDesc::FLOAT,
                               TypeDesc::FLOAT, TypeDesc::FLOAT, TypeDesc::FLOAT, TypeDesc::UINT32};
        spec.alpha_channel = 3;
        spec.z_channel = 4;
        struct Px {
            float r, g, b, a, z;
            uint32_t face;
            float nx, ny, nz, u, v;
            uint32_t iterations;
        };
        static_assert(sizeof(Px) == 48);
        const bool has_n = img.normal.size() == 3 * npx, has_uv = img.u.size() == npx && img.v.size() == npx;
        const bool has_it = img.iterations.size() == npx;
        std::vector<Px> buf(npx);
        for (size_t k = 0; k < npx; ++k)
            buf[k] = {img.rgba[4 * k], img.rgba[4 * k + 1], img.rgba[4 * k + 2], img.rgba[4 * k + 3], img.z[k], img.face[k],
                      has_n ? img.normal[3 * k] : 0.0f, has_n ? img.normal[3 * k + 1] : 0.0f,
                      has_n ? img.normal[3 * k + 2] : 0.0f, has_uv ? img.u[k] : 0.0f, has_uv ? img.v[k] : 0.0f,
                      has_it ? img.iterations[k] : 0u};
        return finish(out->open(path, spec) && out->write_image(TypeDesc::UNKNOWN, buf.data()) && out->close(),
                      *out, path, message);
    }
    const int nch = ext == "jpg" || ext == "jpeg" ? 3 : 4;
    ImageSpec spec(img.width, img.height, nch, TypeDesc::UINT8);
    if (ext == "png") spec.attribute("png:filter", kPngFilterNone);
    // The colour of a pixel is independent of its alpha (a background r,g,b,a is
    // that colour at that opacity), PNG's and TIFF's own convention: without this
    // OpenImageIO takes the data as premultiplied and divides the colour by alpha
    // (a 50 % grey background at alpha 0.5 came out white).
    if (nch == 4) spec.attribute("oiio:UnassociatedAlpha", 1);
    static const Srgb8 srgb8;
    std::vector<uint8_t> buf(npx * nch);
    for (size_t k = 0; k < npx; ++k)
        for (int c = 0; c < nch; ++c) {
            const float x = img.rgba[4 * k + c];
            // Display formats are sRGB; alpha stays linear.
            buf[k * nch + c] = c == 3 ? static_cast<uint8_t>(std::lround(std::clamp(x, 0.0f, 1.0f) * 255.0f)) : srgb8(x);
        }
    return finish(out->open(path, spec) && out->write_image(TypeDesc::UINT8, buf.data()) && out->close(), *out, path,
                  message);
}

}  // namespace
}  // namespace nurbsrt

extern "C" int nurbsrt_write_image_v1(const nurbsrt::RenderImage* image, const char* path, char* message,
                                      size_t message_size) {
    std::string text;
    int status = nurbsrt::kImageIoError;
    try {
        status = nurbsrt::write(*image, path, text);
    } catch (const std::exception& e) {  // no exception crosses the module's C boundary
        text = std::string("cannot write '") + path + "': " + e.what();
    }
    if (message_size > 0) {
        const size_t n = std::min(text.size(), message_size - 1);
        std::memcpy(message, text.data(), n);
        message[n] = '\0';
    }
    return status;
}
