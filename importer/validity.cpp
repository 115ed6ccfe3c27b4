// check_validity (importer.h): BRepCheck_Analyzer on a file's shape, the
// invalid sub-shapes counted by kind.
#include <chrono>

#include <BRepCheck_Analyzer.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedMapOfShape.hxx>

#include "importer/internal.h"
#include "core/error.h"

namespace nurbsrt {
namespace {

// How many sub-shapes of `type` the analyzer finds invalid.
int invalid_of(const BRepCheck_Analyzer& analyzer, const TopoDS_Shape& shape, TopAbs_ShapeEnum type) {
    TopTools_IndexedMapOfShape map;
    TopExp::MapShapes(shape, type, map);
    int n = 0;
    for (int i = 1; i <= map.Extent(); ++i) n += analyzer.IsValid(map(i)) ? 0 : 1;
    return n;
}

}  // namespace

ShapeValidity check_validity(const std::string& path) {
    const occt::OcctModel model = occt::read_model(path, /*read_attributes=*/false);
    const auto t0 = std::chrono::steady_clock::now();
    ShapeValidity v;
    try {
        const BRepCheck_Analyzer analyzer(model.shape);
        v.valid = analyzer.IsValid() == Standard_True;
        if (!v.valid) {
            v.invalid_solids = invalid_of(analyzer, model.shape, TopAbs_SOLID);
            v.invalid_shells = invalid_of(analyzer, model.shape, TopAbs_SHELL);
            v.invalid_faces = invalid_of(analyzer, model.shape, TopAbs_FACE);
            v.invalid_edges = invalid_of(analyzer, model.shape, TopAbs_EDGE);
        }
    } catch (const Standard_Failure& f) {
        // The checker itself failed on it: not a shape to vouch for.
        v.valid = false;
        v.failure = occt::failure_text(f);
    }
    v.check_ms = occt::ms_since(t0);
    return v;
}

}  // namespace nurbsrt
