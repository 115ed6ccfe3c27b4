// import_file: read -> convert every face (surface, box, trim loops) -> mesh -> Scene.
#include <cmath>
#include <filesystem>
#include <map>

#include <BRepBndLib.hxx>
#include <Bnd_Box.hxx>
#include <Standard_Failure.hxx>
#include <TopoDS.hxx>
#include <tbb/parallel_for.h>

#include "importer/internal.h"
#include "core/error.h"
#include "core/scene/scene_ops.h"

namespace nurbsrt {
namespace {

void check_options(const ImportOptions& o) {
    auto bad = [](const std::string& what) { throw Error(ErrorCode::invalid_argument, what); };
    if (!(o.mesh_relative_deflection > 0 && o.mesh_relative_deflection < 1))
        bad("mesh_relative_deflection must be in (0, 1)");
    if (!(o.mesh_angular_deflection > 0 && o.mesh_angular_deflection < 3.2))
        bad("mesh_angular_deflection must be in (0, pi]");
    if (!(o.mesh_time_limit_s >= 0)) bad("mesh_time_limit_s must be >= 0");
    if (!(o.trim_relative_tolerance > 0 && o.trim_relative_tolerance < 0.1))
        bad("trim_relative_tolerance must be in (0, 0.1)");
}

// Stand-in for a face whose conversion failed: keeps the face numbering
// intact; with an empty mesh it never reaches the preliminary map.
NurbsSurface placeholder_surface(Vec3 c) {
    NurbsSurface s;
    s.degree_u = s.degree_v = 1;
    s.num_u = s.num_v = 2;
    s.knots_u = s.knots_v = {0, 0, 1, 1};
    s.cp.assign(4, Vec4{c.x, c.y, c.z, 1});
    return s;
}

BBox to_bbox(const Bnd_Box& b) {
    BBox out;
    if (b.IsVoid()) return out;
    double x0, y0, z0, x1, y1, z1;
    b.Get(x0, y0, z0, x1, y1, z1);
    out.extend(Vec3{x0, y0, z0});
    out.extend(Vec3{x1, y1, z1});
    return out;
}

struct FaceWork {
    occt::ConvertedFace cf;
    occt::UVBox box;
    occt::TrimResult trim;
    std::string error;
};

// For each face, the first face that is the same face placed elsewhere (the same
// TShape and orientation under another location: a part an assembly uses more
// than once), or itself. Such a face's surface, (u,v) box, trim loops and mesh
// are its first one's moved by the relative placement (instance_work,
// instance_mesh), not converted, sampled and meshed again: a placement moves
// the surface and keeps its parameters.
std::vector<size_t> first_instances(const std::vector<TopoDS_Face>& faces) {
    std::map<std::pair<const TopoDS_TShape*, int>, size_t> first;
    std::vector<size_t> out(faces.size());
    for (size_t i = 0; i < faces.size(); ++i)
        out[i] =
            first.try_emplace({faces[i].TShape().get(), static_cast<int>(faces[i].Orientation())}, i).first->second;
    return out;
}

// The placement of face `to` relative to face `from` (the same TShape).
gp_Trsf relative_placement(const TopoDS_Face& to, const TopoDS_Face& from) {
    return to.Location().Transformation() * from.Location().Transformation().Inverted();
}

// Face `to`'s conversion from that of `from`, its first instance: the same box,
// loops and (u,v) map; the surface moved (Geom_Geometry::Transformed, a copy).
FaceWork instance_work(const FaceWork& from, const gp_Trsf& move) {
    FaceWork w = from;
    if (!from.cf.surface.IsNull())
        w.cf.surface = Handle(Geom_BSplineSurface)::DownCast(from.cf.surface->Transformed(move));
    return w;
}

// Likewise its mesh: the same (u,v), the points moved.
FaceMesh instance_mesh(const FaceMesh& from, const gp_Trsf& move) {
    FaceMesh m = from;
    for (Vec3& p : m.xyz) {
        gp_Pnt q(p.x, p.y, p.z);
        q.Transform(move);
        p = {q.X(), q.Y(), q.Z()};
    }
    return m;
}

}  // namespace

Scene import_file(const std::string& path, const ImportOptions& options) {
    // The three stages run end to end from here to the return, so that they are
    // the whole import (a caller subtracts them from the child process's time).
    using Clock = std::chrono::steady_clock;
    const auto t_read = Clock::now();
    check_options(options);
    occt::OcctModel model = occt::read_model(path, options.read_attributes);
    Scene scene;
    scene.timings.read_ms = occt::ms_since(t_read);
    const auto t_convert = Clock::now();  // the conversion counts the face list below too
    scene.source_name = std::filesystem::path(path).filename().string();
    scene.format = format_name(model.format);
    scene.units = model.units;
    scene.bodies = model.bodies;
    scene.parts = model.parts;
    scene.warnings = model.warnings;

    const int n = model.faces.Extent();
    std::vector<TopoDS_Face> faces(static_cast<size_t>(n));
    for (int i = 1; i <= n; ++i) faces[static_cast<size_t>(i - 1)] = TopoDS::Face(model.faces.FindKey(i));

    try {
        // NURBS conversion and geometry queries are thread-safe (only STEP/IGES
        // reading and writing corrupt OCCT's heap when run concurrently);
        // every result lands in its own slot, so the outcome is deterministic.
        std::vector<FaceWork> work(static_cast<size_t>(n));
        const std::vector<size_t> first = first_instances(faces);
        tbb::parallel_for(size_t(0), faces.size(), [&](size_t i) {
            if (first[i] != i) return;
            FaceWork& w = work[i];
            try {
                w.cf = occt::convert_face(faces[i]);
                w.box = occt::face_uv_box(w.cf);
                w.trim = occt::sample_trim_loops(w.cf, w.box, options.trim_relative_tolerance);
            } catch (const Error& e) {
                w.error = e.what();
                w.cf = {};
            } catch (const Standard_Failure& f) {
                w.error = occt::failure_text(f);
                w.cf = {};
            }
        });
        for (size_t i = 0; i < work.size(); ++i)
            if (first[i] != i) work[i] = instance_work(work[first[i]], relative_placement(faces[i], faces[first[i]]));
        scene.timings.nurbs_convert_ms = occt::ms_since(t_convert);

        // Faces only: wireframe entities (unbounded lines, huge construction
        // squares) must not inflate the box that sets the mesh deflection.
        const auto t_mesh = Clock::now();
        Bnd_Box faces_box;
        std::vector<double> face_sizes(faces.size(), 0.0);
        for (size_t i = 0; i < faces.size(); ++i) {
            Bnd_Box b;
            BRepBndLib::Add(faces[i], b, Standard_False);
            if (!b.IsVoid()) face_sizes[i] = std::sqrt(b.SquareExtent());
            faces_box.Add(b);
        }
        const BBox geometric = to_bbox(faces_box);
        const double diag = geometric.diagonal();

        // First instances only (first_instances); the others take their mesh.
        std::vector<occt::ConvertedFace> cfs;
        std::vector<occt::UVBox> boxes;
        std::vector<const std::vector<TrimLoop>*> loops;
        std::vector<double> first_sizes;
        std::vector<uint32_t> numbers;
        for (size_t i = 0; i < work.size(); ++i) {
            if (first[i] != i) continue;
            cfs.push_back(work[i].cf);
            boxes.push_back(work[i].box);
            loops.push_back(&work[i].trim.loops);
            first_sizes.push_back(face_sizes[i]);
            numbers.push_back(static_cast<uint32_t>(i + 1));
        }
        occt::MeshParams mp;
        mp.deflection = diag > 0 && std::isfinite(diag) ? options.mesh_relative_deflection * diag : 1e-3;
        mp.angle = options.mesh_angular_deflection;
        mp.time_limit_s = options.mesh_time_limit_s;
        mp.face_time_limit_s = std::max(1.0, 0.25 * options.mesh_time_limit_s);
        std::vector<FaceMesh> first_meshes, meshes(work.size());
        std::vector<std::string> mesh_warnings;
        occt::mesh_faces(cfs, boxes, loops, first_sizes, numbers, mp, first_meshes, mesh_warnings);
        for (size_t q = 0; q < numbers.size(); ++q) meshes[numbers[q] - 1] = std::move(first_meshes[q]);
        for (size_t i = 0; i < work.size(); ++i)
            if (first[i] != i)
                meshes[i] = instance_mesh(meshes[first[i]], relative_placement(faces[i], faces[first[i]]));
        scene.timings.mesh_ms = occt::ms_since(t_mesh);
        // Assembling the Scene's patches from the converted faces ends the conversion.
        const auto t_assemble = Clock::now();

        scene.faces.resize(static_cast<size_t>(n));
        for (size_t i = 0; i < work.size(); ++i) {
            Face& f = scene.faces[i];
            FaceWork& w = work[i];
            f.index = static_cast<uint32_t>(i + 1);
            f.reversed = faces[i].Orientation() == TopAbs_REVERSED;
            if (i < model.attributes.size()) {
                const occt::FaceAttributes& a = model.attributes[i];
                f.body = a.body;
                f.has_color = a.has_color;
                f.color = a.color;
                f.name = a.name;
                if (f.name.empty() && a.body < scene.bodies.size()) f.name = scene.bodies[a.body].name;
            }
            const std::string label = "face " + std::to_string(i + 1);
            if (!w.error.empty() || w.cf.surface.IsNull()) {
                scene.warnings.push_back(label + ": NURBS conversion failed (" + w.error + "); the face is left empty");
                f.surface = placeholder_surface(geometric.empty() ? Vec3{} : geometric.center());
                f.u_min = f.v_min = 0;
                f.u_max = f.v_max = 1;
                continue;
            }
            f.surface = occt::to_scene_surface(*w.cf.surface);
            f.u_min = w.box.u0;
            f.u_max = w.box.u1;
            f.v_min = w.box.v0;
            f.v_max = w.box.v1;
            f.loops = std::move(w.trim.loops);
            f.trim_tolerance_uv = w.trim.tolerance_uv;
            for (const std::string& m : w.trim.warnings) scene.warnings.push_back(label + ": " + m);
            f.mesh = std::move(meshes[i]);
            for (const Vec3& p : f.mesh.xyz) scene.bbox.extend(p);
        }
        for (std::string& m : mesh_warnings) scene.warnings.push_back(std::move(m));
        if (scene.bbox.empty()) scene.bbox = geometric;
        summarize_parts(scene);
        scene.timings.nurbs_convert_ms += occt::ms_since(t_assemble);
    } catch (const Standard_Failure& f) {
        throw Error(ErrorCode::occt_failure, "import: " + occt::failure_text(f));
    }
    return scene;
}

}  // namespace nurbsrt
