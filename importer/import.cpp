// import_file: read -> convert every face (surface, box, trim loops) -> mesh -> Scene.
#include <cmath>
#include <filesystem>

#include <BRepBndLib.hxx>
#include <Bnd_Box.hxx>
#include <Standard_Failure.hxx>
#include <TopoDS.hxx>
#include <tbb/parallel_for.h>

#include "importer/internal.h"
#include "renderer/error.h"

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
    scene.warnings = model.warnings;

    const int n = model.faces.Extent();
    std::vector<TopoDS_Face> faces(static_cast<size_t>(n));
    for (int i = 1; i <= n; ++i) faces[static_cast<size_t>(i - 1)] = TopoDS::Face(model.faces.FindKey(i));

    try {
        // NURBS conversion and geometry queries are thread-safe (STACK.md);
        // every result lands in its own slot, so the outcome is deterministic.
        std::vector<FaceWork> work(static_cast<size_t>(n));
        tbb::parallel_for(size_t(0), faces.size(), [&](size_t i) {
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

        std::vector<occt::ConvertedFace> cfs(static_cast<size_t>(n));
        std::vector<occt::UVBox> boxes(static_cast<size_t>(n));
        std::vector<const std::vector<TrimLoop>*> loops(static_cast<size_t>(n));
        for (size_t i = 0; i < work.size(); ++i) {
            cfs[i] = work[i].cf;
            boxes[i] = work[i].box;
            loops[i] = &work[i].trim.loops;
        }
        occt::MeshParams mp;
        mp.deflection = diag > 0 && std::isfinite(diag) ? options.mesh_relative_deflection * diag : 1e-3;
        mp.angle = options.mesh_angular_deflection;
        mp.time_limit_s = options.mesh_time_limit_s;
        mp.face_time_limit_s = std::max(1.0, 0.25 * options.mesh_time_limit_s);
        std::vector<FaceMesh> meshes;
        std::vector<std::string> mesh_warnings;
        occt::mesh_faces(cfs, boxes, loops, face_sizes, mp, meshes, mesh_warnings);
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
                scene.warnings.push_back(label + ": NURBS conversion failed (" + w.error +
                                         "); the face is left empty");
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
        scene.timings.nurbs_convert_ms += occt::ms_since(t_assemble);
    } catch (const Standard_Failure& f) {
        throw Error(ErrorCode::occt_failure, "import: " + occt::failure_text(f));
    }
    return scene;
}

}  // namespace nurbsrt
