// The job description of POST /v1/jobs (server/jobs/job_spec.h): outputs numbered
// with generated artifact names and content types, files by index or name,
// every mistake rejected with the right code; and the strict name patterns
// that keep requests from naming anything but a job's own artifacts.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <functional>

#include "core/error.h"
#include "options/render_request.h"
#include "server/jobs/job_document.h"
#include "server/jobs/job_spec.h"
#include "tests/support/error_code_of.h"

using nurbsrt::Error;
using nurbsrt::ErrorCode;
using namespace nurbsrt::server;

namespace {

std::vector<JobInput> two_inputs() { return {{0, "bearing.iges", "IGES", 10}, {1, "screw.step", "STEP", 20}}; }

using nurbsrt::test::code_of;

TEST(JobSpec, OutputsGetArtifactNamesAndContentTypes) {
    ServerConfig config;
    const auto outs = parse_job_spec(R"({"outputs": [
        {"file": 0, "type": "render", "options": {"width": 64, "height": 48}},
        {"file": "screw.step", "type": "render", "options": {"format": "exr"}},
        {"file": 1, "type": "conversion", "format": "igs"},
        {"file": 0, "type": "conversion", "format": "stl"},
        {"file": 0, "type": "conversion", "format": "glb"},
        {"file": 1, "type": "conversion", "format": "json"},
        {"file": 1, "type": "conversion", "format": "step"}]})",
                                     two_inputs(), config)
                          .outputs;
    ASSERT_EQ(outs.size(), 7u);
    const std::vector<std::string> names = {"0-render-0.png",     "1-render-1.exr",     "1-conversion-2.igs",
                                            "0-conversion-3.stl", "0-conversion-4.glb", "1-conversion-5.json",
                                            "1-conversion-6.step"};
    const std::vector<std::string> types = {"image/png",         "image/x-exr",      "model/iges", "model/stl",
                                            "model/gltf-binary", "application/json", "model/step"};
    for (size_t i = 0; i < outs.size(); ++i) {
        EXPECT_EQ(outs[i].index, static_cast<int>(i));
        EXPECT_EQ(outs[i].artifact, names[i]);
        EXPECT_EQ(outs[i].content_type, types[i]);
        EXPECT_TRUE(valid_artifact_name(outs[i].artifact)) << outs[i].artifact;
    }
    EXPECT_EQ(outs[1].file, 1);
    EXPECT_EQ(outs[2].options_json,
              R"({"format":"iges","iges_mode":"brep","strict":false,"units":"source"})");  // alias normalised
    EXPECT_EQ(artifact_format("1-conversion-2.igs"), "iges");
    EXPECT_EQ(artifact_format("0-render-0.jpg"), "jpeg");
    EXPECT_EQ(artifact_format("0-conversion-3.wrl"), "vrml");
    EXPECT_EQ(artifact_format("0-conversion-3.brep"), "brep");
    EXPECT_TRUE(valid_artifact_name("0-conversion-3.brep"));
    EXPECT_TRUE(valid_artifact_name("0-conversion-3.wrl"));
}

// A conversion output takes the options of POST /v1/conversions, stored with
// its format as that request model reads them.
TEST(JobSpec, ConversionOptionsAreTheConversionsRequestModel) {
    ServerConfig config;
    const auto spec = parse_job_spec(R"({"outputs": [
        {"file": 0, "type": "conversion", "format": "stp", "options": {"units": "inch", "step_schema": "ap242",
                                                                       "strict": true, "iges_mode": null}},
        {"file": 1, "type": "conversion", "format": "glb", "options": {"deflection": 0.01}}]})",
                                     two_inputs(), config);
    ASSERT_EQ(spec.outputs.size(), 2u);
    const nurbsrt::ConversionRequest step = nurbsrt::parse_conversion_request(spec.outputs[0].options_json);
    EXPECT_EQ(step.format, nurbsrt::ConversionFormat::step);
    EXPECT_EQ(step.options.units, nurbsrt::LengthUnit::inch);
    EXPECT_EQ(step.options.step_schema, nurbsrt::StepSchema::ap242);
    EXPECT_TRUE(step.strict);
    const nurbsrt::ConversionRequest glb = nurbsrt::parse_conversion_request(spec.outputs[1].options_json);
    EXPECT_EQ(glb.options.deflection, 0.01);
    EXPECT_FALSE(glb.strict);
}

// Stored resolved: every option the format takes, its default named, so the
// job document echoes them and equal requests are equal text.
TEST(JobSpec, ConversionOptionsAreStoredResolved) {
    ServerConfig config;
    const auto spec = parse_job_spec(R"({"outputs": [
        {"file": 0, "type": "conversion", "format": "igs"},
        {"file": 1, "type": "conversion", "format": "stl", "options": {"angular_deflection": 0.2}},
        {"file": 1, "type": "conversion", "format": "json"}]})",
                                     two_inputs(), config);
    EXPECT_EQ(spec.outputs[0].options_json, R"({"format":"iges","iges_mode":"brep","strict":false,"units":"source"})");
    EXPECT_EQ(spec.outputs[1].options_json,
              R"({"angular_deflection":0.2,"deflection":0.002,"format":"stl","strict":false})");
    EXPECT_EQ(spec.outputs[2].options_json, R"({"format":"json","strict":false})");
    // Read back to the same request: "source" is the source's unit.
    const nurbsrt::ConversionRequest iges = nurbsrt::parse_conversion_request(spec.outputs[0].options_json);
    EXPECT_EQ(iges.options.units, nurbsrt::LengthUnit::unknown);
    EXPECT_EQ(nurbsrt::parse_conversion_request(spec.outputs[1].options_json).options.angular_deflection, 0.2);
}

// One artifact per view of a separate layout, and OBJ's .obj with its .mtl.
TEST(JobSpec, OutputsOfSeveralFilesNameEach) {
    ServerConfig config;
    const auto outs = parse_job_spec(R"({"outputs": [
        {"file": 0, "type": "render", "options": {"views": ["front", "iso"], "layout": "separate", "format": "jpeg"}},
        {"file": 1, "type": "conversion", "format": "obj"},
        {"file": 1, "type": "render", "options": {"views": ["front", "iso"]}}]})",
                                     two_inputs(), config)
                          .outputs;
    ASSERT_EQ(outs.size(), 3u);
    const std::vector<ArtifactFile> views = output_artifacts(outs[0]);
    ASSERT_EQ(views.size(), 2u);
    EXPECT_EQ(outs[0].artifact, "0-render-0.front.jpg");
    EXPECT_EQ(views[0].name, "0-render-0.front.jpg");
    EXPECT_EQ(views[1].name, "0-render-0.iso.jpg");
    EXPECT_EQ(views[1].view, "iso");
    EXPECT_EQ(views[1].content_type, "image/jpeg");
    const std::vector<ArtifactFile> obj = output_artifacts(outs[1]);
    ASSERT_EQ(obj.size(), 2u);
    EXPECT_EQ(obj[0].name, "1-conversion-1.obj");
    EXPECT_EQ(obj[0].content_type, "model/obj");
    EXPECT_EQ(obj[1].name, "1-conversion-1.mtl");
    EXPECT_EQ(obj[1].content_type, "model/mtl");
    EXPECT_EQ(output_artifacts(outs[2]).size(), 1u) << "a contact sheet is one image";
    EXPECT_EQ(outs[2].artifact, "1-render-2.png");
    for (const auto& files : {views, obj})
        for (const ArtifactFile& f : files) EXPECT_TRUE(valid_artifact_name(f.name)) << f.name;
    EXPECT_FALSE(valid_artifact_name("0-render-0.a.b.png"));
    EXPECT_FALSE(valid_artifact_name("0-render-0..png"));
    EXPECT_FALSE(valid_artifact_name("0-render-0.x/y.png"));
    EXPECT_EQ(artifact_format("1-conversion-1.obj"), "obj");
}

// The job document lists every file of an output: all of a succeeded one
// (sizes from its result), the placed ones of a running one, and counts them.
TEST(JobDocument, ListsEachFileOfAnOutput) {
    ServerConfig config;
    JobRecord job;
    job.id = std::string(32, 'a');
    job.inputs = two_inputs();
    job.outputs = parse_job_spec(R"({"outputs": [
        {"file": 0, "type": "render", "options": {"views": ["front", "top", "iso"], "layout": "separate"}},
        {"file": 1, "type": "conversion", "format": "obj"}]})",
                                 job.inputs, config)
                      .outputs;
    JobOutput& views = job.outputs[0];
    JobOutput& obj = job.outputs[1];
    views.state = JobState::running;
    obj.state = JobState::succeeded;
    obj.artifact_bytes = 300;
    obj.result_json = R"({"faces": 3, "artifacts": [{"name": "1-conversion-1.obj", "bytes": 280},
                                                    {"name": "1-conversion-1.mtl", "bytes": 20}]})";
    // The first view is in place; the others not yet.
    const auto placed = [](const std::string& name) -> int64_t { return name == "0-render-0.front.png" ? 77 : -1; };
    const nlohmann::json doc = job_json(job, placed);
    const nlohmann::json& running = doc["outputs"][0];
    ASSERT_EQ(running["artifacts"].size(), 1u);
    EXPECT_EQ(running["artifacts"][0]["view"], "front");
    EXPECT_EQ(running["artifacts"][0]["bytes"], 77);
    EXPECT_EQ(running["artifacts"][0]["url"], "/v1/jobs/" + job.id + "/artifacts/0-render-0.front.png");
    EXPECT_FALSE(running.contains("artifact"));
    const nlohmann::json& done = doc["outputs"][1];
    ASSERT_EQ(done["artifacts"].size(), 2u);
    EXPECT_EQ(done["artifacts"][1]["name"], "1-conversion-1.mtl");
    EXPECT_EQ(done["artifacts"][1]["content_type"], "model/mtl");
    EXPECT_EQ(done["artifacts"][1]["bytes"], 20);
    EXPECT_EQ(done["artifact"], done["artifacts"][0]);
    EXPECT_EQ(done["options"], nlohmann::json::parse(R"({"format": "obj", "deflection": 0.002,
                                                          "angular_deflection": 0.35, "strict": false})"));
    EXPECT_EQ(doc["statistics"]["artifacts"], 3);
    EXPECT_EQ(doc["statistics"]["artifact_bytes"], 300);
    // Without the lookup (a webhook's body, the job finished): a running output lists none.
    EXPECT_FALSE(job_json(job)["outputs"][0].contains("artifacts"));
}

TEST(JobSpec, MistakesAreRejected) {
    ServerConfig config;
    config.max_job_outputs = 2;
    config.max_dimension = 1000;
    const auto in = two_inputs();
    auto parse = [&](const char* json) { return code_of([&] { parse_job_spec(json, in, config); }); };
    const char* both = R"({"file": 0, "type": "render"}, {"file": 1, "type": "render"})";
    EXPECT_NO_THROW(parse_job_spec(std::string("{\"outputs\": [") + both + "]}", in, config));
    EXPECT_EQ(parse("[]"), ErrorCode::invalid_argument);
    EXPECT_EQ(parse(R"({"outputs": []})"), ErrorCode::invalid_argument);
    EXPECT_EQ(parse(R"({"outputs": [{"file": 0, "type": "render"}]})"), ErrorCode::invalid_argument);  // file 1 unused
    EXPECT_EQ(parse(R"({"outputs": [{"file": 0, "type": "render"}, {"file": 1, "type": "render"},
                                    {"file": 1, "type": "render"}]})"),
              ErrorCode::limit_exceeded);
    EXPECT_EQ(parse(R"({"outputs": [{"file": 2, "type": "render"}, {"file": 1, "type": "render"}]})"),
              ErrorCode::invalid_argument);
    EXPECT_EQ(parse(R"({"outputs": [{"file": -1, "type": "render"}, {"file": 1, "type": "render"}]})"),
              ErrorCode::invalid_argument);
    EXPECT_EQ(parse(R"({"outputs": [{"file": "x.igs", "type": "render"}, {"file": 1, "type": "render"}]})"),
              ErrorCode::invalid_argument);
    EXPECT_EQ(parse(R"({"outputs": [{"file": 0, "type": "render", "options": {"width": 2000}},
                                    {"file": 1, "type": "render"}]})"),
              ErrorCode::limit_exceeded);
    EXPECT_EQ(parse(R"({"outputs": [{"file": 0, "type": "render", "options": {"bogus": 1}},
                                    {"file": 1, "type": "render"}]})"),
              ErrorCode::invalid_argument);
    EXPECT_EQ(parse(R"({"outputs": [{"file": 0, "type": "conversion", "format": "obj",
                                     "options": {"angular_deflection": 0.001}}, {"file": 1, "type": "render"}]})"),
              ErrorCode::invalid_argument);
    EXPECT_EQ(parse(R"({"outputs": [{"file": 0, "type": "conversion", "format": "step",
                                     "options": {"angular_deflection": 0.5}}, {"file": 1, "type": "render"}]})"),
              ErrorCode::invalid_argument);
    EXPECT_EQ(parse(R"({"outputs": [{"file": 0, "type": "conversion", "format": "dwg"},
                                    {"file": 1, "type": "render"}]})"),
              ErrorCode::invalid_argument);
    // A conversion's options are POST /v1/conversions': what that parser refuses, the spec refuses.
    EXPECT_EQ(
        parse(R"({"outputs": [{"file": 0, "type": "conversion", "format": "step", "options": {"iges_mode": "faces"}},
                                    {"file": 1, "type": "render"}]})"),
        ErrorCode::invalid_argument);
    EXPECT_EQ(parse(R"({"outputs": [{"file": 0, "type": "conversion", "format": "stl", "options": {"deflection": 0.5}},
                                    {"file": 1, "type": "render"}]})"),
              ErrorCode::invalid_argument);
    EXPECT_EQ(parse(R"({"outputs": [{"file": 0, "type": "conversion", "format": "stl", "options": {"format": "glb"}},
                                    {"file": 1, "type": "render"}]})"),
              ErrorCode::invalid_argument);
    EXPECT_EQ(parse(R"({"outputs": [{"file": 0, "type": "conversion", "format": "stl", "options": [1]},
                                    {"file": 1, "type": "render"}]})"),
              ErrorCode::invalid_argument);
    EXPECT_EQ(parse(R"({"outputs": [{"file": 0, "type": "render"}, {"file": 1, "type": "render"}], "x": 1})"),
              ErrorCode::invalid_argument);
    // A filename shared by two parts is ambiguous.
    std::vector<JobInput> same = {{0, "a.step", "STEP", 1}, {1, "a.step", "STEP", 1}};
    EXPECT_EQ(code_of([&] {
                  parse_job_spec(
                      R"({"outputs": [{"file": "a.step", "type": "render"}, {"file": 1, "type": "render"}]})", same,
                      config);
              }),
              ErrorCode::invalid_argument);
}

TEST(JobSpec, NamePatternsAreStrict) {
    EXPECT_TRUE(valid_artifact_name("0-render-0.png"));
    EXPECT_TRUE(valid_artifact_name("12-conversion-345.step"));
    for (const char* bad : {"", "input-0.cad", "../jobs.db", "0-render-0.png/../x", "0-render-0.png\n",
                            "0-render-0.gif", "0-Render-0.png", "/0-render-0.png", "0-render-.png",
                            "partial-0-render-0.png", "123456-render-0.png", "0-render-0.png.exe"})
        EXPECT_FALSE(valid_artifact_name(bad)) << bad;
    EXPECT_TRUE(valid_job_id("0123456789abcdef0123456789abcdef"));
    EXPECT_FALSE(valid_job_id("0123456789ABCDEF0123456789abcdef"));
    EXPECT_FALSE(valid_job_id("../../../../../../../../jobs.db.."));
    EXPECT_FALSE(valid_job_id("0123456789abcdef"));
}

}  // namespace
