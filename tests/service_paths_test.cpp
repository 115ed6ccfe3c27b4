// Problem details never show the service's private directories.
#include <gtest/gtest.h>

#include <filesystem>

#include "server/render/context.h"
#include "server/routes/handler_util.h"

using namespace nurbsrt::server;

TEST(ServicePaths, ErrorMessagesLoseTheDataAndScratchDirectories) {
    const std::string dir = (std::filesystem::temp_directory_path() / "nurbsrt-paths-test").string();
    ServerConfig c;
    c.data_dir = dir + "/";
    ServerContext ctx(c);
    const std::string scratch = ctx.scratch.path();
    ASSERT_EQ(scratch.rfind(dir, 0), 0u) << scratch;
    EXPECT_EQ(without_service_paths("cannot read " + scratch + "/upload-qM81Gn.cad: truncated", ctx),
              "cannot read the upload: truncated");
    EXPECT_EQ(without_service_paths("import of '" + scratch + "/upload-x1.cad' into '" + scratch +
                                        "/nurbsrt-import-AbC' failed; cannot write " + scratch + "/converted-Q.stl",
                                    ctx),
              "import of 'the upload' into 'a scratch file' failed; cannot write the converted file");
    EXPECT_EQ(without_service_paths("cannot open " + dir + "/jobs/ab/in-0 and " + dir + "/jobs.db", ctx),
              "cannot open jobs/ab/in-0 and jobs.db");
    EXPECT_EQ(without_service_paths("no path here", ctx), "no path here");
    std::filesystem::remove_all(dir);
}
