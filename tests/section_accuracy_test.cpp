// Section planes against an independent reference: OCCT's Boolean cut.
//
// For real CAD models (mechanical solids, an assembly, free-form parts), two
// views (iso in perspective, front orthographic) and a plane through the
// bounding-box centre on each axis (its normal towards the eye, so the cut and
// its caps face the camera), every pixel of a whole frame is compared with the
// same contract pixel ray cast by IntCurvesFace_ShapeIntersector
// (importer/reference) at the shape OCCT makes of the cut: BRepAlgoAPI_Cut of the
// model with BRepPrimAPI_MakeHalfSpace. The Boolean's history tells which faces
// of the result come from which face of the model; the others are its caps.
//
// Per pixel: hit or miss; where both hit, cap or face (and which face: ours or
// another at the same depth, for coincident faces), and the hit distance. Pixels
// within one pixel of an edge in either image (a neighbour shows something else,
// or the reference's depth jumps) are the edge band, reported apart: at an edge
// the pixel centre may fall on either side within the model's tolerances.
// Criteria on the rest, as the accuracy suite's: hit/miss agreement >= 99.9 %;
// depth within 1e-6 of the diagonal on >= 99.9 % of the pixels both hit; cap or
// face, and the face (or the body of a cap), agree on >= 99.9 %.
#include <gtest/gtest.h>

#include <BRepAlgoAPI_Cut.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakeSolid.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <BRepPrimAPI_MakeHalfSpace.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopTools_ListOfShape.hxx>
#include <gp_Pln.hxx>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "importer/importer.h"
#include "importer/occt_shape.h"
#include "importer/reference/reference_intersector.h"
#include "renderer/camera.h"
#include "renderer/prepared_scene.h"
#include "renderer/render.h"
#include "tests/support/fixtures.h"

namespace nurbsrt {
namespace {

constexpr int kWidth = 160, kHeight = 120;
constexpr double kRequiredAgreement = 0.999;
constexpr double kDepthTolerance = 1e-6;  // of the diagonal
// A neighbour's reference depth this much (of the diagonal) away marks an edge
// (a step between two sheets of one face, which labels do not show).
constexpr double kDepthStep = 0.02;
// Pixel labels: background 0, face i (1..N), the cap of body b -(1 + b).
int cap_label(int body) { return -(1 + body); }

struct CutReference {
    std::unique_ptr<ReferenceIntersector> inter;
    std::vector<int> origin;  // per face of the cut (1-based): the model's face it comes from, or a cap_label
};

// The model cut by the half-space on the normal's side of `plane`, and the
// origin of each of its faces from the Boolean's history. Every solid is cut
// alone (the parts of an assembly may interfere, which a Boolean's argument must
// not), a closed shell as the solid it bounds (the renderer caps it too), and
// every other face alone: open shells have no inside, their cut makes no cap.
CutReference cut_reference(const occt::OcctModel& model, const SectionPlane& plane, double diag) {
    const gp_Pnt p(plane.point.x, plane.point.y, plane.point.z);
    const gp_Dir n(plane.normal.x, plane.normal.y, plane.normal.z);
    const TopoDS_Face face = BRepBuilderAPI_MakeFace(gp_Pln(p, n)).Face();
    const gp_Pnt removed_side(p.X() + diag * n.X(), p.Y() + diag * n.Y(), p.Z() + diag * n.Z());
    const TopoDS_Solid half = BRepPrimAPI_MakeHalfSpace(face, removed_side).Solid();
    BRep_Builder builder;
    TopoDS_Compound result;
    builder.MakeCompound(result);
    // Result face -> model face, or the cap label of the body it closes: every
    // face of a piece's cut is first taken for a cap of the piece's body (bodies
    // are numbered as the importer numbers them: solids, then shells outside
    // solids), then the history names those that come from the model's faces.
    std::vector<std::pair<TopoDS_Shape, int>> origin_of;
    int body = 0;
    auto cut_one = [&](const TopoDS_Shape& piece) {
        BRepAlgoAPI_Cut cut(piece, half);
        ASSERT_TRUE(cut.IsDone());
        builder.Add(result, cut.Shape());
        for (TopExp_Explorer ex(cut.Shape(), TopAbs_FACE); ex.More(); ex.Next())
            origin_of.emplace_back(ex.Current(), cap_label(body));
        for (TopExp_Explorer ex(piece, TopAbs_FACE); ex.More(); ex.Next()) {
            const int i = model.faces.FindIndex(ex.Current());
            origin_of.emplace_back(ex.Current(), i);
            for (const TopoDS_Shape& m : cut.Modified(ex.Current())) origin_of.emplace_back(m, i);
        }
    };
    for (TopExp_Explorer ex(model.shape, TopAbs_SOLID); ex.More(); ex.Next(), ++body) cut_one(ex.Current());
    for (TopExp_Explorer ex(model.shape, TopAbs_SHELL, TopAbs_SOLID); ex.More(); ex.Next(), ++body) {
        if (BRep_Tool::IsClosed(ex.Current())) {
            cut_one(BRepBuilderAPI_MakeSolid(TopoDS::Shell(ex.Current())).Solid());
            continue;
        }
        for (TopExp_Explorer f(ex.Current(), TopAbs_FACE); f.More(); f.Next()) cut_one(f.Current());
    }
    for (TopExp_Explorer ex(model.shape, TopAbs_FACE, TopAbs_SHELL); ex.More(); ex.Next()) cut_one(ex.Current());
    occt::OcctModel cut_model;
    cut_model.shape = result;
    TopExp::MapShapes(result, TopAbs_FACE, cut_model.faces);
    CutReference ref;
    ref.origin.assign(static_cast<size_t>(cut_model.faces.Extent()) + 1, 0);
    for (const auto& [f, i] : origin_of) {
        const int k = cut_model.faces.FindIndex(f);
        if (k > 0 && i != 0) ref.origin[static_cast<size_t>(k)] = i;
    }
    ref.inter = std::make_unique<ReferenceIntersector>(cut_model);
    return ref;
}

struct Tally {
    int pixels = 0, edge_band = 0, compared = 0, hit_agree = 0, both_hit = 0, depth_ok = 0, label_ok = 0, caps = 0;
    double max_dt = 0;
};

struct Case {
    const char* path;  // under ../shared/models
};

class SectionAccuracy : public testing::TestWithParam<Case> {};

TEST_P(SectionAccuracy, CapsAndCutEdgesMatchTheBooleanCut) {
    NURBSRT_REQUIRE_SHARED_MODELS();
    const std::string path = test::shared_model(GetParam().path);
    const Scene scene = import_file(path);
    const occt::OcctModel model = occt::read_model(path, false);
    ASSERT_EQ(static_cast<int>(scene.faces.size()), model.faces.Extent()) << "face-index contract broken";
    const PreparedScene prepared = prepare(scene);
    const double diag = scene.bbox.diagonal();
    const Vec3 centre = 0.5 * (scene.bbox.lo + scene.bbox.hi);
    const struct {
        const char* name;
        Projection projection;
    } views[] = {{"iso", Projection::perspective}, {"front", Projection::orthographic}};
    for (const auto& view : views) {
        CameraSpec base;
        base.width = kWidth;
        base.height = kHeight;
        base.projection = view.projection;
        const Camera camera(named_view(view.name, scene.bbox, base));
        for (int axis = 0; axis < 3; ++axis) {
            SectionPlane plane;
            plane.point = centre;
            double n[3] = {0, 0, 0};
            n[axis] = 1;
            plane.normal = {n[0], n[1], n[2]};
            // Towards the eye: the removed half faces the camera, the cut shows.
            if (dot(plane.normal, camera.spec().eye - centre) < 0) plane.normal = -plane.normal;
            // A view along the axis shows the cap face-on; one across it, edge-on:
            // both are checked, the latter shows the cut's silhouette.
            RenderOptions options;
            options.sections.planes = {plane};
            const RenderResult ours = render(prepared, camera, options);
            CutReference ref = cut_reference(model, plane, diag);
            const double t_max = 10 * (length(camera.spec().eye - centre) + diag);

            std::vector<int> ref_label(static_cast<size_t>(kWidth) * kHeight), our_label(ref_label.size());
            std::vector<double> ref_t(ref_label.size());
            for (int j = 0; j < kHeight; ++j)
                for (int i = 0; i < kWidth; ++i) {
                    const size_t k = static_cast<size_t>(j) * kWidth + i;
                    const ReferenceHit h = ref.inter->cast(camera.pixel_ray(i, j), t_max);
                    ref_label[k] = h.hit ? ref.origin[static_cast<size_t>(h.face)] : 0;
                    ref_t[k] = h.t;
                    const uint32_t f = ours.image.face[k];
                    our_label[k] = f >= kCapFace ? cap_label(static_cast<int>(f - kCapFace)) : static_cast<int>(f);
                }
            Tally t;
            for (int j = 0; j < kHeight; ++j)
                for (int i = 0; i < kWidth; ++i) {
                    const size_t k = static_cast<size_t>(j) * kWidth + i;
                    ++t.pixels;
                    bool edge = false;
                    for (int dj = -1; dj <= 1 && !edge; ++dj)
                        for (int di = -1; di <= 1 && !edge; ++di) {
                            const int a = i + di, b = j + dj;
                            if (a < 0 || b < 0 || a >= kWidth || b >= kHeight) continue;
                            const size_t q = static_cast<size_t>(b) * kWidth + a;
                            edge = our_label[q] != our_label[k] || ref_label[q] != ref_label[k] ||
                                   (ref_label[k] && ref_label[q] && std::fabs(ref_t[q] - ref_t[k]) > kDepthStep * diag);
                        }
                    if (edge) {
                        ++t.edge_band;
                        continue;
                    }
                    ++t.compared;
                    const bool ref_hit = ref_label[k] != 0, our_hit = our_label[k] != 0;
                    t.hit_agree += ref_hit == our_hit;
                    if (!ref_hit || !our_hit) continue;
                    ++t.both_hit;
                    t.caps += ref_label[k] < 0;
                    const double dt = std::fabs(double(ours.image.z[k]) - ref_t[k]) / diag;
                    t.max_dt = std::max(t.max_dt, dt);
                    t.depth_ok += dt <= kDepthTolerance;
                    t.label_ok +=
                        ref_label[k] == our_label[k] || (ref_label[k] > 0 && our_label[k] > 0 && dt <= kDepthTolerance);
                }
            char line[320];
            std::snprintf(line, sizeof line,
                          "[ section  ] %s %s axis %c: %d px, edge band %d, compared %d: hit/miss %.3f %%, both hit "
                          "%d (caps %d, ours %llu): depth %.3f %% (max |dt|/diag %.2e), cap/face %.3f %%",
                          GetParam().path, view.name, "xyz"[axis], t.pixels, t.edge_band, t.compared,
                          100.0 * t.hit_agree / std::max(t.compared, 1), t.both_hit, t.caps,
                          static_cast<unsigned long long>(ours.stats.cap_pixels),
                          100.0 * t.depth_ok / std::max(t.both_hit, 1), t.max_dt,
                          100.0 * t.label_ok / std::max(t.both_hit, 1));
            std::printf("%s\n", line);
            EXPECT_GE(t.hit_agree, kRequiredAgreement * t.compared) << line;
            EXPECT_GE(t.depth_ok, kRequiredAgreement * t.both_hit) << line;
            EXPECT_GE(t.label_ok, kRequiredAgreement * t.both_hit) << line;
        }
    }
}

// Mechanical solids (STEP and IGES), an assembly of solids, free-form parts.
INSTANTIATE_TEST_SUITE_P(Models, SectionAccuracy,
                         testing::Values(Case{"step/screw.step"}, Case{"step/as1-oc-214.stp"},
                                         Case{"step/featuretype.STEP"}, Case{"step/linkrods.step"},
                                         Case{"step/bug27693_cornetta-step.stp"},
                                         Case{"step/bug3883_xr2-ct-214_bolt.stp"}),
                         [](const testing::TestParamInfo<Case>& info) {
                             return test::sanitize_test_name(info.param.path);
                         });

}  // namespace
}  // namespace nurbsrt
