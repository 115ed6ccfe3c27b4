// MeshScreenPoints (renderer/frame/mesh_screen_points.h): the mesh starts of faces no
// nearby pixel shows, and of sheets of a face in front of a depth. A search
// bounded to a screen distance gives the unbounded search's answer wherever the
// mesh comes within the bound, and nothing where it does not; through the first
// queries' scans and the grid alike. The frontmost point and the covering
// sheets against brute force over the mesh.
#include <gtest/gtest.h>

#include <tbb/task_arena.h>

#include <cmath>
#include <random>

#include "renderer/frame/frame.h"
#include "renderer/frame/mesh_screen_points.h"
#include "renderer_test_surfaces.h"

using namespace nurbsrt;
using namespace nurbsrt::testing;

namespace {

constexpr int kWidth = 96, kHeight = 64;

Scene test_scene() {
    AnalyticPatch sphere, plane;
    return sphere_and_holed_plane(sphere, plane);
}

// A frame's context over a scene at its iso view; MeshScreenPoints reads the
// mesh and camera only (the map stays empty).
struct TestFrame {
    explicit TestFrame(Scene s)
        : scene(std::move(s)),
          cam(iso_view(scene, kWidth, kHeight)),
          prepared(prepare(scene, 1)),
          arena(1),
          progress(options.progress, 1),
          face_cameras(cam, options.face_offsets),
          c{prepared,
            scene,
            cam,
            face_cameras,
            map,
            options,
            arena,
            progress,
            cam.width(),
            cam.height(),
            static_cast<uint32_t>(scene.faces.size()),
            scene.bbox} {}
    Scene scene;
    Camera cam;
    PreparedScene prepared;
    PreliminaryMap map;
    RenderOptions options;
    tbb::task_arena arena;
    Progress progress;
    FaceCameras face_cameras;
    FrameContext c;
};

// Screen position and depth of a model point, as MeshScreenPoints computes them.
void project(const Camera& cam, const Vec3& P, Vec2& s, double& z) {
    const Vec4 ph = cam.project_h(Vec4{P.x, P.y, P.z, 1.0});
    z = cam.depth(ph);
    s = {ph.x / ph.z, ph.y / ph.z};
}

}  // namespace

TEST(MeshScreenPoints, BoundedSearchGivesTheUnboundedAnswerWithinTheBound) {
    const TestFrame f(test_scene());
    const Camera& cam = f.cam;
    const FrameContext& c = f.c;
    const MeshScreenPoints unbounded(c), bounded(c);
    // Screen units span 2 over the height: bounds of 1, 4 and 16 pixels.
    const double pixel = 2.0 / cam.height();
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> x(-1.8, 1.8), y(-1.2, 1.2);
    int within = 0, beyond = 0;
    for (int k = 0; k < 400; ++k) {
        const ScreenPoint sp{x(rng), y(rng)};
        for (uint32_t id = 1; id <= c.nfaces; ++id) {
            Vec2 all[2];
            double d2 = 0;
            const int n = unbounded.nearest_starts(id, sp, all, &d2);
            ASSERT_GT(n, 0);
            for (const double reach : {1.0, 4.0, 16.0}) {
                const double max_d2 = (reach * pixel) * (reach * pixel);
                Vec2 got[2];
                double got_d2 = -1;
                const int m = bounded.nearest_starts(id, sp, got, &got_d2, max_d2);
                if (d2 <= max_d2) {
                    ++within;
                    ASSERT_EQ(m, n);
                    EXPECT_EQ(got_d2, d2);
                    for (int q = 0; q < n; ++q) {
                        EXPECT_EQ(got[q].x, all[q].x);
                        EXPECT_EQ(got[q].y, all[q].y);
                    }
                } else {
                    ++beyond;
                    EXPECT_EQ(m, 0);
                    EXPECT_EQ(got_d2, HUGE_VAL);
                }
            }
        }
    }
    // Both cases occur often (the points cover the faces and the space around them).
    EXPECT_GT(within, 300);
    EXPECT_GT(beyond, 300);
}

// frontmost_point: the mesh point nearest to the eye within a screen distance of
// a point, against a brute-force sampling of every triangle: never behind a
// sample (it is the exact minimum of the piecewise linear depth there), and
// within one sampling step of the nearest sample.
TEST(MeshScreenPoints, FrontmostPointIsTheMeshMinimumDepthWithinReach) {
    const TestFrame f(test_scene());
    const Camera& cam = f.cam;
    const Scene& scene = f.scene;
    const FrameContext& c = f.c;
    const MeshScreenPoints points(c);
    const double reach = 4 * 2.0 / cam.height(), r2 = reach * reach;
    constexpr int kSteps = 40;  // barycentric samples per triangle side
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> x(-1.2, 1.2), y(-0.8, 0.8);
    int compared = 0;
    for (int k = 0; k < 300; ++k) {
        const ScreenPoint sp{x(rng), y(rng)};
        for (uint32_t id = 1; id <= c.nfaces; ++id) {
            const FaceMesh& mesh = scene.faces[id - 1].mesh;
            double brute = HUGE_VAL, slack = 0;
            for (size_t t = 0; t + 2 < mesh.triangles.size(); t += 3) {
                Vec2 s[3];
                double z[3];
                for (int q = 0; q < 3; ++q) project(cam, mesh.xyz[mesh.triangles[t + q]], s[q], z[q]);
                for (int a = 0; a <= kSteps; ++a)
                    for (int b = 0; a + b <= kSteps; ++b) {
                        const double l0 = double(a) / kSteps, l1 = double(b) / kSteps, l2 = 1 - l0 - l1;
                        const double sx = l0 * s[0].x + l1 * s[1].x + l2 * s[2].x - sp.sx;
                        const double sy = l0 * s[0].y + l1 * s[1].y + l2 * s[2].y - sp.sy;
                        if (sx * sx + sy * sy > r2) continue;
                        brute = std::min(brute, l0 * z[0] + l1 * z[1] + l2 * z[2]);
                        slack = std::max(slack, (std::max({z[0], z[1], z[2]}) - std::min({z[0], z[1], z[2]})) / kSteps);
                    }
            }
            Vec2 uv;
            double depth = 0;
            const bool found = points.frontmost_point(id, sp, r2, uv, depth);
            if (brute == HUGE_VAL) continue;
            ASSERT_TRUE(found) << "face " << id << " at (" << sp.sx << ", " << sp.sy << ")";
            ++compared;
            EXPECT_LE(depth, brute + 1e-12 * std::fabs(brute));
            EXPECT_GE(depth, brute - slack - 1e-12 * std::fabs(brute));
        }
    }
    EXPECT_GT(compared, 100);
}

// starts_in_front: the sheets of a face's mesh that cover a screen point, nearest
// to the eye first, cut at a depth. The sphere octant's mesh doubled by a copy
// moved away from the eye (its u shifted by 10), as a face folded over itself:
// points of the octant are covered twice; the front sheet's (u, v) come first,
// and a cut between the two sheets leaves only the front one.
TEST(MeshScreenPoints, StartsInFrontAreTheCoveringSheetsFrontToBack) {
    Scene folded = test_scene();
    {
        const Camera view(iso_view(folded, kWidth, kHeight));
        FaceMesh& m = folded.faces[0].mesh;
        const Vec3 away = 0.3 * folded.bbox.diagonal() * normalize(view.spec().target - view.spec().eye);
        const uint32_t n = static_cast<uint32_t>(m.xyz.size());
        for (uint32_t q = 0; q < n; ++q) {
            m.xyz.push_back(m.xyz[q] + away);
            m.uv.push_back({m.uv[q].x + 10, m.uv[q].y});
        }
        const size_t nt = m.triangles.size();
        for (size_t q = 0; q < nt; ++q) m.triangles.push_back(m.triangles[q] + n);
    }
    const TestFrame f(std::move(folded));
    const Camera& cam = f.cam;
    const Scene& scene = f.scene;
    const FrameContext& c = f.c;
    const MeshScreenPoints points(c);
    const double reach = 2 * 2.0 / cam.height(), r2 = reach * reach;
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> x(-1.2, 1.2), y(-0.8, 0.8);
    int two_sheets = 0;
    for (int k = 0; k < 1000; ++k) {
        const ScreenPoint sp{x(rng), y(rng)};
        for (uint32_t id = 1; id <= c.nfaces; ++id) {
            const FaceMesh& mesh = scene.faces[id - 1].mesh;
            struct Sheet {
                double z;
                Vec2 uv;
            };
            std::vector<Sheet> sheets;  // brute force: every triangle containing sp
            for (size_t t = 0; t + 2 < mesh.triangles.size(); t += 3) {
                Vec2 s[3];
                double z[3];
                for (int q = 0; q < 3; ++q) project(cam, mesh.xyz[mesh.triangles[t + q]], s[q], z[q]);
                const double det = (s[1].y - s[2].y) * (s[0].x - s[2].x) + (s[2].x - s[1].x) * (s[0].y - s[2].y);
                if (det == 0) continue;
                const double l0 = ((s[1].y - s[2].y) * (sp.sx - s[2].x) + (s[2].x - s[1].x) * (sp.sy - s[2].y)) / det;
                const double l1 = ((s[2].y - s[0].y) * (sp.sx - s[2].x) + (s[0].x - s[2].x) * (sp.sy - s[2].y)) / det;
                const double l2 = 1 - l0 - l1;
                if (l0 < 0 || l1 < 0 || l2 < 0) continue;
                const Vec2 &a = mesh.uv[mesh.triangles[t]], &b = mesh.uv[mesh.triangles[t + 1]],
                           &cc = mesh.uv[mesh.triangles[t + 2]];
                sheets.push_back({l0 * z[0] + l1 * z[1] + l2 * z[2],
                                  {l0 * a.x + l1 * b.x + l2 * cc.x, l0 * a.y + l1 * b.y + l2 * cc.y}});
            }
            if (sheets.size() != 2) continue;  // skip points on a shared triangle edge and outside the face
            std::sort(sheets.begin(), sheets.end(), [](const Sheet& a, const Sheet& b) { return a.z < b.z; });
            ++two_sheets;
            Vec2 got[4];
            ASSERT_EQ(points.starts_in_front(id, sp, r2, HUGE_VAL, got, 4), 2);
            for (int q = 0; q < 2; ++q) {
                EXPECT_NEAR(got[q].x, sheets[q].uv.x, 1e-9);
                EXPECT_NEAR(got[q].y, sheets[q].uv.y, 1e-9);
            }
            ASSERT_EQ(points.starts_in_front(id, sp, r2, 0.5 * (sheets[0].z + sheets[1].z), got, 4), 1);
            EXPECT_NEAR(got[0].x, sheets[0].uv.x, 1e-9);
            EXPECT_NEAR(got[0].y, sheets[0].uv.y, 1e-9);
            // In front of both: no sheet covers sp; the nearest point of the
            // clipped mesh (if any within reach) is offered instead, never more.
            EXPECT_LE(points.starts_in_front(id, sp, r2, sheets[0].z, got, 4), 1);
        }
    }
    EXPECT_GT(two_sheets, 50);
}

// faces_near: every face (not excluded) whose mesh comes within the bound of a
// screen point, nearest first, whatever faces it touches: the same faces and
// distances as nearest_starts asked face by face.
TEST(MeshScreenPoints, FacesNearAreEveryFaceWithinTheBoundNearestFirst) {
    const TestFrame f(test_scene());
    const MeshScreenPoints points(f.c), each(f.c);
    const double pixel = 2.0 / f.cam.height();
    constexpr double kReach = 8;  // pixels
    std::mt19937 rng(13);
    std::uniform_real_distribution<double> x(-1.8, 1.8), y(-1.2, 1.2);
    int found = 0;
    for (int k = 0; k < 400; ++k) {
        const ScreenPoint sp{x(rng), y(rng)};
        const double max_d2 = (kReach * pixel) * (kReach * pixel);
        std::vector<std::pair<double, uint32_t>> expected;
        for (uint32_t id = 1; id <= f.c.nfaces; ++id) {
            Vec2 starts[2];
            double d2 = 0;
            if (each.nearest_starts(id, sp, starts, &d2, max_d2) > 0 && d2 <= max_d2) expected.push_back({d2, id});
        }
        std::sort(expected.begin(), expected.end());
        MeshScreenPoints::FarFace out[4];
        const int n = points.faces_near(sp, nullptr, 0, out, {4, kReach});
        ASSERT_EQ(n, static_cast<int>(expected.size()));
        for (int q = 0; q < n; ++q) {
            EXPECT_EQ(out[q].id, expected[q].second);
            EXPECT_EQ(out[q].d2, expected[q].first);
        }
        found += n;
        // An excluded face is left out, the others stay.
        if (n > 0) {
            const uint32_t skip = out[0].id;
            EXPECT_EQ(points.faces_near(sp, &skip, 1, out, {4, kReach}), n - 1);
            for (int q = 0; q < n - 1; ++q) EXPECT_NE(out[q].id, skip);
        }
    }
    EXPECT_GT(found, 100);
}
