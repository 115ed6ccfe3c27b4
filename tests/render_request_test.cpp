// The image format, decided once at the edge (the API's `format`, the CLI's file
// extension) and carried as ImageFormat: its defaults (anti-aliasing on for the
// pictures, PNG and JPEG; JPEG's opaque white background) follow the kind, not
// a name compared as text.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/error.h"
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

// `views` of names and cameras: each view's camera is the request's with what
// the view gives replaced; a named view drops the request's placement; labels
// default to the view's name or "viewN"; bad elements are refused naming
// views[k]; layout separate needs distinct labels.
TEST(RenderOptions, ViewsOfNamesAndCameras) {
    using nurbsrt::Error;
    using nurbsrt::parse_render_options;
    using nurbsrt::Projection;
    const auto r = parse_render_options(
        R"({"eye": [9, 9, 9], "projection": "perspective", "fov_deg": 30,
            "views": ["top", {"eye": [100, 0, 0], "target": [0, 0, 0]}, {"view": "front", "name": "elev_1",
            "projection": "orthographic"}]})");
    ASSERT_EQ(r.views.size(), 3u);
    EXPECT_EQ(r.views[0].name, "top");
    EXPECT_EQ(r.views[0].camera.view, "top");
    EXPECT_FALSE(r.views[0].camera.eye);                               // the named view places it
    EXPECT_EQ(r.views[0].camera.projection, Projection::perspective);  // the request's
    EXPECT_EQ(r.views[0].camera.fov_deg, 30);
    EXPECT_EQ(r.views[1].name, "view2");
    EXPECT_EQ(r.views[1].camera.eye->x, 100);
    EXPECT_EQ(r.views[2].name, "elev_1");
    EXPECT_EQ(r.views[2].camera.projection, Projection::orthographic);
    EXPECT_EQ(nurbsrt::view_names(r), (std::vector<std::string>{"top", "view2", "elev_1"}));
    const auto fails_naming = [](const char* json, const char* field) {
        try {
            parse_render_options(json);
            ADD_FAILURE() << "no error for " << json;
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
        }
    };
    fails_naming(R"({"views": ["top", {"eye": [1, 2]}]})", "views[1].eye");
    fails_naming(R"({"views": [{"lens": 3}]})", "'lens' in 'views[0]'");
    fails_naming(R"({"views": [{"name": "a/b", "view": "top"}]})", "views[0].name");
    fails_naming(R"({"views": [{"eye": [0, 0, 0], "target": [0, 0, 0]}]})", "");  // eye at the target
    fails_naming(R"({"views": []})", "1 to 16");
    fails_naming(R"({"views": ["top", "top"], "layout": "separate"})", "two views are 'top'");
    EXPECT_EQ(parse_render_options(R"({"views": ["top", "top"]})").views.size(), 2u);  // a sheet may repeat
}

}  // namespace
