// The image format, decided once at the edge (the API's `format`, the CLI's file
// extension) and carried as ImageFormat: its defaults (anti-aliasing on for the
// pictures, PNG and JPEG; JPEG's opaque white background) follow the kind, not
// a name compared as text.
#include <gtest/gtest.h>

#include "options/render_request.h"

namespace {

using nurbsrt::ImageFormat;

TEST(RenderOptions, ImageFormatByExtension) {
    using nurbsrt::image_format_of_extension;
    EXPECT_EQ(image_format_of_extension(".png"), ImageFormat::png);
    EXPECT_EQ(image_format_of_extension("PNG"), ImageFormat::png);
    EXPECT_EQ(image_format_of_extension(".jpg"), ImageFormat::jpeg);
    EXPECT_EQ(image_format_of_extension("jpeg"), ImageFormat::jpeg);
    EXPECT_EQ(image_format_of_extension(".TIF"), ImageFormat::tiff);
    EXPECT_EQ(image_format_of_extension("tiff"), ImageFormat::tiff);
    EXPECT_EQ(image_format_of_extension(".exr"), ImageFormat::exr);
    EXPECT_EQ(image_format_of_extension(".bmp"), ImageFormat::other);
    EXPECT_EQ(image_format_of_extension(""), ImageFormat::other);
}

TEST(RenderOptions, DefaultsFollowTheFormat) {
    using nurbsrt::default_antialias;
    using nurbsrt::default_background;
    using nurbsrt::kDefaultAntialias;
    EXPECT_EQ(default_antialias(ImageFormat::png), kDefaultAntialias);
    EXPECT_EQ(default_antialias(ImageFormat::jpeg), kDefaultAntialias);
    EXPECT_EQ(default_antialias(ImageFormat::tiff), 0);
    EXPECT_EQ(default_antialias(ImageFormat::exr), 0);
    EXPECT_EQ(default_antialias(ImageFormat::other), 0);
    EXPECT_EQ(default_background(ImageFormat::jpeg).alpha, 1.0);
    EXPECT_EQ(default_background(ImageFormat::png).alpha, 0.0);
    EXPECT_EQ(default_background(ImageFormat::tiff).alpha, 0.0);
}

TEST(RenderOptions, ApiFormatParsedOnce) {
    using nurbsrt::parse_render_options;
    const auto jpg = parse_render_options(R"({"format":"jpg"})");
    EXPECT_EQ(jpg.format.kind, ImageFormat::jpeg);
    EXPECT_EQ(jpg.format.name, "jpeg");
    EXPECT_EQ(jpg.format.extension, ".jpg");
    EXPECT_EQ(jpg.format.content_type, "image/jpeg");
    const auto tif = parse_render_options(R"({"format":"tif"})");
    EXPECT_EQ(tif.format.kind, ImageFormat::tiff);
    EXPECT_EQ(tif.format.content_type, "image/tiff");
    EXPECT_EQ(parse_render_options("{}").format.kind, ImageFormat::png);  // the API's default
    EXPECT_THROW(parse_render_options(R"({"format":"bmp"})"), std::exception);
}

}  // namespace
