// The pre-scan of STEP/IGES text: real files pass with their true counts, absurd
// ones (a huge list, deep nesting, too many entities) are refused before OCCT
// parses them, and delimiters inside strings, comments and Hollerith fields do
// not count.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "importer/isolated.h"
#include "importer/prescan.h"
#include "core/error.h"
#include "tests/support/fixtures.h"

using namespace nurbsrt;

namespace {

std::string write_temp(const std::string& name, const std::string& text) {
    const auto path = std::filesystem::temp_directory_path() / ("nurbsrt-prescan-" + name);
    std::ofstream(path, std::ios::binary) << text;
    return path.string();
}

std::string step_with_data(const std::string& data) {
    return "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION(('a, b; c'),'2;1');\nFILE_NAME('x','',(''),(''),'','','');\n"
           "FILE_SCHEMA(('AUTOMOTIVE_DESIGN'));\nENDSEC;\nDATA;\n" +
           data + "ENDSEC;\nEND-ISO-10303-21;\n";
}

// A POLYLINE entity whose point list has `items` items.
std::string polyline(int items) {
    std::string line = "#1=POLYLINE('',(";
    for (int i = 1; i < items; ++i) line += "#2,";
    return line + "#2));\n";
}

ErrorCode refusal(const std::string& path, CadFormat f, const PrescanLimits& limits) {
    try {
        prescan_cad_file(path, f, limits);
    } catch (const Error& e) {
        return e.code();
    }
    return ErrorCode::internal;  // not refused
}

}  // namespace

TEST(Prescan, StepCountsEntitiesListsAndNesting) {
    const std::string path = write_temp(
        "ok.step", step_with_data("#1=CARTESIAN_POINT('p;(,)',(0.,1.,2.));\n/* a comment ; , ( */\n"
                                  "#2=B_SPLINE_SURFACE_WITH_KNOTS('',1,1,((#1,#1,#1,#1),(#1,#1,#1,#1)),.U.,.F.,.F.,.F.,"
                                  "(2,2),(2,2),(0.,1.),(0.,1.),.UNSPECIFIED.);\n#3=ABC(());\n"));
    const PrescanReport r = prescan_cad_file(path, CadFormat::step, {});
    EXPECT_EQ(r.entities, 3u);       // instances (#N=); header statements are none
    EXPECT_EQ(r.longest_list, 13u);  // the surface's own parameter list
    EXPECT_EQ(r.deepest_nesting, 3);
    std::filesystem::remove(path);
}

TEST(Prescan, StepRefusesHugeListsDeepNestingAndTooManyEntities) {
    const std::string list = write_temp("list.step", step_with_data(polyline(2001)));
    PrescanLimits limits;
    limits.max_list_items = 1000;
    EXPECT_EQ(refusal(list, CadFormat::step, limits), ErrorCode::unreadable_file);
    limits.max_list_items = 5000;
    EXPECT_EQ(prescan_cad_file(list, CadFormat::step, limits).longest_list, 2001u);

    const std::string deep =
        write_temp("deep.step", step_with_data("#1=A(" + std::string(100, '(') + std::string(101, ')') + ";\n"));
    EXPECT_EQ(refusal(deep, CadFormat::step, {}), ErrorCode::unreadable_file);

    std::string many;
    for (int i = 1; i <= 300; ++i) {
        many += '#';
        many += std::to_string(i);
        many += "=A(1);\n";
    }
    const std::string entities = write_temp("many.step", step_with_data(many));
    limits = {};
    limits.max_entities = 100;
    EXPECT_EQ(refusal(entities, CadFormat::step, limits), ErrorCode::unreadable_file);
    for (const auto& p : {list, deep, entities}) std::filesystem::remove(p);
}

TEST(Prescan, ImportIsolatedRefusesBeforeAnyChildStarts) {
    const std::string path = write_temp("refused.step", step_with_data(polyline(3001)));
    IsolationLimits limits;
    limits.prescan.max_list_items = 1000;
    limits.worker_executable = "/nonexistent/worker";  // a started child would fail differently
    try {
        import_isolated(path, {}, limits);
        FAIL() << "not refused";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::unreadable_file);
        EXPECT_NE(std::string(e.what()).find("a list of more than 1000 items (the limit)"), std::string::npos)
            << e.what();
    }
    std::filesystem::remove(path);
}

TEST(Prescan, RealFilesPass) {
    for (const char* file :
         {"/usr/share/opencascade/data/step/screw.step", "/usr/share/opencascade/data/iges/bearing.iges"}) {
        const bool iges = std::string(file).find(".iges") != std::string::npos;
        const PrescanReport r = prescan_cad_file(file, iges ? CadFormat::iges : CadFormat::step, {});
        EXPECT_GT(r.entities, 50u) << file;
        EXPECT_GT(r.longest_list, 3u) << file;
        EXPECT_LT(r.longest_list, 100000u) << file;
    }
}

TEST(Prescan, IgesCountsParameterListsAndSkipsHollerith) {
    auto rec = [](std::string body, char section, int seq) {
        body.resize(72, ' ');
        char tail[16];
        std::snprintf(tail, sizeof tail, "%c%7d\n", section, seq);
        return body + tail;
    };
    std::string iges = rec("a test file", 'S', 1) + rec("1H,,1H;,4HA,B;,", 'G', 1);
    iges += rec("     116       1       0       0       0       0       0       000000000", 'D', 1);
    iges += rec("     116       0       0       1       0                               0", 'D', 2);
    std::string params = "116,1.,2.,3.,0,5H;,,;;,7.;";  // the Hollerith field holds both delimiters
    params.resize(64, ' ');
    iges += params + "       1P      1\n";  // columns 65-72: the entity's directory pointer
    iges += rec("S      1G      2D      2P      1", 'T', 1);
    const std::string path = write_temp("t.iges", iges);
    const PrescanReport r = prescan_cad_file(path, CadFormat::iges, {});
    EXPECT_EQ(r.entities, 1u);
    EXPECT_EQ(r.longest_list, 7u);  // 116, 1., 2., 3., 0, 5H;,,;;, 7.
    PrescanLimits limits;
    limits.max_list_items = 6;
    EXPECT_EQ(refusal(path, CadFormat::iges, limits), ErrorCode::unreadable_file);
    std::filesystem::remove(path);
}

// No real file is refused by the default limits: every STEP/IGES of
// ../shared/models (good and broken alike: the broken ones must reach OCCT's
// own, precise error) passes, with counts reported for the record.
TEST(Prescan, EveryRealModelPassesTheDefaults) {
    NURBSRT_REQUIRE_SHARED_MODELS();
    size_t files = 0, longest = 0, entities = 0;
    int deepest = 0;
    for (const char* dir : {"step", "iges", "duck", "broken"}) {
        for (const std::string& path : test::shared_model_files(dir)) {
            const CadFormat f = detect_format(path);
            if (f == CadFormat::unknown) continue;
            PrescanReport r;
            ASSERT_NO_THROW(r = prescan_cad_file(path, f, {})) << path;
            ++files;
            longest = std::max(longest, r.longest_list);
            entities = std::max(entities, r.entities);
            deepest = std::max(deepest, r.deepest_nesting);
        }
    }
    EXPECT_GT(files, 30u);
    std::printf("pre-scan of %zu files: most entities %zu, longest list %zu, deepest nesting %d\n", files, entities,
                longest, deepest);
}
