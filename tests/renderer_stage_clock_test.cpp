// Stage timings that add up: StageClock's marks sum to its total by
// construction, and a frame's stages (RenderStats) sum to its total_ms; the
// Newton statistics agree with their histogram.
#include <gtest/gtest.h>

#include <cmath>
#include <thread>

#include "renderer/render.h"
#include "core/stage_clock.h"
#include "renderer_test_surfaces.h"

using namespace nurbsrt;
using namespace nurbsrt::testing;

namespace {

using Clock = StageClock::Clock;
constexpr auto kStep = std::chrono::milliseconds(3);

Clock::time_point at(Clock::time_point t0, int steps) { return t0 + steps * kStep; }

}  // namespace

TEST(StageClock, MarksRunEndToEndAndSumToTheTotal) {
    const auto t0 = Clock::now();
    StageClock c(t0);
    EXPECT_DOUBLE_EQ(c.mark("a", at(t0, 1)), 3.0);
    EXPECT_DOUBLE_EQ(c.mark("b", at(t0, 3)), 6.0);
    EXPECT_DOUBLE_EQ(c.mark("a", at(t0, 4)), 3.0);  // a stage marked twice: its parts add
    ASSERT_EQ(c.stages().size(), 2u);
    EXPECT_EQ(c.stages()[0].name, "a");  // in order of first mark
    EXPECT_DOUBLE_EQ(c.ms("a"), 6.0);
    EXPECT_DOUBLE_EQ(c.ms("b"), 6.0);
    EXPECT_DOUBLE_EQ(c.ms("never"), 0.0);
    EXPECT_DOUBLE_EQ(c.total_ms(), 12.0);
    EXPECT_DOUBLE_EQ(c.sum_ms(), c.total_ms());
}

TEST(StageClock, NestedStagesAreTakenOutOfTheirEnclosingStage) {
    const auto t0 = Clock::now();
    StageClock c(t0);
    c.add("child", 4.0);   // measured elsewhere, inside the running stage
    c.add("other", -1.0);  // nonsense counts as nothing
    c.add("nan", std::nan(""));
    EXPECT_DOUBLE_EQ(c.mark("call", at(t0, 2)), 2.0);
    EXPECT_DOUBLE_EQ(c.ms("child"), 4.0);
    EXPECT_DOUBLE_EQ(c.ms("other"), 0.0);
    EXPECT_DOUBLE_EQ(c.ms("nan"), 0.0);
    EXPECT_DOUBLE_EQ(c.sum_ms(), c.total_ms());
    // More nested time than the stage had: the stage is 0, never negative.
    c.add("child", 10.0);
    EXPECT_DOUBLE_EQ(c.mark("call", at(t0, 3)), 0.0);
    EXPECT_GT(c.sum_ms(), c.total_ms());
}

TEST(StageClock, ACallerMarkBeforeThePreviousOneCountsAsNone) {
    const auto t0 = Clock::now();
    StageClock c(t0);
    c.mark("a", at(t0, 2));
    EXPECT_DOUBLE_EQ(c.mark("b", at(t0, 1)), 0.0);
    EXPECT_DOUBLE_EQ(c.total_ms(), 6.0);
    EXPECT_DOUBLE_EQ(c.sum_ms(), c.total_ms());
}

TEST(StageClock, RealTimeMarksAddUp) {
    StageClock c;
    std::this_thread::sleep_for(kStep);
    c.mark("sleep");
    c.mark("nothing");
    EXPECT_GE(c.ms("sleep"), 3.0);
    EXPECT_GE(c.ms("nothing"), 0.0);
    EXPECT_NEAR(c.sum_ms(), c.total_ms(), 1e-9 * c.total_ms());
}

namespace {

double frame_stage_sum(const RenderStats& s) {
    return s.prepare_ms + s.setup_ms + s.preliminary_map_ms + s.newton_ms + s.shadow_map_ms + s.shade_ms +
           s.antialias_ms + s.edges_ms + s.statistics_ms;
}

void expect_newton_statistics_add_up(const RenderStats& s) {
    uint64_t hist_sum = 0, steps = 0;
    ASSERT_EQ(s.iteration_histogram.size(), static_cast<size_t>(s.iteration_limit) + 1);
    for (size_t k = 0; k < s.iteration_histogram.size(); ++k) {
        hist_sum += s.iteration_histogram[k];
        steps += k * s.iteration_histogram[k];
    }
    EXPECT_EQ(hist_sum, s.solves);
    EXPECT_EQ(s.converged + s.trimmed + s.diverged + s.singular + s.max_iterations + s.left_domain + s.behind_eye,
              s.solves);
    // Unconverged after iteration_limit steps: they are in the histogram's last bin.
    EXPECT_LE(s.max_iterations, s.iteration_histogram.back());
    EXPECT_NEAR(s.mean_iterations, s.solves ? double(steps) / double(s.solves) : 0.0, 1e-12);
    EXPECT_EQ(s.rescue_neighbour + s.rescue_silhouette + s.rescue_general + s.rescue_trim_tolerance, s.fallback);
    EXPECT_EQ(s.converged + s.fallback, s.pixels_hit);
    EXPECT_GT(s.solves, 0u);
}

}  // namespace

TEST(FrameStatistics, StagesSumToTheTotalAndNewtonCountsToTheHistogram) {
    AnalyticPatch sphere, plane;
    const Scene scene = sphere_and_holed_plane(sphere, plane);
    const Camera cam(iso_view(scene, 160, 120));
    for (NewtonMethod m : {NewtonMethod::proposed, NewtonMethod::martin}) {
        for (bool look : {false, true}) {
            RenderOptions opt;
            opt.method = m;
            opt.antialias = look ? 4 : 0;
            opt.edges = look;
            opt.shadows = look;
            const RenderStats s = render(scene, cam, opt).stats;
            SCOPED_TRACE(std::string(newton_method_name(m)) + (look ? " with the look passes" : " plain"));
            EXPECT_GT(s.prepare_ms, 0.0);
            EXPECT_GE(s.statistics_ms, 0.0);
            EXPECT_EQ(s.shadow_map_ms > 0, look);
            // Laps of one clock: equal but for the rounding of the sum.
            EXPECT_NEAR(frame_stage_sum(s), s.total_ms, 1e-9 * s.total_ms);
            EXPECT_LE(s.newton_primary_ms, s.newton_ms);
            expect_newton_statistics_add_up(s);
        }
    }
}

TEST(FrameStatistics, AnIterationCapCountsItsUnconvergedSolvesInTheLastBin) {
    AnalyticPatch sphere, plane;
    const Scene scene = sphere_and_holed_plane(sphere, plane);
    const Camera cam(iso_view(scene, 96, 72));
    RenderOptions opt;
    opt.newton.max_iterations = 1;  // many solves need 2 or more steps
    const RenderStats s = render(scene, cam, opt).stats;
    EXPECT_EQ(s.iteration_limit, 1);
    EXPECT_GT(s.max_iterations, 0u);
    expect_newton_statistics_add_up(s);
}
