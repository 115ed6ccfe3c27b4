// The assembly tree of an import (Scene::parts): ids, names, colours, placements,
// face counts and boxes, the same for every import of a file and through the
// isolated import's binary scene; joined scenes number their roots on.
#include <gtest/gtest.h>

#include <set>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/io/assembly_tree_json.h"
#include "core/io/scene_io.h"
#include "core/scene/scene_ops.h"
#include "importer/importer.h"
#include "importer/isolated.h"
#include "tests/support/fixtures.h"

namespace T = nurbsrt::test;
using nurbsrt::Part;
using nurbsrt::Scene;

namespace {

// The tree as one comparable text: id, name, parent, faces per line.
std::string outline(const Scene& s) {
    std::string out;
    for (const Part& p : s.parts)
        out += p.id + " " + p.name + " " + std::to_string(p.parent) + " " + std::to_string(p.faces) + "\n";
    return out;
}

}  // namespace

TEST(AssemblyTree, FixtureAssemblyIsARootAndItsTwoPlacements) {
    const Scene s = nurbsrt::import_file(T::assembly());
    ASSERT_EQ(s.parts.size(), 3u) << outline(s);
    EXPECT_EQ(s.parts[0].id, "0");
    EXPECT_EQ(s.parts[0].parent, -1);
    EXPECT_EQ(s.parts[0].faces, s.faces.size());
    for (int k = 0; k < 2; ++k) {
        const Part& p = s.parts[static_cast<size_t>(k + 1)];
        EXPECT_EQ(p.id, "0/" + std::to_string(k));
        EXPECT_EQ(p.name, T::kAssemblyInstanceNames[k]);
        EXPECT_EQ(p.parent, 0);
        EXPECT_EQ(p.faces, static_cast<uint32_t>(T::kAssemblyPartFaces));
        ASSERT_TRUE(p.has_color);
        EXPECT_NEAR(p.color.r, T::kAssemblyColor.r, 1e-6);
        // A pure translation: the identity and the instance's offset.
        EXPECT_DOUBLE_EQ(p.placement[0], 1.0);
        EXPECT_DOUBLE_EQ(p.placement[5], 1.0);
        EXPECT_DOUBLE_EQ(p.placement[10], 1.0);
        EXPECT_NEAR(p.placement[3], T::kAssemblyOffsets[k].x, 1e-9);
        EXPECT_NEAR(p.placement[7], T::kAssemblyOffsets[k].y, 1e-9);
        EXPECT_NEAR(p.placement[11], T::kAssemblyOffsets[k].z, 1e-9);
        // Its box is that of its faces, inside the scene's.
        EXPECT_FALSE(p.bbox.empty());
        EXPECT_GE(p.bbox.lo.x, s.bbox.lo.x - 1e-9);
        EXPECT_LE(p.bbox.hi.x, s.bbox.hi.x + 1e-9);
    }
    // Every body is placed by a leaf, and each leaf's faces are its bodies' faces.
    for (const nurbsrt::Body& b : s.bodies) EXPECT_TRUE(b.part == 1 || b.part == 2) << b.part;
    EXPECT_LT(s.parts[1].bbox.hi.x, s.parts[2].bbox.hi.x);  // left of right
    // The JSON's face_ranges: each face index 1..N (the face AOV's) in the runs
    // of the part that places its body, and in no other part's.
    const nlohmann::json tree = nurbsrt::assembly_tree_json(s);
    ASSERT_EQ(tree.size(), s.parts.size());
    EXPECT_TRUE(tree[0]["face_ranges"].empty()) << "the root places no body itself";
    std::vector<int> owner(s.faces.size() + 1, -1);
    for (size_t k = 0; k < tree.size(); ++k)
        for (const nlohmann::json& run : tree[k]["face_ranges"])
            for (uint64_t f = run[0].get<uint64_t>(); f <= run[1].get<uint64_t>(); ++f) {
                ASSERT_LE(f, s.faces.size());
                EXPECT_EQ(owner[f], -1) << "face " << f << " in two parts";
                owner[f] = static_cast<int>(k);
            }
    for (size_t i = 0; i < s.faces.size(); ++i)
        EXPECT_EQ(owner[i + 1], s.bodies[s.faces[i].body].part) << "face " << i + 1;
}

TEST(AssemblyTree, SameForEveryImportAndThroughTheIsolatedImport) {
    const std::string in = T::assembly();
    const Scene a = nurbsrt::import_file(in), b = nurbsrt::import_file(in);
    EXPECT_EQ(outline(a), outline(b));
    const Scene isolated = nurbsrt::import_isolated(in, {});
    EXPECT_EQ(outline(a), outline(isolated));
    ASSERT_EQ(isolated.parts.size(), a.parts.size());
    for (size_t i = 0; i < a.parts.size(); ++i) {
        EXPECT_EQ(isolated.parts[i].placement, a.parts[i].placement);
        EXPECT_EQ(isolated.parts[i].bbox.lo.x, a.parts[i].bbox.lo.x);
        EXPECT_EQ(isolated.parts[i].has_color, a.parts[i].has_color);
    }
    for (size_t i = 0; i < a.bodies.size(); ++i) EXPECT_EQ(isolated.bodies[i].part, a.bodies[i].part);
}

TEST(AssemblyTree, WithoutAttributesThereIsNone) {
    nurbsrt::ImportOptions o;
    o.read_attributes = false;
    const Scene s = nurbsrt::import_file(T::assembly(), o);
    EXPECT_TRUE(s.parts.empty());
    for (const nurbsrt::Body& b : s.bodies) EXPECT_EQ(b.part, -1);
}

TEST(AssemblyTree, JoinedScenesNumberTheirRootsOn) {
    const Scene one = nurbsrt::import_file(T::assembly());
    Scene joined = one;
    nurbsrt::append_scene(joined, one);
    ASSERT_EQ(joined.parts.size(), 6u);
    EXPECT_EQ(joined.parts[3].id, "1");
    EXPECT_EQ(joined.parts[4].id, "1/0");
    EXPECT_EQ(joined.parts[4].parent, 3);
    EXPECT_EQ(joined.bodies[one.bodies.size()].part, one.bodies[0].part + 3);
    std::set<std::string> ids;
    for (const Part& p : joined.parts) ids.insert(p.id);
    EXPECT_EQ(ids.size(), joined.parts.size());
}

TEST(AssemblyTree, ABinaryTreeWhoseParentComesLaterIsCorrupt) {
    Scene s = nurbsrt::import_file(T::assembly());
    s.parts[1].parent = 2;  // a child before its parent: not depth first, maybe a cycle
    try {
        (void)nurbsrt::deserialize_scene(nurbsrt::serialize_scene(s));
        FAIL() << "accepted";
    } catch (const nurbsrt::Error& e) {
        EXPECT_EQ(e.code(), nurbsrt::ErrorCode::corrupt_scene);
        EXPECT_NE(std::string(e.what()).find("part 1 has parent 2"), std::string::npos) << e.what();
    }
}

// A real assembly of another CAD system: as1-oc-214 (18 placed parts in nested
// sub-assemblies), each face under exactly one leaf.
TEST(AssemblyTree, As1NestedAssemblies) {
    NURBSRT_REQUIRE_SHARED_MODELS();
    const Scene s = nurbsrt::import_file(T::shared_model("step/as1-oc-214.stp"));
    ASSERT_FALSE(s.parts.empty());
    EXPECT_EQ(s.parts[0].faces, s.faces.size());
    size_t leaves = 0, leaf_faces = 0;
    std::set<std::string> ids;
    for (size_t i = 0; i < s.parts.size(); ++i) {
        ids.insert(s.parts[i].id);
        bool has_children = false;
        for (const Part& q : s.parts) has_children |= q.parent == static_cast<int32_t>(i);
        if (!has_children) {
            ++leaves;
            leaf_faces += s.parts[i].faces;
        }
    }
    EXPECT_EQ(ids.size(), s.parts.size());
    EXPECT_EQ(leaves, s.bodies.size());
    EXPECT_EQ(leaf_faces, s.faces.size());
}
