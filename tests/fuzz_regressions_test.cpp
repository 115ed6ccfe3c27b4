// Inputs the libFuzzer harnesses of fuzz/ found to break our parsers, reduced
// to what broke them (the exact inputs are in fuzz/regressions/). Each must be
// refused with nurbsrt::Error like any other bad input, never escape as
// another exception or crash.
#include <gtest/gtest.h>
#include <httplib.h>

#include <climits>
#include <functional>
#include <sstream>
#include <string>

#include "cli/scene_placements.h"
#include "core/error.h"
#include "core/io/scene_io.h"
#include "server/http/upload.h"
#include "tests/support/error_code_of.h"

using nurbsrt::Error;
using nurbsrt::ErrorCode;

namespace {

using nurbsrt::test::code_of;

// A query string is bytes: "?heig\xFB\xFB...ht=10" reached the options as a
// JSON key, and writing that JSON threw nlohmann's invalid UTF-8 type_error,
// which became a 500 instead of a 400.
TEST(FuzzRegressions, QueryParameterThatIsNotUtf8IsInvalidArgument) {
    for (const bool in_name : {true, false}) {
        httplib::Request req;
        req.method = "POST";
        req.set_header("Content-Type", "model/step");
        req.body = "ISO-10303-21;";
        req.params.emplace("width", "20");
        if (in_name)
            req.params.emplace("heig\xFB\xFBht", "10");
        else
            req.params.emplace("view", "to\xFFp");
        EXPECT_EQ(code_of([&] { (void)nurbsrt::server::read_upload(req); }), ErrorCode::invalid_argument)
            << (in_name ? "in a name" : "in a value");
    }
}

// The render scene file read "scale" with nlohmann's value(key, 1.0), which
// throws json::type_error for a string: `nurbsrt render` ended on an uncaught
// exception instead of naming the mistake.
TEST(FuzzRegressions, SceneFileScaleThatIsNotANumberIsInvalidArgument) {
    for (const char* scale : {"\"b./a.stp\"", "\"2\"", "null", "[1]", "{}"}) {
        std::istringstream in(std::string(R"({"models": [{"file": "b.igs", "scale": )") + scale + "}]}");
        EXPECT_EQ(code_of([&] { (void)nurbsrt::cli::parse_scene_file(in, "scenes/s.json"); }),
                  ErrorCode::invalid_argument)
            << "scale " << scale;
    }
    std::istringstream ok(R"({"models": [{"file": "b.igs", "scale": 2}, {"file": "c.igs"}]})");
    const auto placements = nurbsrt::cli::parse_scene_file(ok, "scenes/s.json");
    ASSERT_EQ(placements.size(), 2u);
    EXPECT_DOUBLE_EQ(placements[0].xf.m[0], 2.0);
    EXPECT_DOUBLE_EQ(placements[1].xf.m[0], 1.0);
    EXPECT_EQ(placements[0].file, "scenes/b.igs");
}

// A binary scene whose surface has degree INT_MAX: the check "fewer control
// points than degree + 1" computed INT_MAX + 1 (signed overflow, undefined
// behaviour that UBSan reports). It must be refused as corrupt.
TEST(FuzzRegressions, SceneSurfaceDegreeIntMaxIsCorruptScene) {
    for (const bool in_u : {true, false}) {
        nurbsrt::Scene scene;
        nurbsrt::Face f;
        f.index = 1;
        f.surface.degree_u = in_u ? INT_MAX : 1;
        f.surface.degree_v = in_u ? 1 : INT_MAX;
        f.surface.num_u = f.surface.num_v = 2;
        f.surface.knots_u = f.surface.knots_v = {0, 0, 1, 1};
        f.surface.cp.resize(4);
        scene.faces.push_back(f);
        const std::string bytes = nurbsrt::serialize_scene(scene);
        EXPECT_EQ(code_of([&] { (void)nurbsrt::deserialize_scene(bytes); }), ErrorCode::corrupt_scene)
            << (in_u ? "degree_u" : "degree_v");
    }
}

}  // namespace
