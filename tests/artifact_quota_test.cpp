// server/jobs/artifact_quota.h: the estimate a job is admitted by, and the check
// both submission and each artifact's write go through.
#include <gtest/gtest.h>

#include "core/error.h"
#include "server/jobs/artifact_quota.h"

using namespace nurbsrt::server;

TEST(ArtifactQuota, EstimatesBoundWhatTheOutputsWrite) {
    JobOutput png;
    png.kind = OutputKind::render;
    png.options_json = R"({"width":400,"height":300})";
    EXPECT_EQ(estimated_artifact_bytes(png, 1000), 400 * 300 * 4);  // RGBA, uncompressed
    JobOutput exr = png;
    exr.options_json = R"({"width":400,"height":300,"format":"exr"})";
    EXPECT_EQ(estimated_artifact_bytes(exr, 1000), 400 * 300 * 48);  // 12 float channels
    JobOutput views = png;  // a frame per view, one file each or a sheet of them
    views.options_json = R"({"width":400,"height":300,"views":["front","top","iso"],"layout":"separate"})";
    EXPECT_EQ(estimated_artifact_bytes(views, 1000), 3 * 400 * 300 * 4);
    JobOutput conversion;
    conversion.kind = OutputKind::conversion;
    conversion.options_json = R"({"format":"stl"})";
    EXPECT_EQ(estimated_artifact_bytes(conversion, 88'552), 4 * 88'552);
}

TEST(ArtifactQuota, CheckRefusesOnlyBeyondTheQuota) {
    EXPECT_NO_THROW(check_artifact_quota(600, 400, 1000, "x"));  // exactly full is allowed
    try {
        check_artifact_quota(600 << 20, 500 << 20, size_t(1000) << 20, "the job's artifacts, estimated");
        FAIL() << "no exception";
    } catch (const nurbsrt::Error& e) {
        EXPECT_EQ(e.code(), nurbsrt::ErrorCode::limit_exceeded);
        const std::string m = e.what();
        EXPECT_NE(m.find("the job's artifacts, estimated (500 MiB)"), std::string::npos) << m;
        EXPECT_NE(m.find("quota of 1000 MiB (600 MiB in use"), std::string::npos) << m;
    }
    EXPECT_GT(default_artifact_quota("/"), size_t(0));
}
