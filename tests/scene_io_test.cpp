// Scene binary serialization (core/io/scene_io.h): exact round trips and rejection of
// every kind of damaged input with Error(corrupt_scene).
#include "core/io/scene_io.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <set>
#include <string>

#include "core/error.h"

using namespace nurbsrt;
using ::testing::HasSubstr;

namespace {

// ---- field-by-field comparison, doubles bit-exact ----------------------------

bool bits_equal(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }
bool bits_equal(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

#define EXPECT_BITS(a, b) EXPECT_TRUE(bits_equal((a), (b))) << #a << ": " << (a) << " vs " << (b)

void expect_same(Vec2 a, Vec2 b) {
    EXPECT_BITS(a.x, b.x);
    EXPECT_BITS(a.y, b.y);
}
void expect_same(Vec3 a, Vec3 b) {
    EXPECT_BITS(a.x, b.x);
    EXPECT_BITS(a.y, b.y);
    EXPECT_BITS(a.z, b.z);
}
void expect_same(Vec4 a, Vec4 b) {
    EXPECT_BITS(a.x, b.x);
    EXPECT_BITS(a.y, b.y);
    EXPECT_BITS(a.z, b.z);
    EXPECT_BITS(a.w, b.w);
}
void expect_same(Color a, Color b) {
    EXPECT_BITS(a.r, b.r);
    EXPECT_BITS(a.g, b.g);
    EXPECT_BITS(a.b, b.b);
}
void expect_same(double a, double b) { EXPECT_BITS(a, b); }
void expect_same(uint32_t a, uint32_t b) { EXPECT_EQ(a, b); }
void expect_same(const std::string& a, const std::string& b) { EXPECT_EQ(a, b); }

void expect_same(const TrimLoop& a, const TrimLoop& b);
void expect_same(const Face& a, const Face& b);
void expect_same(const Body& a, const Body& b);
void expect_same(const Part& a, const Part& b);

template <class T>
void expect_same(const std::vector<T>& a, const std::vector<T>& b) {
    ASSERT_EQ(a.size(), b.size());
    for (size_t i = 0; i < a.size(); ++i) expect_same(a[i], b[i]);
}

void expect_same(const NurbsSurface& a, const NurbsSurface& b) {
    EXPECT_EQ(a.degree_u, b.degree_u);
    EXPECT_EQ(a.degree_v, b.degree_v);
    EXPECT_EQ(a.num_u, b.num_u);
    EXPECT_EQ(a.num_v, b.num_v);
    EXPECT_EQ(a.rational, b.rational);
    expect_same(a.knots_u, b.knots_u);
    expect_same(a.knots_v, b.knots_v);
    expect_same(a.cp, b.cp);
}

void expect_same(const TrimLoop& a, const TrimLoop& b) {
    EXPECT_EQ(a.outer, b.outer);
    expect_same(a.points, b.points);
}

void expect_same(const Face& a, const Face& b) {
    EXPECT_EQ(a.index, b.index);
    expect_same(a.surface, b.surface);
    EXPECT_BITS(a.u_min, b.u_min);
    EXPECT_BITS(a.u_max, b.u_max);
    EXPECT_BITS(a.v_min, b.v_min);
    EXPECT_BITS(a.v_max, b.v_max);
    EXPECT_EQ(a.reversed, b.reversed);
    expect_same(a.loops, b.loops);
    EXPECT_BITS(a.trim_tolerance_uv, b.trim_tolerance_uv);
    expect_same(a.mesh.uv, b.mesh.uv);
    expect_same(a.mesh.xyz, b.mesh.xyz);
    expect_same(a.mesh.triangles, b.mesh.triangles);
    EXPECT_EQ(a.mesh.fallback_grid, b.mesh.fallback_grid);
    EXPECT_EQ(a.has_color, b.has_color);
    expect_same(a.color, b.color);
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.body, b.body);
}

void expect_same(const Body& a, const Body& b) {
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.has_color, b.has_color);
    expect_same(a.color, b.color);
    EXPECT_EQ(a.part, b.part);
}

void expect_same(const Part& a, const Part& b) {
    EXPECT_EQ(a.id, b.id);
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.parent, b.parent);
    for (size_t i = 0; i < a.placement.size(); ++i) expect_same(a.placement[i], b.placement[i]);
    EXPECT_EQ(a.has_color, b.has_color);
    expect_same(a.color, b.color);
    EXPECT_EQ(a.faces, b.faces);
    expect_same(a.bbox.lo, b.bbox.lo);
    expect_same(a.bbox.hi, b.bbox.hi);
}

void expect_same(const Scene& a, const Scene& b) {
    EXPECT_EQ(a.source_name, b.source_name);
    EXPECT_EQ(a.format, b.format);
    EXPECT_EQ(a.units, b.units);
    expect_same(a.bbox.lo, b.bbox.lo);
    expect_same(a.bbox.hi, b.bbox.hi);
    EXPECT_BITS(a.timings.read_ms, b.timings.read_ms);
    EXPECT_BITS(a.timings.nurbs_convert_ms, b.timings.nurbs_convert_ms);
    EXPECT_BITS(a.timings.mesh_ms, b.timings.mesh_ms);
    expect_same(a.warnings, b.warnings);
    expect_same(a.bodies, b.bodies);
    expect_same(a.parts, b.parts);
    expect_same(a.faces, b.faces);
}

// ---- scenes ------------------------------------------------------------------

NurbsSurface bilinear(double x0, bool rational) {
    NurbsSurface s;
    s.degree_u = 1;
    s.degree_v = 2;
    s.num_u = 2;
    s.num_v = 3;
    s.knots_u = {-0.5, -0.5, 1.0 / 3.0, 1.0 / 3.0};
    s.knots_v = {0, 0, 0, 2.5e-7, 2.5e-7, 2.5e-7};
    s.rational = rational;
    for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 3; ++j) {
            const double w = rational && j == 1 ? std::sqrt(0.5) : 1.0;
            s.cp.push_back({w * (x0 + i), w * j * 0.1, w * -1e-300, w});
        }
    return s;
}

Face make_face(uint32_t index, bool variant) {
    Face f;
    f.index = index;
    f.surface = bilinear(variant ? -7.25 : 1.0 / 7.0, variant);
    f.u_min = -0.5;
    f.u_max = 1.0 / 3.0;
    f.v_min = 0;
    f.v_max = 2.5e-7;
    f.reversed = variant;
    if (variant) {
        f.loops.push_back({{{0, 0}, {0.25, 0}, {0.25, 2e-7}, {-0.0, 1e-7}}, true});
        f.loops.push_back({{{0.1, 1e-8}, {0.2, 1e-8}, {0.15, 5e-8}}, false});
        f.loops.push_back({{}, false});  // degenerate but representable
    }
    f.trim_tolerance_uv = variant ? 1e-9 : 0.0;
    f.mesh.uv = {{-0.5, 0}, {1.0 / 3.0, 0}, {1.0 / 3.0, 2.5e-7}, {-0.5, 2.5e-7}};
    f.mesh.xyz = {{1, 2, 3}, {4, 5, 6}, {7, 8, 9}, {std::nextafter(1.0, 2.0), -0.0, 5e-324}};
    f.mesh.triangles = {0, 1, 2, 0, 2, 3};
    f.mesh.fallback_grid = variant;
    f.has_color = variant;
    f.color = variant ? Color{0.1f, 0.2f, 0.3f} : Color{};
    f.name = variant ? std::string(
                           "Fl\xc3\xa4"
                           "che\0 #2",
                           12)
                     : std::string();
    f.body = variant ? 1 : 0;
    return f;
}

Scene make_full_scene() {
    Scene s;
    s.source_name = "duck.step";
    s.format = "STEP";
    s.units = "inch";
    s.bbox.extend(Vec3{-1.5, 2.0 / 3.0, 1e300});
    s.bbox.extend(Vec3{4, 5, -6});
    s.timings = {12.5, 1.0 / 3.0, std::numeric_limits<double>::denorm_min()};
    s.warnings = {"face 2: mesh fallback to uv grid", "", "healed loop\nwith newline"};
    s.bodies = {{"Body A", true, {1.0f, 0.0f, 0.5f}, 1}, {"", false, {}, 2}};
    s.parts.resize(3);
    s.parts[0].id = "0";
    s.parts[0].name = "assembly";
    s.parts[1].id = "0/0";
    s.parts[1].name = "Gehäuse";
    s.parts[1].parent = 0;
    s.parts[1].has_color = true;
    s.parts[1].color = {0.1f, 0.2f, 0.3f};
    s.parts[1].placement = {0, -1, 0, 12.5, 1, 0, 0, -1.0 / 3.0, 0, 0, 1, 1e-300};
    s.parts[2].id = "0/1";
    s.parts[2].parent = 0;
    s.parts[2].faces = 7;
    s.parts[2].bbox.extend(Vec3{-1, -2, -3});
    s.faces = {make_face(1, false), make_face(2, true), make_face(3, true)};
    return s;
}

// A small scene for the exhaustive truncation / flip loops.
Scene make_small_scene() {
    Scene s;
    s.source_name = "a.step";
    s.format = "STEP";
    s.units = "mm";
    s.warnings = {"w1", "w2"};
    s.bodies = {{"b", true, {0.5f, 0.5f, 0.5f}}};
    s.faces = {make_face(1, true)};
    return s;
}

void expect_corrupt(const std::string& bytes, const std::string& why, const char* substr = nullptr) {
    try {
        (void)deserialize_scene(bytes);
        ADD_FAILURE() << "accepted: " << why;
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::corrupt_scene) << why << ": " << e.what();
        if (substr) {
            EXPECT_THAT(e.what(), HasSubstr(substr)) << why;
        }
    } catch (const std::exception& e) {
        ADD_FAILURE() << why << ": wrong exception type: " << e.what();
    }
}

uint64_t fnv1a64(const char* p, size_t n) {  // independent copy of the format's checksum
    uint64_t h = 0xcbf29ce484222325ull;
    for (size_t i = 0; i < n; ++i) h = (h ^ static_cast<unsigned char>(p[i])) * 0x100000001b3ull;
    return h;
}

// Overwrites the u64 at `offset` (absolute) and recomputes the trailing checksum.
std::string forge_u64(std::string bytes, size_t offset, uint64_t value) {
    std::memcpy(bytes.data() + offset, &value, 8);
    const size_t payload = bytes.size() - 20 - 8;
    const uint64_t h = fnv1a64(bytes.data() + 20, payload);
    std::memcpy(bytes.data() + bytes.size() - 8, &h, 8);
    return bytes;
}

uint64_t read_u64(const std::string& bytes, size_t offset) {
    uint64_t v;
    std::memcpy(&v, bytes.data() + offset, 8);
    return v;
}

}  // namespace

TEST(SceneIo, RoundTripEverything) {
    const Scene a = make_full_scene();
    const std::string bytes = serialize_scene(a);
    const Scene b = deserialize_scene(bytes);
    expect_same(a, b);
    EXPECT_EQ(serialize_scene(b), bytes);  // deterministic
    std::printf("[ figures  ] full test scene: %zu bytes\n", bytes.size());
}

TEST(SceneIo, EmptyScene) {
    const Scene a;
    const std::string bytes = serialize_scene(a);
    EXPECT_EQ(bytes.substr(0, 8), "NRBSCENE");
    const Scene b = deserialize_scene(bytes);
    expect_same(a, b);
    EXPECT_TRUE(b.bbox.empty());
    EXPECT_TRUE(b.faces.empty());
}

TEST(SceneIo, HeaderLayout) {
    const std::string bytes = serialize_scene(make_small_scene());
    uint32_t version;
    std::memcpy(&version, bytes.data() + 8, 4);
    EXPECT_EQ(version, kSceneFormatVersion);
    EXPECT_EQ(read_u64(bytes, 12), bytes.size() - 28);
    EXPECT_EQ(read_u64(bytes, bytes.size() - 8), fnv1a64(bytes.data() + 20, bytes.size() - 28));
}

TEST(SceneIo, EveryTruncationIsCorrupt) {
    const std::string bytes = serialize_scene(make_small_scene());
    for (size_t n = 0; n < bytes.size(); ++n) expect_corrupt(bytes.substr(0, n), "prefix " + std::to_string(n));
    expect_corrupt(bytes + '\0', "one trailing byte");
}

TEST(SceneIo, EverySingleByteFlipIsCorrupt) {
    const std::string bytes = serialize_scene(make_small_scene());
    for (size_t i = 0; i < bytes.size(); ++i)
        for (unsigned mask : {0x01u, 0x80u, 0xffu}) {
            std::string b = bytes;
            b[i] = static_cast<char>(b[i] ^ mask);
            expect_corrupt(b, "flip at " + std::to_string(i) + " mask " + std::to_string(mask));
        }
}

TEST(SceneIo, HugeCountsWithValidChecksum) {
    const Scene s = make_small_scene();
    const std::string bytes = serialize_scene(s);
    // Payload starts at 20: str "a.step" (8+6), "STEP" (8+4), "mm" (8+2), bbox 48, timings 24.
    const size_t source_len_at = 20;
    const size_t warnings_at = 20 + 14 + 12 + 10 + 48 + 24;
    const size_t bodies_at = warnings_at + 8 + (8 + 2) * 2;
    const size_t parts_at =
        bodies_at + 8 + (8 + 1 + 1 + 12 + 4 + 1);  // a body: name "b", has_color, Color, part, closed
    const size_t faces_at = parts_at + 8;          // no parts
    ASSERT_EQ(read_u64(bytes, source_len_at), 6u);
    ASSERT_EQ(read_u64(bytes, warnings_at), 2u);
    ASSERT_EQ(read_u64(bytes, bodies_at), 1u);
    ASSERT_EQ(read_u64(bytes, parts_at), 0u);
    ASSERT_EQ(read_u64(bytes, faces_at), 1u);
    // Counts whose allocation would throw bad_alloc / length_error (or take gigabytes) if the
    // reader trusted them: they must be rejected against the bytes left, as corrupt_scene.
    for (uint64_t huge : {uint64_t{1} << 40, uint64_t{1} << 62, ~uint64_t{0}, uint64_t{1} << 32}) {
        expect_corrupt(forge_u64(bytes, source_len_at, huge), "string length", "exceeds");
        expect_corrupt(forge_u64(bytes, warnings_at, huge), "warnings count", "exceeds");
        expect_corrupt(forge_u64(bytes, bodies_at, huge), "bodies count", "exceeds");
        expect_corrupt(forge_u64(bytes, parts_at, huge), "parts count", "exceeds");
        expect_corrupt(forge_u64(bytes, faces_at, huge), "faces count", "exceeds");
    }
    // Every 8-byte window of the payload overwritten with a huge value and re-checksummed:
    // either rejected as corrupt_scene or (a double field hit) accepted; never another failure.
    int rejected = 0;
    for (size_t off = 20; off + 8 <= bytes.size() - 8; ++off) {
        for (uint64_t huge : {uint64_t{1} << 40, ~uint64_t{0}}) {
            try {
                (void)deserialize_scene(forge_u64(bytes, off, huge));
            } catch (const Error& e) {
                EXPECT_EQ(e.code(), ErrorCode::corrupt_scene) << off;
                ++rejected;
            } catch (const std::exception& e) {
                ADD_FAILURE() << "offset " << off << ": " << e.what();
            }
        }
    }
    EXPECT_GT(rejected, 0);
}

TEST(SceneIo, SanityChecksOnValidChecksum) {
    // The writer does not validate, so an invalid Scene yields a well-formed file with a
    // correct checksum whose content the reader must reject.
    struct Case {
        const char* name;
        void (*mutate)(Face&);
        const char* message;
    };
    const Case cases[] = {
        {"degree 0", [](Face& f) { f.surface.degree_u = 0; }, "degrees"},
        {"negative degree", [](Face& f) { f.surface.degree_v = -3; }, "degrees"},
        {"too few control points", [](Face& f) { f.surface.num_u = 1; }, "fewer than degree + 1"},
        {"knot count", [](Face& f) { f.surface.knots_v.push_back(1.0); }, "knots_v has 7 values, expected"},
        {"decreasing knots", [](Face& f) { f.surface.knots_u[1] = 0.5; }, "non-decreasing"},
        {"NaN knot", [](Face& f) { f.surface.knots_u[0] = std::nan(""); }, "non-decreasing"},
        {"cp count", [](Face& f) { f.surface.cp.pop_back(); }, "expected num_u * num_v"},
        {"cp count vs num",
         [](Face& f) {
             f.surface.num_v = 4;
             f.surface.knots_v.push_back(1);
         },
         "expected num_u * num_v"},
        {"triangle index", [](Face& f) { f.mesh.triangles[4] = 4; }, "triangle index 4 out of range"},
        {"triangle count", [](Face& f) { f.mesh.triangles.pop_back(); }, "multiple of 3"},
        {"uv/xyz mismatch", [](Face& f) { f.mesh.xyz.pop_back(); }, "uv but"},
    };
    for (const Case& c : cases) {
        Scene s = make_small_scene();
        c.mutate(s.faces[0]);
        expect_corrupt(serialize_scene(s), c.name, c.message);
    }
    // Booleans other than 0/1 (bodies[0].has_color right after its name "b").
    const std::string bytes = serialize_scene(make_small_scene());
    const size_t has_color_at = 20 + 14 + 12 + 10 + 48 + 24 + 8 + 20 + 8 + 9;
    ASSERT_EQ(bytes[has_color_at], 1);
    std::string b = bytes;
    b[has_color_at] = 2;
    const uint64_t h = fnv1a64(b.data() + 20, b.size() - 28);
    std::memcpy(b.data() + b.size() - 8, &h, 8);
    expect_corrupt(b, "boolean 2", "invalid boolean");
}

TEST(SceneIo, WrongMagicAndVersion) {
    const std::string bytes = serialize_scene(make_small_scene());
    std::string m = bytes;
    m[0] = 'X';
    expect_corrupt(m, "magic", "magic");
    expect_corrupt(std::string(64, '\0'), "zeros", "magic");
    std::string v = bytes;
    const uint32_t other = kSceneFormatVersion + 41;
    std::memcpy(v.data() + 8, &other, 4);
    expect_corrupt(v, "version", ("version " + std::to_string(other)).c_str());
    expect_corrupt(v, "version", ("version " + std::to_string(kSceneFormatVersion)).c_str());
    expect_corrupt(forge_u64(bytes, 12, read_u64(bytes, 12) + 1), "payload size", "payload");
}

TEST(SceneIo, FileHelpers) {
    const std::string path = ::testing::TempDir() + "nurbsrt_scene_io_test.nrbscene";
    const Scene a = make_full_scene();
    write_scene_file(a, path);
    expect_same(a, read_scene_file(path));
    std::remove(path.c_str());

    const std::string missing = ::testing::TempDir() + "no/such/dir/scene.bin";
    try {
        (void)read_scene_file(missing);
        ADD_FAILURE() << "read of a missing file succeeded";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::io);
        EXPECT_THAT(e.what(), HasSubstr(missing));
        EXPECT_THAT(e.what(), HasSubstr("No such file"));
    }
    try {
        write_scene_file(a, missing);
        ADD_FAILURE() << "write into a missing directory succeeded";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::io);
        EXPECT_THAT(e.what(), HasSubstr(missing));
    }
    // A file that exists but is not a scene: corrupt_scene, not io.
    const std::string junk = ::testing::TempDir() + "nurbsrt_scene_io_junk.bin";
    std::FILE* f = std::fopen(junk.c_str(), "wb");
    ASSERT_NE(f, nullptr);
    std::fputs("ISO-10303-21;\n", f);
    std::fclose(f);
    try {
        (void)read_scene_file(junk);
        ADD_FAILURE() << "junk accepted";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::corrupt_scene);
    }
    std::remove(junk.c_str());
}

TEST(ErrorCodes, NamesAreStableAndDistinct) {
    EXPECT_STREQ(error_code_name(ErrorCode::io), "io");
    EXPECT_STREQ(error_code_name(ErrorCode::corrupt_scene), "corrupt_scene");
    EXPECT_STREQ(error_code_name(ErrorCode::unreadable_file), "unreadable_file");
    EXPECT_STREQ(error_code_name(ErrorCode::internal), "internal");
    std::set<std::string> names;
    for (int c = 0; c <= static_cast<int>(ErrorCode::internal); ++c)
        names.insert(error_code_name(static_cast<ErrorCode>(c)));
    EXPECT_EQ(names.size(), static_cast<size_t>(ErrorCode::internal) + 1);
}
