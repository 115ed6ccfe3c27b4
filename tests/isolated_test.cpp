// Process-isolated import (importer/isolated.h): a crashing or hanging import
// fails only its own call, with the right typed error, and the caller goes on.
#include <gtest/gtest.h>

#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <fstream>
#include <iterator>

#include "importer/isolated.h"
#include "core/error.h"
#include "core/io/scene_io.h"
#include "tests/support/error_code_of.h"

namespace {

const std::string kScrew = "/usr/share/opencascade/data/step/screw.step";

// Every test runs with both worker programs: nurbsrt-worker (what the service
// starts; cli/worker_main.cpp) and nurbsrt's own hidden subcommands (the fallback
// where the worker is not installed). They must behave identically.
class IsolatedImport : public ::testing::TestWithParam<const char*> {
protected:
    nurbsrt::IsolationLimits limits(double seconds) const {
        nurbsrt::IsolationLimits l;
        l.time_limit_s = seconds;
        l.worker_executable = GetParam();
        return l;
    }
};

using nurbsrt::test::code_of;

// setenv affects the child started by fork/exec; each test restores it.
struct FaultHook {
    explicit FaultHook(const char* what) { setenv("NURBSRT_IMPORT_WORKER_FAULT", what, 1); }
    ~FaultHook() { unsetenv("NURBSRT_IMPORT_WORKER_FAULT"); }
};

TEST_P(IsolatedImport, SameSceneAsInProcess) {
    const nurbsrt::Scene a = nurbsrt::import_isolated(kScrew, {}, limits(120));
    const nurbsrt::Scene b = nurbsrt::import_file(kScrew, {});
    ASSERT_EQ(a.faces.size(), b.faces.size());
    // Import is deterministic, so the serialized geometry must match byte for byte
    // once the (wall-clock) timings are equalized.
    nurbsrt::Scene a2 = a, b2 = b;
    a2.timings = b2.timings = {};
    EXPECT_EQ(nurbsrt::serialize_scene(a2), nurbsrt::serialize_scene(b2));
}

TEST_P(IsolatedImport, ChildErrorsKeepTheirCode) {
    EXPECT_EQ(code_of([this] { nurbsrt::import_isolated("/nonexistent.step", {}, limits(60)); }),
              nurbsrt::ErrorCode::io);
    // Per process: ctest runs the two instances of this test at once, and a shared
    // name let one remove the file while the other's child read it (io, not unsupported_format).
    const std::string junk =
        (std::filesystem::temp_directory_path() / ("nurbsrt-isolated-junk-" + std::to_string(::getpid()) + ".igs"))
            .string();
    std::ofstream(junk) << "this is not a CAD file\n";
    EXPECT_EQ(code_of([&, this] { nurbsrt::import_isolated(junk, {}, limits(60)); }),
              nurbsrt::ErrorCode::unsupported_format);
    std::filesystem::remove(junk);
}

TEST_P(IsolatedImport, CrashFailsOnlyThisImport) {
    {
        FaultHook hook("crash");
        EXPECT_EQ(code_of([this] { nurbsrt::import_isolated(kScrew, {}, limits(60)); }),
                  nurbsrt::ErrorCode::import_crashed);
    }
    EXPECT_EQ(nurbsrt::import_isolated(kScrew, {}, limits(120)).faces.size(), 10u);
}

TEST_P(IsolatedImport, HangIsKilledAtTheTimeLimit) {
    FaultHook hook("hang");
    const auto t0 = std::chrono::steady_clock::now();
    EXPECT_EQ(code_of([this] { nurbsrt::import_isolated(kScrew, {}, limits(1.0)); }),
              nurbsrt::ErrorCode::import_timeout);
    // Not a performance assertion: proves the child was killed rather than waited for.
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 30.0);
}

TEST(IsolatedImportOptions, WorkerOptionsRoundTrip) {
    nurbsrt::ImportOptions o;
    o.mesh_relative_deflection = 0.0123;
    o.mesh_angular_deflection = 0.5;
    o.mesh_time_limit_s = 7;
    o.trim_relative_tolerance = 3e-5;
    o.read_attributes = false;
    const nurbsrt::ImportOptions p = nurbsrt::import_options_from_args(nurbsrt::import_options_to_args(o));
    EXPECT_EQ(p.mesh_relative_deflection, o.mesh_relative_deflection);
    EXPECT_EQ(p.mesh_angular_deflection, o.mesh_angular_deflection);
    EXPECT_EQ(p.mesh_time_limit_s, o.mesh_time_limit_s);
    EXPECT_EQ(p.trim_relative_tolerance, o.trim_relative_tolerance);
    EXPECT_EQ(p.read_attributes, o.read_attributes);
    EXPECT_THROW(nurbsrt::import_options_from_args({"--bogus=1"}), nurbsrt::Error);
    EXPECT_THROW(nurbsrt::import_options_from_args({"--mesh-angle=abc"}), nurbsrt::Error);
}

// The child's stages (Scene::timings) and the parent's share (IsolationTimings)
// are the whole call: what the service's render timings add up from.
TEST_P(IsolatedImport, StagesAndIsolationAreTheWholeCall) {
    nurbsrt::IsolationTimings t;
    const auto t0 = std::chrono::steady_clock::now();
    const nurbsrt::Scene s = nurbsrt::import_isolated(kScrew, {}, limits(120), &t);
    const double wall = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    const nurbsrt::ImportTimings& c = s.timings;
    const double sum = t.prescan_ms + t.isolation_ms + t.transfer_ms + c.read_ms + c.nurbs_convert_ms + c.mesh_ms;
    EXPECT_GT(t.isolation_ms, 0);  // starting a process is never free
    EXPECT_GT(t.transfer_ms, 0);
    EXPECT_GE(t.prescan_ms, 0);
    // By construction, not by timing: the stages add up to the call's total,
    // which lies within the wall time seen from outside.
    EXPECT_NEAR(sum, t.total_ms, 1e-9 * t.total_ms);
    EXPECT_LE(t.total_ms, wall);
}

// A file's plan (the service's batch jobs): one child reads the file once for
// the scene and every conversion, and makes what separate calls make.
TEST_P(IsolatedImport, FilePlanReadsOnceAndMatchesSeparateCalls) {
    const std::string dir =
        (std::filesystem::temp_directory_path() / ("nurbsrt-isolated-plan-" + std::to_string(::getpid()) + "-" +
                                                   std::to_string(reinterpret_cast<uintptr_t>(GetParam()) % 1000)))
            .string();
    std::filesystem::create_directories(dir);
    nurbsrt::FilePlan plan;
    plan.scene = true;
    plan.conversions = {dir + "/a.glb", dir + "/a.stl", dir + "/a.stp"};
    const nurbsrt::FileResult r = nurbsrt::process_file_isolated(kScrew, plan, limits(120));
    EXPECT_EQ(r.reads, 1);
    EXPECT_EQ(r.uses, 4);  // the import and three conversions
    EXPECT_GT(r.read_ms, 0);
    ASSERT_TRUE(r.scene) << (r.scene_error ? r.scene_error->what() : "");
    nurbsrt::Scene alone = nurbsrt::import_isolated(kScrew, {}, limits(120)), shared = *r.scene;
    alone.timings = shared.timings = {};
    EXPECT_EQ(nurbsrt::serialize_scene(shared), nurbsrt::serialize_scene(alone));
    ASSERT_EQ(r.conversions.size(), 3u);
    double read_ms = 0;
    for (const auto& c : r.conversions) {
        ASSERT_TRUE(c.report) << (c.error ? c.error->what() : "");
        EXPECT_EQ(c.report->faces, 10);
        read_ms += c.report->read_ms;
    }
    EXPECT_EQ(read_ms, 0);  // the import paid the one read
    // The mesh outputs are byte for byte those of a conversion alone (the STEP
    // file is not: OCCT's writer orders its styles differently from run to run).
    for (const char* ext : {".glb", ".stl"}) {
        nurbsrt::convert_isolated(kScrew, dir + "/b" + ext, limits(120));
        std::ifstream a(dir + "/a" + ext, std::ios::binary), b(dir + "/b" + ext, std::ios::binary);
        const std::string sa((std::istreambuf_iterator<char>(a)), {}), sb((std::istreambuf_iterator<char>(b)), {});
        EXPECT_FALSE(sa.empty());
        EXPECT_EQ(sa, sb) << ext;
    }
    // Each conversion's own options cross to the child (a job output's options).
    nurbsrt::FilePlan with_options;
    with_options.conversions = {dir + "/o.stp", dir + "/o.stl"};
    with_options.conversion_options.resize(2);
    with_options.conversion_options[0].units = nurbsrt::LengthUnit::cm;
    with_options.conversion_options[1].deflection = 0.05;
    const nurbsrt::FileResult o = nurbsrt::process_file_isolated(kScrew, with_options, limits(120));
    ASSERT_EQ(o.conversions.size(), 2u);
    ASSERT_TRUE(o.conversions[0].report && o.conversions[1].report);
    EXPECT_EQ(o.conversions[0].report->out_units, "cm");
    EXPECT_LT(o.conversions[1].report->triangles, r.conversions[1].report->triangles);
    // A file that cannot be read: every item has the read's error, tried once.
    const std::string junk = dir + "/junk.stp";
    std::ofstream(junk) << "ISO-10303-21;\nHEADER;\nthis is not a STEP file\n";
    plan.conversions = {dir + "/j.stl", dir + "/j.glb"};
    const nurbsrt::FileResult bad = nurbsrt::process_file_isolated(junk, plan, limits(60));
    ASSERT_TRUE(bad.scene_error);
    EXPECT_EQ(bad.reads, 1);
    for (const auto& c : bad.conversions) {
        ASSERT_TRUE(c.error);
        EXPECT_EQ(c.error->code(), bad.scene_error->code());
        EXPECT_STREQ(c.error->what(), bad.scene_error->what());
    }
    std::filesystem::remove_all(dir);
}

// A crash fails the whole plan with the child's error, as an import's.
TEST_P(IsolatedImport, FilePlanCrashFailsTheWholeFile) {
    const FaultHook fault("crash");
    nurbsrt::FilePlan plan;
    plan.scene = true;
    EXPECT_EQ(code_of([&] { nurbsrt::process_file_isolated(kScrew, plan, limits(60)); }),
              nurbsrt::ErrorCode::import_crashed);
}

INSTANTIATE_TEST_SUITE_P(Workers, IsolatedImport, ::testing::Values(NURBSRT_WORKER_BINARY, NURBSRT_BINARY),
                         [](const ::testing::TestParamInfo<const char*>& info) {
                             return std::string(info.index == 0 ? "nurbsrt_worker" : "nurbsrt_subcommand");
                         });

// With no worker named, the import runs nurbsrt-worker from beside the running
// program: this test binary is built beside it and has no worker subcommand of
// its own, so a successful import proves the sibling was found and used.
TEST(IsolatedImportDefault, FindsTheWorkerBesideTheProgram) {
    ASSERT_TRUE(std::filesystem::exists(NURBSRT_WORKER_BINARY));
    ASSERT_EQ(std::filesystem::path(NURBSRT_WORKER_BINARY).parent_path(),
              std::filesystem::canonical("/proc/self/exe").parent_path());
    nurbsrt::IsolationLimits l;
    l.time_limit_s = 120;
    EXPECT_EQ(nurbsrt::import_isolated(kScrew, {}, l).faces.size(), 10u);
}

}  // namespace
