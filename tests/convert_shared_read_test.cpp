// The outputs of one shared read (importer/shared_read.h: a job file's child
// imports the file once and writes all its conversions from that read) are
// what lone conversions of the file write, in any order of the outputs:
//  * byte-identical for BREP, STL, glb and VRML (no timestamps in them): no
//    triangulation of the import or of an earlier mesh output leaks into BREP;
//    a mesh output takes over the mesh of the mesh output just before it (same
//    parameters: BRepMesh would make the same one) with its counts and its
//    measured deviation, and meshes anew after anything else;
//  * STEP and IGES (whose headers carry the time of writing): the same fidelity
//    report and warnings, so IGES -> STEP's grouping of named members into
//    assemblies (a change of the document) is its own, not the later outputs';
//  * a second mesh output counts the degenerate triangles it left out again
//    (the sphere's poles), as a lone one does.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "importer/importer.h"
#include "importer/shared_read.h"
#include "tests/support/fixtures.h"

namespace {

std::string bytes_of(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

bool has_timestamp(const std::string& ext) { return ext == ".step" || ext == ".igs"; }

struct Output {
    nurbsrt::ConvertReport report;
    std::string bytes;
};

// Converts `in` to each of `outputs` (extensions; a repeated one gets a
// numbered name), with a SharedRead that first imports the file (as the file
// worker does for renders) when `shared`, else each conversion alone.
std::vector<Output> convert_all(const std::string& in, const std::vector<std::string>& outputs, bool shared,
                                const std::string& tag) {
    std::vector<Output> out;
    std::optional<nurbsrt::SharedRead> read;
    if (shared) {
        read.emplace(in);
        (void)nurbsrt::import_file(in);
    }
    for (size_t i = 0; i < outputs.size(); ++i) {
        const std::string path = nurbsrt::test::fixture_dir() + "/shared-" + tag + "-" + std::to_string(i) + outputs[i];
        Output o;
        o.report = nurbsrt::convert_file(in, path);
        o.bytes = bytes_of(path);
        out.push_back(std::move(o));
    }
    if (read) {
        EXPECT_EQ(read->reads(), 1) << tag;
    }
    return out;
}

void expect_as_alone(const Output& lone, const Output& shared, const std::string& ext, const std::string& what) {
    EXPECT_EQ(shared.report.fidelity, lone.report.fidelity) << what;
    EXPECT_EQ(shared.report.warnings, lone.report.warnings) << what;
    EXPECT_EQ(shared.report.triangles, lone.report.triangles) << what;
    EXPECT_EQ(shared.report.degenerate_triangles, lone.report.degenerate_triangles) << what;
    if (!has_timestamp(ext)) {
        const auto at = std::mismatch(lone.bytes.begin(), lone.bytes.end(), shared.bytes.begin(), shared.bytes.end());
        const size_t i = static_cast<size_t>(at.first - lone.bytes.begin());
        EXPECT_TRUE(shared.bytes == lone.bytes)
            << what << ": the files differ from byte " << i << " of " << lone.bytes.size() << " ("
            << shared.bytes.size() << "): '" << lone.bytes.substr(i, 60) << "' / '" << shared.bytes.substr(i, 60)
            << "'";
    }
}

void check_orders(const std::string& in, const std::vector<std::string>& outputs, const std::string& tag) {
    const std::vector<Output> lone = convert_all(in, outputs, false, tag + "-lone");
    std::vector<std::string> reversed(outputs.rbegin(), outputs.rend());
    const std::vector<Output> forward = convert_all(in, outputs, true, tag + "-fwd");
    const std::vector<Output> backward = convert_all(in, reversed, true, tag + "-bwd");
    for (size_t i = 0; i < outputs.size(); ++i) {
        expect_as_alone(lone[i], forward[i], outputs[i],
                        tag + " " + outputs[i] + " #" + std::to_string(i) + " forward");
        expect_as_alone(lone[i], backward[outputs.size() - 1 - i], outputs[i],
                        tag + " " + outputs[i] + " #" + std::to_string(i) + " backward");
    }
}

TEST(ConvertSharedRead, OutputsAreWhatLoneConversionsWrite) {
    // An IGES file of named members (the assembly through OCCT's XDE IGES
    // writer): its STEP output expands them into an assembly.
    const std::string igs = nurbsrt::test::fixture_dir() + "/shared-assembly.igs";
    nurbsrt::convert_file(nurbsrt::test::assembly(), igs);
    check_orders(igs, {".step", ".brep", ".stl", ".glb", ".wrl", ".igs", ".step"}, "assembly");
}

TEST(ConvertSharedRead, EveryMeshOutputCountsItsDegenerateTriangles) {
    const std::string sphere = nurbsrt::test::sphere();
    const std::vector<Output> lone = convert_all(sphere, {".stl"}, false, "sphere-lone");
    ASSERT_GT(lone[0].report.degenerate_triangles, 0) << "the sphere's poles give BRepMesh degenerate triangles";
    check_orders(sphere, {".stl", ".brep", ".stl", ".glb"}, "sphere");
}

TEST(ConvertSharedRead, MeshOutputsInARowShareOneMesh) {
    const std::string sphere = nurbsrt::test::sphere();
    const std::vector<std::string> outputs = {".stl", ".glb", ".wrl", ".brep", ".stl", ".glb"};
    const std::vector<Output> lone = convert_all(sphere, outputs, false, "row-lone");
    const std::vector<Output> shared = convert_all(sphere, outputs, true, "row-shared");
    const bool expected[] = {false, true, true, false, false, true};
    for (size_t i = 0; i < outputs.size(); ++i) {
        EXPECT_FALSE(lone[i].report.mesh_shared) << outputs[i] << " #" << i;
        EXPECT_EQ(shared[i].report.mesh_shared, expected[i]) << outputs[i] << " #" << i;
        expect_as_alone(lone[i], shared[i], outputs[i], "row " + outputs[i] + " #" + std::to_string(i));
    }
}

}  // namespace
