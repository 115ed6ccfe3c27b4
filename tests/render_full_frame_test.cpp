// Zero holes and zero wrong-sheet speckles over the WHOLE frame.
//
// Sampling one pixel in 64 against the exact reference (render_accuracy_test)
// cannot see single-pixel defects: cracks along shared edges, pinholes in thin
// faces, a pixel showing a farther sheet. This test renders each model at 512 x 512
// in two named views, as a user does (import_file -> fit_view -> render), and runs
// the full-frame check (tests/support/full_frame_check.h) over every pixel: every
// background pixel enclosed by hits, every depth spike and the far side of every
// depth step between sheets is re-cast against
// OCCT's IntCurvesFace_ShapeIntersector on the original shape, disputes settled
// with BRepExtrema. None may be a hole (the exact ray hits a face, we show
// background) or a speckle (the exact ray has a nearer hit than ours), except the
// few still open that kKnownRemaining lists with their cause: their counts may
// not rise. And no hit pixel may show a point that is off its ray (every pixel).
//
// Runs on generated fixtures always (filleted boxes whose vertex blends meet edge
// fillets, a fan of thin twisted blades) and on every good model of
// ../shared/models (step/, iges/, duck/; not broken/) when that directory exists.
// One test case per model, so ctest runs them in parallel. The frames are
// rendered with exact shadows, and every shadowed pixel (and a sample of the lit
// ones) re-cast towards the light against the same reference
// (tests/support/shadow_check.h): no acne, no leaks.
#include <BRepGProp.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <GProp_GProps.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>
#include <gtest/gtest.h>

#include <cmath>

#include <chrono>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <string>
#include <vector>

#include "importer/importer.h"
#include "importer/occt_shape.h"
#include "importer/reference/reference_intersector.h"
#include "renderer/camera.h"
#include "renderer/render.h"
#include "tests/support/fixtures.h"
#include "tests/support/occt_distance.h"
#include "tests/support/full_frame_check.h"
#include "tests/support/shadow_check.h"

namespace {

namespace fs = std::filesystem;
namespace T = nurbsrt::test;
using namespace nurbsrt;

// The resolution at which the defects were reported, and the two views: the CLI's
// default (iso, perspective) and an axis view in orthographic projection (rays
// parallel: grazing rays along whole faces, the other classic failure).
constexpr int kSize = 512;
struct View {
    const char* name;
    Projection projection;
};
constexpr View kViews[2] = {{"iso", Projection::perspective}, {"front", Projection::orthographic}};
// The good models' folders under ../shared/models (broken/ holds invalid files).
const char* const kModelDirs[] = {"step", "iges", "duck"};

// Defects the renderer still has (work to do, not a tolerance): per model and
// view, the holes and speckles the check finds today, each with its diagnosed
// cause. The test fails if a count rises above these, and everywhere
// else (every fixture, every other model and view) it demands 0. When a fix
// lands, the entry's counts go down to 0 and the entry is removed.
struct Known {
    const char* model;  // relative to ../shared/models, or a generated fixture's name
    const char* view;
    long holes, speckles;
    const char* cause;
};
// Since the check also re-casts the far side of every depth step (2026-12-05;
// before, only spikes: runs of far-sheet pixels went unseen) it found 482
// wrong-sheet pixels over the models and fixtures; the renderer then fixed 377
// of them (silhouette pixels a sheet behind their neighbour: 14 on a filleted
// box, 26 on the torus, sphere rims; steps filled from diagonal neighbours'
// and map faces, and from the faces beyond the edge of the face in front;
// rescued rim pixels beside another face from their own face's mesh in front:
// trj8, trj3, ship_part5, sunglasses_lens 13 -> 0). The thin faces' tries
// (NearerSheet::thin_tries: a face narrower than a pixel running diagonally,
// whose map pixels cover every second or third pixel centre, tried at the pixels
// within 2 of each) took 105 -> 37: marsCapsule front 68 -> 4, r0901 iso 3 -> 0,
// bearing front 2 -> 1; trying thin faces over their whole mesh on screen
// (thin_face_tries) 37 -> 35 (as1_motor iso 2 -> 0); the rescue trying the
// map's own face from its far starts where that face failed and another was
// hit, 35 -> 31 (ec_turbine front 4 -> 0: a fillet seen edge-on whose map start
// diverged, 33 units in front of the face shown); the check's allowance for a
// grazing contact's spread, 31 -> 18 (below); rescued silhouette pixels trying
// their diagonal neighbours' faces and starts, and silhouette pixels their
// 4-neighbours' faces just in front, 18 -> 13; silhouette pixels alone on
// their face searching its mesh in front, 13 -> 10; silhouette pixels alone on
// their sheet trying starts across their face's rim, 10 -> 8; steps past the
// edge of a face in front trying the faces that join the pixel's own face, 8 -> 7;
// steps past the end of an unsewn face in front trying the faces near on screen,
// 7 -> 3; steps whose face in front Newton fails on trying the faces hit two
// pixels beyond the step, 3 -> 2; steps on one face trying the middle of their
// pair's (u, v), and steps whose face in front Newton fails on trying the faces
// joining it a few pixels off, 2 -> 0 (the notes in the list).
// (bug29715_slow front listed 14 speckles, diagnosed as reachable from a
// neighbour's start where the pixel is no candidate, until the check learnt one
// contact's spread at grazing incidence (kContactSpreadMargin): 13 of them were
// our root and the reference's on the same contact of a coil seen edge-on,
// |n . d| 0.002-0.004 (three measured), both within their solver's tolerance of
// the ray and 2.2e-4 to 1.1e-3 apart along it, inside 2 (1.7e-6 + 1e-7) / |n . d|.)
const std::vector<Known> kKnownRemaining = {
    // (bearing front's, face 20, a blend strip 0.0106 in front of the hit
    // between the face in front (165) and the pixel's, hidden behind 165's
    // edge but for a few pixels 3 rows off, where Newton left 165's box at the
    // step, went when such steps tried the faces joining the face in front hit
    // within 3 pixels beyond the step, from their mesh at the pixel:
    // NearerSheet::faces_joining_failed.)
    // (bug29715_slow front's, a dense coil seen edge-on whose map start
    // diverged and whose 8 neighbours' starts all led to a root on another
    // turn 15 units behind, went when a step whose pair lies on the pixel's
    // face tried the middle of the pair's (u, v), as pits do: NearerSheet::find.)
    // (bearing iso's, a blend 0.0021 in front of the hit whose nearest pixels
    // lay two to the right, beyond a face in front on which Newton failed, went
    // when such steps tried the faces hit two pixels beyond them:
    // NearerSheet::faces_beyond_failed.)
    // (marsCapsule front's four, symmetric: a panel's band split into two
    // unsewn faces, the second 1.5 footprints in front of the face shown, at a
    // step whose face in front, the band's first half, ends there (Newton
    // leaves its box); the faces joining it, which beyond_edges tries, are
    // none (no mesh node shared with any face). They went when such steps
    // tried the faces near on screen: NearerSheet::unlinked_end.)
    // (cylinder_block front's, a drafted wall seen edge-on between a floor and
    // the face in front, with no pixel of its own in the map, went when steps
    // past the edge of a face in front also tried the faces joining the
    // pixel's own face: NearerSheet::find, beyond_edges.)
    // (Each duck front's speckle, a ray clipping the body by its rim whose map
    // start led Newton to the exit root, t 5.6863 against the entry's 5.6712,
    // went when such silhouette pixels tried starts beyond the map's (u, v)
    // from the exit's: NearerSheet::across_own_rim.)
    // (eight_cyl iso's and BUC50025 iso's speckles, silhouette pixels whose
    // map start on a face no neighbour showed led Newton to that face's farther
    // root (20 and 0.38 units behind), and heartValve iso's, went when the
    // nearer-sheet pass searched such a face's mesh in front of the hit, as it
    // did at rescued silhouette pixels only.)
    // (ec_turbine-A iso's speckle, a blade's silhouette pixel filled by the
    // rescue 1.5 units behind the hub face only its diagonal neighbour showed,
    // went when the nearer-sheet pass tried the diagonal neighbours' faces at
    // rescued silhouette pixels too, as at steps; and one of each duck front's
    // two, a rim pixel the rescue filled from a 4-neighbour's start on the
    // farther root of its own face (t 5.505 against 5.415), when it tried the
    // diagonal neighbours' own starts there first; and marsCapsule iso's, a
    // silhouette pixel of a panel 0.0075 behind its neighbour panel whose
    // pixel lay beside it, not across the silhouette, when silhouette pixels
    // tried such 4-neighbours' faces in front; and one of heartValve iso's
    // two, a rim pixel on the farther root of its thin face 31 units behind,
    // when silhouette pixels tried their diagonal neighbours' starts on their
    // own face where those do not continue one sheet turning away.)
    // (bug29715_slow front's speckle, a dense folded face seen edge-on, whose
    // pixel by the fold's silhouette reached the farther of two roots close
    // together (v -160.6; the nearer at -164.4) from every start tried (the
    // 3x3's hits, all 8 neighbours, 16 of the face's mesh sheets in front),
    // went when the nearer-sheet pass solved such silhouette pixels from
    // the (u, v) the sheet's step extrapolates to past the pixel: 21 pixels
    // of that view came nearer; this check had flagged one of them, the other
    // 20 were no candidates of it, neither depth spikes nor enclosed background.)
    // (marsCapsule iso's speckle, a face in front not adjacent by mesh nodes to
    // the 3x3's faces, went when the nearer-sheet pass searched the faces near
    // on screen in front of the hit at pits nothing else fills; at every
    // unfilled pit that had cost the cylinder block's Newton stage about 50 %,
    // after the occluders' edges and concave corners are left out ~1 ms.)
    // (The bolt's iso hole, a silhouette pixel 4e-5 outside a convex loop's
    // polyline where the exact face covers it, went with the trim loops sampled
    // to 3e-6 instead of 1e-5 of their box: ImportOptions::trim_relative_tolerance.)
};

// Shadow disagreements the renderer still has (work to do, not a tolerance),
// counted over the fixed sample of tests/support/shadow_check.h; everywhere else
// the test demands 0, and these counts may not rise. They follow the light map's
// mesh pixel by pixel: 10 % finer map deflection moved them from 45 false shadows
// and 98 leaks over all models to 41 and 89, single entries by up to 6; meshing
// the analytic faces themselves (instead of their B-spline conversions with
// re-fitted pcurves) moved them to 51 and 90, raising 6 entries and lowering 6.
// (Those moves were partly the sample's: an even stride over the shadowed and
// lit pixels shifted every sample when one pixel changed. The sample is now a
// fixed pseudo-random subset per pixel; re-counted with it: 47 and 88.)
// Trim loops sampled to 1e-5 of the (u, v) box instead of 1e-4 (their band, 2x
// the trim uncertainty, was up to 200x the models' edge tolerance: t4mec 0.245
// mm against 0.0012): 47 -> 4 false shadows, 88 -> 51 leaks.
// Causes, diagnosed on
// samples (trj8, cornetta, t4mec, trj5; the other models' disagreements were
// not each traced):
//  - leaks: the light ray crosses an occluder that the light's map does not show
//    in the 3x3 around the point, hidden behind a face the map shows there that
//    the ray passes by (box_sides: faces 51 and 291 behind 53 and 242). Trying
//    the faces adjacent to those (shadow_rays.cpp, where the map shows another
//    face at the point's own pixel) took the leaks over all models 53 -> 28
//    (8 entries gone, box_sides 4 -> 0, ship_part5 5 -> 4). A face of the 3x3
//    whose solve from the map's start found no point at all (diverged, off its
//    box: the start on another part of a strongly curved face) is retried from
//    its mesh where the ray pierces it: 28 -> 22 (ec_turbine iso, t4mec front,
//    ship_part5 4 -> 1, bearing 4 -> 3; from the nearest mesh point also where
//    the ray passes beside the mesh, ship_part5 -> 0 at 12x the retries). A
//    point's own face solved to the point itself, lit at a grazing angle, is
//    retried from the face's mesh sheets in front of it (a hull crossed again
//    nearer the light; never a plane): 22 -> 16 (ship_kcs iso 7 -> 3, both ducks
//    1 -> 0; light rays +0.5 % on the phone, +4 % trj8, +10 % ducks; at any
//    angle and on planes too +28-41 %). Left: thin faces
//    whose crossing lies in their trim band (trj8: faces 398/403/405 reached
//    outside their loops, within the band, which beyond contact blocks only
//    beside another face's crossing), or crossings at grazing incidence where
//    Newton from the map's starts does not converge (the sphere of the analytic
//    test: rays inside its silhouette by under 1 % of its radius); IGES faces
//    whose orientation the entering test cannot trust (bearing: a contact
//    crossing 7e-6 from the point taken for leaving); and on trj8 a crossing just beside
//    a point at an edge, outside the occluder's trim, through its outward side
//    (taken for a convex edge's own face).
//  - false shadows (t4mec, trj5): a crossing of an adjacent face within its trim
//    band and within a light-map pixel of the point, entering, where the exact
//    face is not crossed (taken for a concave edge's contact); the crossings
//    higher above the point's surface than the band is wide are no longer taken
//    (19 -> 17 and 20 -> 18), the rest lay within that height: the band was
//    wide because the trim loops were sampled coarsely (above; t4mec 17 -> 0,
//    trj5 18 -> 2 with the finer loops). Such a contact crossing must now also
//    lie within the face's trim uncertainty of its loops (trim_uv, not the
//    two-face band): trj5 2 -> 1. The one left lay 0.9x the ledge's
//    uncertainty outside its loop (the edges' 3D tolerance seen in (u, v)),
//    0.55x it above the point's wall: a concave edge's crossing that high lies
//    that far inside the exact face, so it may lie only the uncertainty less
//    that height outside the loop (trj5 1 -> 0; leaks unchanged).
//  - box_sides: a grazing-lit hole wall (cosine 0.09) shadowed through the
//    sliver of the hole that the plate's inscribed loop leaves inside the plate
//    (the crossing 4e-4 outside the exact plate); taking such crossings for
//    slivers where they leave a solid on a face adjacent to the point's let the
//    light leak where the point's own face shadows itself (2 models), so not;
//    loops sampled to 3e-6 of their box instead of 1e-5 leave no such sliver
//    there (2 -> 1 false shadows over all models).
//  - marsCapsule front's false shadow was the reference's: its light ray crosses
//    face 15's interior (BRepExtrema: 1e-10 from it) and the intersector reports
//    no hit; shadow_check now settles such disputes (reference misses).
struct KnownShadow {
    const char* model;
    const char* view;
    long false_shadows, leaks;
};
const KnownShadow kKnownShadowDisagreements[] = {
    // Spring: the coil crossed in front of a point on the end face where
    // Newton from the light map's and the pierced mesh's starts diverges (iso);
    // a contact crossing of the end face 0.16 from a coil point, outside its
    // trim by more than the concave-edge allowance (iso); the coil's or the
    // end face's own other part in front of a point whose map starts all lead
    // to the point itself (front: the coil lit at cosine 0.06, the end face
    // at 0.46, where the own-sheet retry, for grazing light only, does not run).
    {"iges/bug22869_Spring.igs", "iso", 0, 2},  {"iges/bug22869_Spring.igs", "front", 0, 2},
    {"step/ec_turbine-A.stp", "front", 0, 1},   {"step/trj8_b1-ec-214.stp", "iso", 0, 4},
    {"step/trj8_b1-ec-214.stp", "front", 0, 1}, {"iges/bearing.iges", "iso", 0, 3},
    {"iges/heartValve.igs", "iso", 0, 1},       {"iges/marsCapsule.igs", "iso", 0, 2},
    {"iges/ship_kcs.igs", "iso", 0, 3},         {"iges/ship_part5.igs", "iso", 0, 1},
};

const KnownShadow* known_shadow(const std::string& rel, const std::string& view) {
    for (const KnownShadow& k : kKnownShadowDisagreements)
        if (rel == k.model && view == k.view) return &k;
    return nullptr;
}

const Known* known_remaining(const std::string& rel, const std::string& view) {
    for (const Known& k : kKnownRemaining)
        if (rel == k.model && view == k.view) return &k;
    return nullptr;
}

struct Case {
    std::string name;     // gtest parameter name
    std::string fixture;  // a generated fixture, or
    std::string path;     // a file of ../shared/models
    std::string rel;      // its path relative to ../shared/models
};

std::vector<Case> cases() {
    std::vector<Case> v;
    for (const char* f : {"filleted_box", "filleted_box_blend", "blade_fan", "box_with_holes", "thin_ring"})
        v.push_back({std::string("fixture_") + f, f, "", ""});
    const std::string root = T::shared_models_dir();
    if (root.empty()) {
        v.push_back({"shared_models_absent", "", "", ""});
        return v;
    }
    for (const char* dir : kModelDirs)
        for (const std::string& p : T::shared_model_files(dir)) {
            const std::string rel = fs::relative(p, root).string();
            v.push_back({T::sanitize_test_name(rel), "", p, rel});
        }
    return v;
}

[[maybe_unused]] void PrintTo(const Case& c, std::ostream* os) { *os << c.name; }

class RenderFullFrame : public testing::TestWithParam<Case> {};

TEST_P(RenderFullFrame, NoHolesNoSpeckles) {
    const Case& c = GetParam();
    if (c.fixture.empty() && c.path.empty()) NURBSRT_REQUIRE_SHARED_MODELS();
    const std::string path = c.fixture.empty() ? c.path : T::fixture_by_name(c.fixture);
    ASSERT_TRUE(fs::exists(path)) << path;

    using Clock = std::chrono::steady_clock;
    const auto t0 = Clock::now();
    const Scene scene = import_file(path);
    const occt::OcctModel model = occt::read_model(path, false);
    ASSERT_EQ(static_cast<int>(scene.faces.size()), model.faces.Extent()) << "face-index contract broken";
    ReferenceIntersector inter(model);
    const PreparedScene prepared = prepare(scene);
    std::cout << "[ full-frame ] " << c.name << ": " << scene.faces.size() << " faces, import+read+prepare "
              << std::fixed << std::setprecision(2) << std::chrono::duration<double>(Clock::now() - t0).count() << " s"
              << std::defaultfloat << "\n";

    for (const View& view : kViews) {
        CameraSpec base;
        base.width = base.height = kSize;
        base.projection = view.projection;
        const Camera camera(fit_view(view.name, scene, base));
        // With the key light's shadows: they change no hit, and their isolated
        // flags are checked below for acne and leaks.
        RenderOptions options;
        options.shadows = true;
        const RenderResult r = render(prepared, camera, options);
        const std::string label = c.name + "/" + view.name;
        const T::FullFrameReport rep = T::full_frame_check(label, scene, model, inter, camera, r.image);
        std::cout << rep.text() << "   render " << std::fixed << std::setprecision(0) << r.stats.total_ms << " ms"
                  << std::defaultfloat << "\n"
                  << std::flush;
        RecordProperty(std::string(view.name) + "_holes", static_cast<int>(rep.holes));
        RecordProperty(std::string(view.name) + "_speckles", static_cast<int>(rep.speckles));
        RecordProperty(std::string(view.name) + "_off_ray", static_cast<int>(rep.off_ray));
        RecordProperty(std::string(view.name) + "_candidates", static_cast<int>(rep.enclosed + rep.spikes + rep.steps));
        RecordProperty(std::string(view.name) + "_unchecked", static_cast<int>(rep.unchecked));
        const Known* known = known_remaining(c.rel.empty() ? c.fixture : c.rel, view.name);
        if (known)
            std::cout << "   known remaining: " << known->holes << " holes, " << known->speckles << " speckles ("
                      << known->cause << ")\n";
        if (rep.unchecked)
            std::cout << "   NOTE: " << rep.unchecked << " shallow depth spikes and steps not checked within "
                      << T::kCheckBudgetSeconds << " s\n";
        EXPECT_LE(rep.holes, known ? known->holes : 0)
            << label << ": background pixels where the exact ray hits a face";
        EXPECT_LE(rep.speckles, known ? known->speckles : 0)
            << label << ": pixels showing a farther sheet than the exact nearest hit";
        EXPECT_EQ(rep.off_ray, 0) << label << ": pixels showing a point of their face that is not on their ray";
        // A blank frame must not pass trivially.
        EXPECT_GT(rep.pixels_hit, 100) << label << ": too few hits to judge";
        const T::ShadowCheckReport shadows = T::shadow_check(scene, model, inter, camera, r.image);
        std::cout << shadows.text(label) << std::flush;
        RecordProperty(std::string(view.name) + "_shadow_checked", static_cast<int>(shadows.checked));
        const KnownShadow* ks = known_shadow(c.rel.empty() ? c.fixture : c.rel, view.name);
        if (ks)
            std::cout << "   known shadow disagreements: " << ks->false_shadows << " false shadows, " << ks->leaks
                      << " leaks\n";
        EXPECT_LE(shadows.false_shadows, ks ? ks->false_shadows : 0)
            << label << ": shadowed (acne?) where the exact light ray is free";
        EXPECT_LE(shadows.leaks, ks ? ks->leaks : 0) << label << ": the key light leaks through an occluder";
    }
}

// The check's allowance for one contact's spread (kContactSpreadMargin) rests on
// |n . d| at the reference point: on a box's top face (normal +z) a ray tilted
// by a from the face's normal meets it at cos(a), whichever side it comes from.
TEST(FullFrameCheck, IncidenceCosineOfAPlane) {
    const TopoDS_Shape box = BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), 10, 10, 10).Shape();
    TopoDS_Face top;
    for (TopExp_Explorer e(box, TopAbs_FACE); e.More(); e.Next()) {
        const TopoDS_Face f = TopoDS::Face(e.Current());
        GProp_GProps props;
        BRepGProp::SurfaceProperties(f, props);
        if (props.CentreOfMass().Z() > 9.999) top = f;
    }
    ASSERT_FALSE(top.IsNull());
    for (const double a : {0.0, 0.5, 1.2, 1.5688}) {  // 1.5688: cos 0.002, the grazing coil's
        const Vec3 down{std::sin(a), 0, -std::cos(a)}, up{-std::sin(a), 0, std::cos(a)};
        EXPECT_NEAR(T::incidence_cosine(top, gp_Pnt(3, 4, 10), down), std::cos(a), 1e-12) << a;
        EXPECT_NEAR(T::incidence_cosine(top, gp_Pnt(3, 4, 10), up), std::cos(a), 1e-12) << a;
    }
    // A point off the face is projected onto its surface first.
    EXPECT_NEAR(T::incidence_cosine(top, gp_Pnt(3, 4, 10.5), Vec3{0, 0, 1}), 1.0, 1e-12);
}

INSTANTIATE_TEST_SUITE_P(Models, RenderFullFrame, testing::ValuesIn(cases()),
                         [](const testing::TestParamInfo<Case>& i) { return i.param.name; });

}  // namespace
