// Parts chosen by id or name glob (options/part_selection.h) on the generated
// assembly (two instances of one bracket): hidden parts leave the frame and
// its fit, `only` isolates, colours replace the file's, and a pattern that
// names no part is refused naming the request field and listing the parts.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <string>

#include "core/error.h"
#include "importer/importer.h"
#include "options/part_selection.h"
#include "options/render_request.h"
#include "core/scene/scene_ops.h"
#include "renderer/render.h"
#include "tests/support/fixtures.h"

namespace nurbsrt {
namespace {

namespace T = test;

const Scene& assembly() {
    static const Scene scene = import_file(T::assembly());
    return scene;
}

// The faces of the instance named `name`.
std::set<uint32_t> faces_named(const Scene& s, const std::string& name) {
    std::set<uint32_t> out;
    for (const Face& f : s.faces)
        if (s.bodies[f.body].part >= 0 && s.parts[static_cast<size_t>(s.bodies[f.body].part)].name == name)
            out.insert(f.index);
    return out;
}

RenderResult render_with(const RenderRequest& r) {
    RenderOptions options = render_options_for(r, assembly());
    options.antialias = 0;
    const Camera camera(camera_spec_for(r, assembly(), options.hidden_faces));
    return render(assembly(), camera, options);
}

TEST(PartSelection, HideByNameGlobLeavesThePartOut) {
    const Scene& s = assembly();
    const std::set<uint32_t> left = faces_named(s, "bracket_left");
    ASSERT_EQ(left.size(), static_cast<size_t>(T::kAssemblyPartFaces));
    RenderRequest r;
    r.width = 160;
    r.height = 120;
    r.parts.hide = {"*_left"};
    const RenderResult hidden = render_with(r);
    EXPECT_EQ(hidden.stats.hidden_faces, left.size());
    for (uint32_t f : hidden.image.face) EXPECT_EQ(left.count(f), 0u) << "hidden face " << f << " drawn";
    EXPECT_GT(hidden.stats.pixels_hit, 0u);
}

TEST(PartSelection, OnlyByIdIsolatesAndTheViewFramesIt) {
    const Scene& s = assembly();
    const std::set<uint32_t> right = faces_named(s, "bracket_right");
    RenderRequest r;
    r.width = 160;
    r.height = 120;
    r.parts.only = {"0/1"};
    const RenderResult only = render_with(r);
    EXPECT_EQ(only.stats.hidden_faces, s.faces.size() - right.size());
    for (uint32_t f : only.image.face) EXPECT_TRUE(f == 0 || right.count(f)) << "face " << f;
    // Framed alone, the one bracket covers more of the frame than both together.
    r.parts.only.clear();
    const RenderResult both = render_with(r);
    EXPECT_GT(only.stats.pixels_hit, both.stats.pixels_hit);
}

TEST(PartSelection, ColoursReplaceTheFilesAndTheSubtreeFollowsItsNode) {
    RenderRequest r;
    r.width = 96;
    r.height = 72;
    r.parts.color = {{"0", Color{0, 0, 1}}, {"bracket_right", Color{0, 1, 0}}};  // later entries win
    RenderOptions options = render_options_for(r, assembly());
    const std::set<uint32_t> right = faces_named(assembly(), "bracket_right");
    ASSERT_EQ(options.face_colors.size(), assembly().faces.size());
    for (size_t i = 0; i < options.face_colors.size(); ++i) {
        ASSERT_TRUE(options.face_colors[i]);
        EXPECT_EQ(options.face_colors[i]->g, right.count(static_cast<uint32_t>(i + 1)) ? 1.0f : 0.0f);
    }
    const RenderResult res = render_with(r);
    EXPECT_EQ(res.stats.recoloured_faces, assembly().faces.size());
    bool blue = false, green = false;
    for (size_t k = 0; k < res.image.face.size(); ++k) {
        if (!res.image.face[k]) continue;
        const float* px = &res.image.rgba[4 * k];
        blue |= px[2] > 0.1f && px[0] < 0.01f && px[1] < 0.01f;
        green |= px[1] > 0.1f && px[0] < 0.01f && px[2] < 0.01f;
    }
    EXPECT_TRUE(blue && green);
}

// A ghost is blended over what lies behind it (a second frame without the
// ghost faces): over the transparent background its pixels are partly
// transparent, the AOVs still show its faces, the frame's stages sum as before.
TEST(PartSelection, GhostIsSeeThrough) {
    const Scene& s = assembly();
    const std::set<uint32_t> left = faces_named(s, "bracket_left");
    RenderRequest r;
    r.width = 160;
    r.height = 120;
    const RenderResult plain = render_with(r);
    r.parts.ghost = {"bracket_left"};
    const RenderResult ghost = render_with(r);
    EXPECT_EQ(ghost.stats.ghost_faces, left.size());
    EXPECT_GT(ghost.stats.ghost_pixels, 0u);
    EXPECT_GT(ghost.stats.ghost_behind_ms, 0.0);
    EXPECT_EQ(ghost.image.face, plain.image.face);  // the AOVs: the first surface
    uint64_t see_through = 0;
    for (size_t k = 0; k < ghost.image.face.size(); ++k) {
        const bool is_ghost = left.count(ghost.image.face[k]) > 0;
        const float a = ghost.image.rgba[4 * k + 3];
        if (is_ghost)
            see_through += a < 1.0f;
        else
            EXPECT_EQ(a, plain.image.rgba[4 * k + 3]) << k;
    }
    EXPECT_EQ(see_through, ghost.stats.ghost_pixels);  // nothing behind the left bracket: background shows
    const RenderStats& st = ghost.stats;
    EXPECT_NEAR(st.setup_ms + st.preliminary_map_ms + st.newton_ms + st.shadow_map_ms + st.shade_ms + st.antialias_ms +
                    st.edges_ms + st.statistics_ms + st.prepare_ms,
                st.total_ms, 1e-6 * st.total_ms + 1e-9);
}

// parts.move draws a part translated, in the frame: the same faces at the
// same depths as a scene whose part was moved in its geometry and prepared
// again, over the whole frame; the view frames the moved part.
TEST(PartSelection, MoveDrawsThePartWhereTheGeometryMovedWouldBe) {
    const Scene& s = assembly();
    const std::set<uint32_t> left = faces_named(s, "bracket_left");
    const Vec3 t{0, 0, 0.3 * s.bbox.diagonal()};
    RenderRequest r;
    r.width = 160;
    r.height = 120;
    r.parts.move = {{"bracket_left", t}};
    RenderOptions options = render_options_for(r, s);
    ASSERT_EQ(options.face_offsets.size(), s.faces.size());
    Scene moved = s;
    for (Face& f : moved.faces) {
        if (!left.count(f.index)) continue;
        for (Vec4& p : f.surface.cp) p = Affine::translation(t).apply_h(p);
        for (Vec3& p : f.mesh.xyz) p = p + t;
    }
    moved.bbox = BBox{};
    for (const Face& f : moved.faces)
        for (const Vec3& p : f.mesh.xyz) moved.bbox.extend(p);
    RenderRequest plain_request = r;
    plain_request.parts.move.clear();
    RenderOptions plain = render_options_for(plain_request, moved);
    options.antialias = plain.antialias = 0;
    const Camera camera(camera_spec_for(plain_request, moved));
    EXPECT_NEAR(length(camera.spec().eye - camera_spec_for(r, s, {}, options.face_offsets).eye), 0,
                1e-9 * moved.bbox.diagonal());
    const RenderResult a = render(s, camera, options), b = render(moved, camera, plain);
    EXPECT_EQ(a.stats.moved_faces, left.size());
    size_t same = 0, shown_left = 0;
    for (size_t k = 0; k < a.image.face.size(); ++k) {
        same += a.image.face[k] == b.image.face[k];
        shown_left += left.count(a.image.face[k]);
        if (a.image.face[k] && a.image.face[k] == b.image.face[k]) {
            EXPECT_NEAR(a.image.z[k], b.image.z[k], 1e-6 * moved.bbox.diagonal()) << k;
        }
    }
    EXPECT_GE(double(same), 0.9999 * double(a.image.face.size()));
    EXPECT_GT(shown_left, 100u);
    // Bad moves are refused naming the field.
    EXPECT_THROW(parse_part_move("bracket_left=1,2", "--part-move"), Error);
    EXPECT_THROW(parse_part_move("=1,2,3", "--part-move"), Error);
    EXPECT_THROW(parse_render_options(R"({"parts": {"move": {"bracket_left": [1, "a", 3]}}})"), Error);
    EXPECT_EQ(parse_part_move("a=b=1,2,3", "x").first, "a=b");
}

TEST(PartSelection, PatternMatchingNothingNamesTheFieldAndListsParts) {
    RenderRequest r;
    r.parts.hide = {"bracket_left", "gear*"};
    try {
        render_options_for(r, assembly());
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::invalid_argument);
        const std::string m = e.what();
        EXPECT_NE(m.find("parts.hide[1] 'gear*' matches no part"), std::string::npos) << m;
        EXPECT_NE(m.find("0/0 bracket_left"), std::string::npos) << m;
    }
    EXPECT_THROW(check_part_pattern("", "x"), Error);
    EXPECT_THROW(check_part_pattern(std::string(257, 'a'), "x"), Error);
    EXPECT_THROW(check_part_pattern("a\nb", "x"), Error);
}

TEST(PartSelection, JsonFormsAndRefusals) {
    const RenderRequest r = parse_render_options(
        R"({"parts": {"hide": ["a*"], "only": ["0/1"], "color": {"b?": "1,0,0", "c": [0, 1, 0]}}})");
    EXPECT_EQ(r.parts.hide, std::vector<std::string>{"a*"});
    EXPECT_EQ(r.parts.only, std::vector<std::string>{"0/1"});
    ASSERT_EQ(r.parts.color.size(), 2u);
    const RenderRequest q = parse_render_options(R"({"parts": "{\"hide\": [\"a*\"]}"})");  // a query parameter's text
    EXPECT_EQ(q.parts.hide, std::vector<std::string>{"a*"});
    for (const char* bad :
         {R"({"parts": {"spin": ["a"]}})", R"({"parts": {"hide": "a"}})", R"({"parts": {"hide": [1]}})",
          R"({"parts": {"color": {"a": "2,0,0"}}})", R"({"parts": []})", R"({"parts": {"only": [""]}})"}) {
        try {
            parse_render_options(bad);
            ADD_FAILURE() << bad << ": accepted";
        } catch (const Error& e) {
            EXPECT_EQ(e.code(), ErrorCode::invalid_argument) << bad;
            EXPECT_NE(std::string(e.what()).find("parts"), std::string::npos) << bad << ": " << e.what();
        }
    }
}

}  // namespace
}  // namespace nurbsrt
