// BRepMesh tessellation of a whole file (see tessellate.h).
#include "importer/faces/tessellate.h"

#include <BRepMesh_IncrementalMesh.hxx>
#include <BRepTools.hxx>
#include <BRep_Tool.hxx>
#include <Poly_Triangulation.hxx>
#include <Standard_Failure.hxx>
#include <TopLoc_Location.hxx>
#include <TopoDS.hxx>

#include <chrono>

#include "importer/occt_shape.h"
#include "core/error.h"

namespace nurbsrt {
namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

}  // namespace

struct Tessellator::Impl {
    occt::OcctModel model;
    std::vector<Affine> placements;
    double read_ms = 0;
};

Tessellator::Tessellator(const std::string& path, const std::vector<Affine>& placements)
    : impl_(std::make_unique<Impl>()) {
    const auto t0 = Clock::now();
    impl_->model = occt::read_model(path, false);
    impl_->read_ms = ms_since(t0);
    impl_->placements = placements.empty() ? std::vector<Affine>{Affine{}} : placements;
}

Tessellator::~Tessellator() = default;
double Tessellator::read_ms() const { return impl_->read_ms; }

Tessellation Tessellator::mesh(double deflection, double angle_rad, bool parallel) {
    if (!(deflection > 0) || !(angle_rad > 0))
        throw Error(ErrorCode::invalid_argument, "tessellate: deflection and angle must be positive");
    Tessellation out;
    const TopoDS_Shape& shape = impl_->model.shape;
    BRepTools::Clean(shape);  // else BRepMesh keeps a finer or coarser earlier mesh
    auto t0 = Clock::now();
    try {
        IMeshTools_Parameters params;
        params.Deflection = deflection;
        params.Angle = angle_rad;
        params.InParallel = parallel ? Standard_True : Standard_False;
        BRepMesh_IncrementalMesh mesher(shape, params);
    } catch (const Standard_Failure& e) {
        throw Error(ErrorCode::occt_failure, std::string("BRepMesh: ") + e.GetMessageString());
    }
    out.mesh_ms = ms_since(t0);

    t0 = Clock::now();
    TriangleMesh one;
    const auto& faces = impl_->model.faces;
    for (int fi = 1; fi <= faces.Extent(); ++fi) {
        const TopoDS_Face& face = TopoDS::Face(faces.FindKey(fi));
        TopLoc_Location loc;
        const Handle(Poly_Triangulation) tri = BRep_Tool::Triangulation(face, loc);
        if (tri.IsNull() || tri->NbTriangles() == 0) {
            ++out.faces_without_triangles;
            continue;
        }
        const gp_Trsf trsf = loc.Transformation();
        const uint32_t base = static_cast<uint32_t>(one.xyz.size());
        const int n = tri->NbNodes();
        for (int i = 1; i <= n; ++i) {
            const gp_Pnt p = tri->Node(i).Transformed(trsf);
            one.xyz.push_back({p.X(), p.Y(), p.Z()});
        }
        for (int t = 1; t <= tri->NbTriangles(); ++t) {
            int a, b, c;
            tri->Triangle(t).Get(a, b, c);
            if (a < 1 || b < 1 || c < 1 || a > n || b > n || c > n) continue;
            one.triangles.insert(one.triangles.end(),
                                 {base + static_cast<uint32_t>(a - 1), base + static_cast<uint32_t>(b - 1),
                                  base + static_cast<uint32_t>(c - 1)});
        }
    }
    out.faces_without_triangles *= static_cast<int>(impl_->placements.size());
    for (const Affine& a : impl_->placements) {
        const uint32_t base = static_cast<uint32_t>(out.mesh.xyz.size());
        for (const Vec3& p : one.xyz) out.mesh.xyz.push_back(a.apply(p));
        for (uint32_t k : one.triangles) out.mesh.triangles.push_back(base + k);
    }
    out.extract_ms = ms_since(t0);
    return out;
}

}  // namespace nurbsrt
