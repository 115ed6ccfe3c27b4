// "Identical output for 1 and 2 threads" on real models, end to end as a user runs
// it (import -> named view -> render): every AOV buffer and every statistic except
// timings must be bit-identical. The renderer is designed for it (its passes: each
// pixel's result depends only on the map and the previous pass, never on which
// thread ran first), and this is what would catch a race or an order dependence.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "importer/importer.h"
#include "renderer/camera.h"
#include "renderer/render.h"
#include "support/fixtures.h"
#include "tests/support/render_compare.h"

using namespace nurbsrt;

namespace {

struct ThreadCase {
    std::string name, path;  // path "" -> shared model absent
};

std::vector<ThreadCase> thread_cases() {
    std::vector<ThreadCase> c;
    c.push_back({"occt_bearing_iges", "/usr/share/opencascade/data/iges/bearing.iges"});
    c.push_back({"phone_cornetta", test::shared_model("step/bug27693_cornetta-step.stp")});
    c.push_back({"duck", test::shared_model("duck/duck_from_glscene.igs")});
    return c;
}

void expect_same(const RenderResult& a, const RenderResult& b, const std::string& what) {
    SCOPED_TRACE(what);
    test::expect_identical_renders(a, b);
}

}  // namespace

class RenderThreads : public ::testing::TestWithParam<ThreadCase> {};

TEST_P(RenderThreads, OneAndTwoThreadsGiveIdenticalOutput) {
    const ThreadCase& c = GetParam();
    if (c.path.empty()) GTEST_SKIP() << "../shared/models is absent: skipping " << c.name;
    const Scene scene = import_file(c.path);
    CameraSpec base;
    base.width = 320;
    base.height = 240;
    for (const char* view : {"iso", "front"})
        for (NewtonMethod m : {NewtonMethod::proposed, NewtonMethod::martin}) {
            const Camera cam(fit_view(view, scene, base));
            RenderOptions o1, o2;
            o1.method = o2.method = m;
            o1.threads = 1;
            o2.threads = 2;
            const RenderResult a = render(scene, cam, o1), b = render(scene, cam, o2);
            ASSERT_EQ(a.stats.threads, 1);
            ASSERT_EQ(b.stats.threads, 2);
            EXPECT_GT(a.stats.pixels_hit, 1000u);
            expect_same(a, b, c.name + "/" + view + "/" + newton_method_name(m));
            std::printf("[ threads ] %s/%s/%s: %zu hit pixels, %llu rescued, identical: %s\n", c.name.c_str(), view,
                        newton_method_name(m), a.stats.pixels_hit, static_cast<unsigned long long>(a.stats.fallback),
                        ::testing::Test::HasFailure() ? "NO" : "yes");
        }
}

// Prepare once, render many (renderer/prepared_scene.h) on real models: frames of
// one PreparedScene from several views, with 1 thread, equal fresh single
// renders of the Scene with 2 threads, bit for bit.
TEST_P(RenderThreads, PreparedOnceManyViewsEqualFreshRenders) {
    const ThreadCase& c = GetParam();
    if (c.path.empty()) GTEST_SKIP() << "../shared/models is absent: skipping " << c.name;
    const Scene scene = import_file(c.path);
    const PreparedScene prepared = prepare(scene);
    CameraSpec base;
    base.width = 320;
    base.height = 240;
    for (const char* view : {"iso", "front", "top", "left"}) {
        const Camera cam(fit_view(view, scene, base));
        RenderOptions o1, o2;
        o1.threads = 1;
        o2.threads = 2;
        const RenderResult many = render(prepared, cam, o1), fresh = render(scene, cam, o2);
        EXPECT_GT(many.stats.pixels_hit, 1000u);
        expect_same(many, fresh, c.name + "/" + view + "/prepared");
    }
}

INSTANTIATE_TEST_SUITE_P(Models, RenderThreads, ::testing::ValuesIn(thread_cases()),
                         [](const ::testing::TestParamInfo<ThreadCase>& i) { return i.param.name; });
