// Meshing for the mesh outputs (STL, glb): see convert_writers.h.
#include <cmath>

#include <BRepBndLib.hxx>
#include <BRepMesh_IncrementalMesh.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <IMeshTools_Parameters.hxx>
#include <Poly_Triangulation.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopLoc_Location.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>

#include "importer/convert/convert_writers.h"
#include "importer/internal.h"
#include "core/error.h"

namespace nurbsrt::occt {

double mesh_for_export(const TopoDS_Shape& shape, ConvertReport& r) {
    const auto t0 = std::chrono::steady_clock::now();
    TopTools_IndexedMapOfShape faces;
    TopExp::MapShapes(shape, TopAbs_FACE, faces);
    // Faces only, as for the import's own mesh: wireframe entities (unbounded
    // lines, construction geometry) must not inflate the box that sets the deflection.
    Bnd_Box box;
    for (int i = 1; i <= faces.Extent(); ++i) BRepBndLib::Add(faces(i), box, Standard_False);
    const double diag = box.IsVoid() ? 0.0 : std::sqrt(box.SquareExtent());
    const ImportOptions defaults;
    IMeshTools_Parameters params;
    params.Deflection = diag > 0 && std::isfinite(diag) ? defaults.mesh_relative_deflection * diag : 1e-3;
    params.Angle = defaults.mesh_angular_deflection;
    params.InParallel = Standard_True;
    try {
        BRepMesh_IncrementalMesh mesher(shape, params);
    } catch (const Standard_Failure& f) {
        throw Error(ErrorCode::occt_failure, "BRepMesh: " + failure_text(f));
    }
    r.triangles = 0;
    r.unmeshed_faces = 0;
    for (int i = 1; i <= faces.Extent(); ++i) {
        TopLoc_Location loc;
        const Handle(Poly_Triangulation) t = BRep_Tool::Triangulation(TopoDS::Face(faces(i)), loc);
        if (t.IsNull() || t->NbTriangles() == 0)
            ++r.unmeshed_faces;
        else
            r.triangles += t->NbTriangles();
    }
    r.mesh_ms = ms_since(t0);
    if (r.triangles == 0)
        throw Error(ErrorCode::occt_failure,
                    "BRepMesh produced no triangles for any of the " + std::to_string(faces.Extent()) + " faces");
    return params.Deflection;
}

}  // namespace nurbsrt::occt
