// server/jobs/artifact_reuse.h: the key of an output made before, keeping and
// finding its artifact and result, and expiry by age.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "server/jobs/artifact_reuse.h"

using namespace nurbsrt::server;
namespace fs = std::filesystem;

namespace {

JobOutput conversion(const std::string& format, const std::string& artifact) {
    JobOutput o;
    o.kind = OutputKind::conversion;
    o.options_json = R"({"format":")" + format + R"("})";
    o.artifact = artifact;
    return o;
}

std::string slurp(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

class ArtifactReuseTest : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / ("nurbsrt-reuse-test-" + std::to_string(::getpid()));
        fs::remove_all(dir_);
        fs::create_directories(dir_ + "/job");
    }
    void TearDown() override { fs::remove_all(dir_); }
    std::string dir_;
};

}  // namespace

TEST(ArtifactReuseKey, DependsOnTheFileTheKindTheOptionsAndTheExtension) {
    const JobOutput stl = conversion("stl", "0-conversion-1.stl");
    const std::string a(64, 'a'), b(64, 'b');
    EXPECT_EQ(ArtifactReuse::key(a, stl), ArtifactReuse::key(a, conversion("stl", "3-conversion-7.stl")))
        << "the artifact's name (file and output numbers) is not part of the key";
    EXPECT_NE(ArtifactReuse::key(a, stl), ArtifactReuse::key(b, stl));
    EXPECT_NE(ArtifactReuse::key(a, stl), ArtifactReuse::key(a, conversion("glb", "0-conversion-1.glb")));
    JobOutput render = stl;
    render.kind = OutputKind::render;
    EXPECT_NE(ArtifactReuse::key(a, stl), ArtifactReuse::key(a, render));
    EXPECT_EQ(ArtifactReuse::key(a, stl).size(), 64u);
    // An output of several files: a key per file, by its view and extension, not its output's number.
    const JobOutput obj = conversion("obj", "0-conversion-1.obj");
    EXPECT_EQ(ArtifactReuse::key(a, obj), ArtifactReuse::key(a, obj, "0-conversion-1.obj"));
    EXPECT_NE(ArtifactReuse::key(a, obj, "0-conversion-1.obj"), ArtifactReuse::key(a, obj, "0-conversion-1.mtl"));
    EXPECT_EQ(ArtifactReuse::key(a, render, "0-render-1.front.png"),
              ArtifactReuse::key(a, render, "2-render-5.front.png"));
    EXPECT_NE(ArtifactReuse::key(a, render, "0-render-1.front.png"),
              ArtifactReuse::key(a, render, "0-render-1.iso.png"));
}

TEST_F(ArtifactReuseTest, KeepsFindsAndExpires) {
    ArtifactReuse reuse(dir_ + "/reuse");
    const std::string key = ArtifactReuse::key(std::string(64, 'c'), conversion("stl", "0-conversion-0.stl"));
    EXPECT_FALSE(reuse.recall(key, dir_ + "/job/partial-x.stl"));  // nothing kept yet
    { std::ofstream(dir_ + "/job/0-conversion-0.stl") << "solid bytes"; }
    reuse.remember(key, dir_ + "/job/0-conversion-0.stl", R"({"faces":3})");
    fs::remove(dir_ + "/job/0-conversion-0.stl");  // the job that made it is gone: the kept link remains
    const auto result = reuse.recall(key, dir_ + "/job/partial-y.stl");
    ASSERT_TRUE(result);
    EXPECT_EQ(*result, R"({"faces":3})");
    EXPECT_EQ(slurp(dir_ + "/job/partial-y.stl"), "solid bytes");
    struct stat st {};
    ASSERT_EQ(::stat((dir_ + "/job/partial-y.stl").c_str(), &st), 0);
    EXPECT_EQ(st.st_nlink, 2u);                                       // a hard link, not a copy
    EXPECT_FALSE(reuse.recall("../../etc/passwd", dir_ + "/job/z"));  // only keys name entries

    EXPECT_EQ(reuse.expire(unix_now_ms() - 60'000), 0);  // made just now: kept
    EXPECT_EQ(reuse.expire(unix_now_ms() + 60'000), 1);  // everything made before a minute from now
    EXPECT_FALSE(reuse.recall(key, dir_ + "/job/partial-z.stl"));
}
