// Image output (write_image): the 8-bit sRGB codes of PNG/JPEG/TIFF are
// round(255 encode(x)) with the IEC 61966-2-1 transfer function, alpha linear and
// not applied to the colour (a colour at alpha 0.25 keeps its code), out-of-range
// and NaN values clamped.
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

#include "core/error.h"
#include "renderer/render.h"

namespace {

double srgb_encode(double x) { return x <= 0.0031308 ? 12.92 * x : 1.055 * std::pow(x, 1.0 / 2.4) - 0.055; }
double srgb_decode(double y) { return y <= 0.04045 ? y / 12.92 : std::pow((y + 0.055) / 1.055, 2.4); }

TEST(ImageWrite, SrgbCodesAreRoundedTransferFunction) {
    // Every code's two neighbouring boundaries and a dense sweep of [0, 1].
    std::vector<float> xs;
    for (int k = 0; k <= 20000; ++k) xs.push_back(static_cast<float>(k) / 20000.0f);
    for (int c = 1; c < 256; ++c) {
        const float b = static_cast<float>(srgb_decode((c - 0.5) / 255.0));
        xs.push_back(std::nextafter(b, 0.0f));
        xs.push_back(std::nextafter(b, 2.0f));
    }
    xs.push_back(-0.5f);
    xs.push_back(1.5f);
    xs.push_back(std::nanf(""));
    nurbsrt::RenderImage img;
    img.width = static_cast<int>(xs.size());
    img.height = 1;
    for (const float x : xs) img.rgba.insert(img.rgba.end(), {x, x, x, 0.25f});
    img.z.assign(xs.size(), INFINITY);
    img.face.assign(xs.size(), 0);
    const std::string path = (std::filesystem::temp_directory_path() / "nurbsrt-srgb-test.png").string();
    nurbsrt::write_image(img, path);
    // Read the file's own codes: OpenImageIO premultiplies PNG colour by alpha on
    // reading unless asked not to.
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    auto in = OIIO::ImageInput::open(path, &config);
    ASSERT_TRUE(in);
    std::vector<uint8_t> px(xs.size() * 4);
    ASSERT_TRUE(in->read_image(0, 0, 0, 4, OIIO::TypeDesc::UINT8, px.data()));
    in->close();
    std::filesystem::remove(path);
    int off_by_one = 0;
    for (size_t k = 0; k < xs.size(); ++k) {
        const double x = std::isnan(xs[k]) ? 0.0 : std::clamp(static_cast<double>(xs[k]), 0.0, 1.0);
        const double exact = 255.0 * srgb_encode(x);
        const int got = px[4 * k], want = static_cast<int>(std::lround(exact));
        // A value within a float's rounding of a boundary may land on either side.
        if (got != want) {
            ++off_by_one;
            EXPECT_EQ(std::abs(got - want), 1) << "x=" << xs[k];
            EXPECT_LT(std::abs(exact - std::floor(exact) - 0.5), 1e-4) << "x=" << xs[k] << " is not at a boundary";
        }
        EXPECT_EQ(px[4 * k + 1], px[4 * k]);
        EXPECT_EQ(px[4 * k + 3], 64) << "alpha 0.25 stays linear: round(63.75)";
    }
    EXPECT_LE(off_by_one, 255 * 2) << "only the points placed at boundaries may round the other way";
}

// Every channel of every pixel of an image file, as float.
std::vector<float> read_pixels(const std::string& path, int& channels) {
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    auto in = OIIO::ImageInput::open(path, &config);
    if (!in) return {};
    channels = in->spec().nchannels;
    std::vector<float> px(static_cast<size_t>(in->spec().width) * in->spec().height * channels);
    if (!in->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, px.data())) return {};
    return px;
}

// encode_image (the service's answers, made in memory) holds what write_image
// writes to a file: the same pixels in every format, read back by OpenImageIO.
TEST(ImageWrite, EncodedBytesDecodeAsTheWrittenFile) {
    nurbsrt::RenderImage img;
    img.width = 37;  // not a multiple of a TIFF strip's or a JPEG block's size
    img.height = 21;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            const float a = x % 5 == 0 ? 0.0f : 1.0f - 0.02f * y;
            img.rgba.insert(img.rgba.end(), {x / 36.0f, y / 20.0f, 0.3f, a});
            img.z.push_back(a > 0 ? 1.0f + x : INFINITY);
            img.face.push_back(a > 0 ? static_cast<uint32_t>(y) : 0u);
        }
    const auto dir = std::filesystem::temp_directory_path();
    for (const std::string format : {"png", "jpg", "tif", "exr"}) {
        SCOPED_TRACE(format);
        const std::string written = (dir / ("nurbsrt-encode-test-w." + format)).string();
        const std::string encoded = (dir / ("nurbsrt-encode-test-e." + format)).string();
        nurbsrt::write_image(img, written);
        const std::string bytes = nurbsrt::encode_image(img, format);
        ASSERT_GT(bytes.size(), 64u);
        {
            std::ofstream f(encoded, std::ios::binary);
            f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
        }
        int cw = 0, ce = 0;
        const std::vector<float> pw = read_pixels(written, cw), pe = read_pixels(encoded, ce);
        std::filesystem::remove(written);
        std::filesystem::remove(encoded);
        ASSERT_EQ(pw.size(), static_cast<size_t>(img.width) * img.height * cw);
        EXPECT_EQ(ce, cw);
        EXPECT_EQ(pe, pw);
        EXPECT_EQ(cw, format == "exr" ? 12 : format == "jpg" ? 3 : 4);
    }
    try {
        nurbsrt::encode_image(img, "bmpx");
        ADD_FAILURE() << "an unknown format encoded";
    } catch (const nurbsrt::Error& e) {
        EXPECT_EQ(e.code(), nurbsrt::ErrorCode::unsupported_format) << e.what();
    }
}

}  // namespace
