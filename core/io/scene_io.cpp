// Binary Scene serialization; format in scene_io.h.
//
// Payload layout (every count/length is u64, bool is one byte 0/1, Color is 3 f32):
//   str source_name, str format, str units
//   bbox: 6 f64 (lo.xyz, hi.xyz)
//   timings: 3 f64 (read, nurbs_convert, mesh)
//   warnings: count, str...
//   bodies: count, { str name, bool has_color, Color, i32 part, bool closed }...
//   parts: count, { str id, str name, i32 parent, 12 f64 placement, bool has_color, Color,
//                   u32 faces, bbox: 6 f64 }...
//   faces: count, {
//     u32 index,
//     surface: i32 degree_u, degree_v, num_u, num_v, bool rational,
//              knots_u: count, f64...; knots_v: count, f64...; cp: count, 4 f64...
//     f64 u_min, u_max, v_min, v_max, bool reversed,
//     loops: count, { bool outer, points: count, 2 f64... }...
//     f64 trim_tolerance_uv,
//     mesh: uv: count, 2 f64...; xyz: count, 3 f64...; triangles: count, u32...; bool fallback_grid
//     bool has_color, Color, str name, u32 body }...
#include "core/io/scene_io.h"

#include <bit>
#include <cmath>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <initializer_list>

#include "core/error.h"

namespace nurbsrt {

static_assert(std::endian::native == std::endian::little, "scene format assumes a little-endian host");
static_assert(sizeof(double) == 8 && sizeof(float) == 4);

uint64_t scene_checksum(const char* payload, size_t n) {
    uint64_t h = 14695981039346656037ull;  // FNV-1a 64 offset basis and prime
    for (size_t i = 0; i < n; ++i) {
        h ^= static_cast<unsigned char>(payload[i]);
        h *= 1099511628211ull;
    }
    return h;
}

namespace {

constexpr char kMagic[8] = {'N', 'R', 'B', 'S', 'C', 'E', 'N', 'E'};
constexpr size_t kHeaderSize = 8 + 4 + 8;
constexpr size_t kTrailerSize = 8;

// ---- writer ------------------------------------------------------------------

class Writer {
public:
    std::string out;

    template <class T>
    void raw(const T& v) {
        char b[sizeof(T)];
        std::memcpy(b, &v, sizeof(T));
        out.append(b, sizeof(T));
    }
    void u8(bool v) { out.push_back(v ? 1 : 0); }
    void u32(uint32_t v) { raw(v); }
    void i32(int32_t v) { raw(v); }
    void u64(uint64_t v) { raw(v); }
    void f64(double v) { raw(v); }
    // Runs of one type, in the order the format lists them.
    void i32s(std::initializer_list<int32_t> vs) {
        for (const int32_t v : vs) i32(v);
    }
    void f64s(std::initializer_list<double> vs) {
        for (const double v : vs) f64(v);
    }
    void str(const std::string& s) {
        u64(s.size());
        out.append(s);
    }
    void vec2(Vec2 v) { f64s({v.x, v.y}); }
    void vec3(Vec3 v) { f64s({v.x, v.y, v.z}); }
    void vec4(Vec4 v) { f64s({v.x, v.y, v.z, v.w}); }
    void color(Color c) {
        raw(c.r);
        raw(c.g);
        raw(c.b);
    }
    void doubles(const std::vector<double>& v) {
        u64(v.size());
        for (double d : v) f64(d);
    }
};

void write_surface(Writer& w, const NurbsSurface& s) {
    w.i32s({s.degree_u, s.degree_v, s.num_u, s.num_v});
    w.u8(s.rational);
    w.doubles(s.knots_u);
    w.doubles(s.knots_v);
    w.u64(s.cp.size());
    for (const Vec4& p : s.cp) w.vec4(p);
}

void write_face(Writer& w, const Face& f) {
    w.u32(f.index);
    write_surface(w, f.surface);
    w.f64s({f.u_min, f.u_max, f.v_min, f.v_max});
    w.u8(f.reversed);
    w.u64(f.loops.size());
    for (const TrimLoop& l : f.loops) {
        w.u8(l.outer);
        w.u64(l.points.size());
        for (Vec2 p : l.points) w.vec2(p);
    }
    w.f64(f.trim_tolerance_uv);
    w.u64(f.mesh.uv.size());
    for (Vec2 p : f.mesh.uv) w.vec2(p);
    w.u64(f.mesh.xyz.size());
    for (Vec3 p : f.mesh.xyz) w.vec3(p);
    w.u64(f.mesh.triangles.size());
    for (uint32_t t : f.mesh.triangles) w.u32(t);
    w.u8(f.mesh.fallback_grid);
    w.u8(f.has_color);
    w.color(f.color);
    w.str(f.name);
    w.u32(f.body);
}

// ---- reader ------------------------------------------------------------------

[[noreturn]] void corrupt(const std::string& what) { throw Error(ErrorCode::corrupt_scene, "corrupt scene: " + what); }

// Bounds-checked cursor over the payload. Every read checks the remaining bytes;
// count() checks that count * min_element_size bytes remain before anything is allocated.
class Reader {
public:
    Reader(const char* p, size_t n) : p_(p), end_(p + n), begin_(p) {}

    size_t remaining() const { return static_cast<size_t>(end_ - p_); }
    size_t offset() const { return static_cast<size_t>(p_ - begin_); }

    template <class T>
    T raw(const char* what) {
        if (remaining() < sizeof(T)) {
            corrupt(std::string("truncated payload reading ") + what + " at payload offset " +
                    std::to_string(offset()));
        }
        T v;
        std::memcpy(&v, p_, sizeof(T));
        p_ += sizeof(T);
        return v;
    }
    bool boolean(const char* what) {
        const auto b = raw<uint8_t>(what);
        if (b > 1) {
            corrupt(std::string("invalid boolean ") + std::to_string(b) + " for " + what + " at payload offset " +
                    std::to_string(offset() - 1));
        }
        return b != 0;
    }
    uint32_t u32(const char* what) { return raw<uint32_t>(what); }
    int32_t i32(const char* what) { return raw<int32_t>(what); }
    double f64(const char* what) { return raw<double>(what); }
    float f32(const char* what) { return raw<float>(what); }

    // A count of elements that each take at least min_size bytes.
    size_t count(const char* what, size_t min_size) {
        const uint64_t c = raw<uint64_t>(what);
        if (c > remaining() / min_size) {
            corrupt(std::string("count ") + std::to_string(c) + " of " + what + " exceeds the " +
                    std::to_string(remaining()) + " bytes left in the payload");
        }
        return static_cast<size_t>(c);
    }
    std::string str(const char* what) {
        const size_t n = count(what, 1);
        std::string s(p_, n);
        p_ += n;
        return s;
    }
    // Braced lists evaluate left to right: the fields in file order.
    Vec2 vec2(const char* w) { return Vec2{f64(w), f64(w)}; }
    Vec3 vec3(const char* w) { return Vec3{f64(w), f64(w), f64(w)}; }
    Vec4 vec4(const char* w) { return Vec4{f64(w), f64(w), f64(w), f64(w)}; }
    Color color(const char* w) { return Color{f32(w), f32(w), f32(w)}; }

private:
    const char* p_;
    const char* end_;
    const char* begin_;
};

std::string face_ctx(size_t i, const char* what) { return "face " + std::to_string(i) + ": " + what; }

void read_knots(Reader& r, std::vector<double>& knots, int n, int p, const char* dir, size_t fi) {
    const size_t c = r.count("knots", 8);
    const size_t expected = static_cast<size_t>(n) + static_cast<size_t>(p) + 1;
    if (c != expected) {
        corrupt(face_ctx(fi, "knots_") + dir + " has " + std::to_string(c) +
                " values, expected num + degree + 1 = " + std::to_string(expected));
    }
    knots.resize(c);
    for (double& k : knots) k = r.f64("knot");
    for (size_t k = 0; k + 1 < c; ++k) {
        if (!(knots[k] <= knots[k + 1])) {  // also rejects NaN
            corrupt(face_ctx(fi, "knots_") + dir + " not non-decreasing at index " + std::to_string(k));
        }
    }
    if (!(knots[p] < knots[n]) || !std::isfinite(knots[p]) || !std::isfinite(knots[n])) {
        corrupt(face_ctx(fi, "knots_") + dir + " has an empty or non-finite parameter range");
    }
}

void read_surface(Reader& r, NurbsSurface& s, size_t fi) {
    s.degree_u = r.i32("degree_u");
    s.degree_v = r.i32("degree_v");
    s.num_u = r.i32("num_u");
    s.num_v = r.i32("num_v");
    if (s.degree_u < 1 || s.degree_v < 1) {
        corrupt(face_ctx(fi, "surface degrees ") + std::to_string(s.degree_u) + "," + std::to_string(s.degree_v) +
                " (must be >= 1)");
    }
    // num <= degree, not num < degree + 1: a degree of INT_MAX overflowed there.
    if (s.num_u <= s.degree_u || s.num_v <= s.degree_v) {
        corrupt(face_ctx(fi, "surface has ") + std::to_string(s.num_u) + "x" + std::to_string(s.num_v) +
                " control points, fewer than degree + 1");
    }
    s.rational = r.boolean("rational");
    read_knots(r, s.knots_u, s.num_u, s.degree_u, "u", fi);
    read_knots(r, s.knots_v, s.num_v, s.degree_v, "v", fi);
    const size_t c = r.count("control points", 32);
    const uint64_t expected = static_cast<uint64_t>(s.num_u) * static_cast<uint64_t>(s.num_v);
    if (c != expected) {
        corrupt(face_ctx(fi, "surface has ") + std::to_string(c) +
                " control points, expected num_u * num_v = " + std::to_string(expected));
    }
    s.cp.resize(c);
    for (Vec4& p : s.cp) p = r.vec4("control point");
}

void read_face(Reader& r, Face& f, size_t fi) {
    f.index = r.u32("face index");
    read_surface(r, f.surface, fi);
    f.u_min = r.f64("u_min");
    f.u_max = r.f64("u_max");
    f.v_min = r.f64("v_min");
    f.v_max = r.f64("v_max");
    f.reversed = r.boolean("reversed");
    f.loops.resize(r.count("trim loops", 9));
    for (TrimLoop& l : f.loops) {
        l.outer = r.boolean("loop outer");
        l.points.resize(r.count("loop points", 16));
        for (Vec2& p : l.points) p = r.vec2("loop point");
    }
    f.trim_tolerance_uv = r.f64("trim_tolerance_uv");
    f.mesh.uv.resize(r.count("mesh uv", 16));
    for (Vec2& p : f.mesh.uv) p = r.vec2("mesh uv");
    f.mesh.xyz.resize(r.count("mesh xyz", 24));
    for (Vec3& p : f.mesh.xyz) p = r.vec3("mesh xyz");
    if (f.mesh.uv.size() != f.mesh.xyz.size()) {
        corrupt(face_ctx(fi, "mesh has ") + std::to_string(f.mesh.uv.size()) + " uv but " +
                std::to_string(f.mesh.xyz.size()) + " xyz vertices");
    }
    const size_t nt = r.count("mesh triangle indices", 4);
    if (nt % 3 != 0)
        corrupt(face_ctx(fi, "mesh triangle index count ") + std::to_string(nt) + " is not a multiple of 3");
    f.mesh.triangles.resize(nt);
    const size_t nv = f.mesh.uv.size();
    for (size_t k = 0; k < nt; ++k) {
        const uint32_t t = r.u32("mesh triangle index");
        if (t >= nv) {
            corrupt(face_ctx(fi, "mesh triangle index ") + std::to_string(t) + " out of range (" + std::to_string(nv) +
                    " vertices)");
        }
        f.mesh.triangles[k] = t;
    }
    f.mesh.fallback_grid = r.boolean("mesh fallback_grid");
    f.has_color = r.boolean("face has_color");
    f.color = r.color("face color");
    f.name = r.str("face name");
    f.body = r.u32("face body");
}

// A node of the assembly tree, in the order of the layout above.
void write_part(Writer& w, const Part& p) {
    w.str(p.id);
    w.str(p.name);
    w.i32(p.parent);
    for (const double v : p.placement) w.f64(v);
    w.u8(p.has_color);
    w.color(p.color);
    w.u32(p.faces);
    for (const Vec3 corner : {p.bbox.lo, p.bbox.hi}) w.vec3(corner);
}

// The part at `index`; its parent must come before it (depth first: no cycle).
void read_part(Reader& r, Part& p, size_t index) {
    p.id = r.str("part id");
    p.name = r.str("part name");
    p.parent = r.i32("part parent");
    if (p.parent < -1 || p.parent >= static_cast<int64_t>(index))
        corrupt("part " + std::to_string(index) + " has parent " + std::to_string(p.parent));
    for (double& v : p.placement) v = r.f64("part placement");
    p.has_color = r.boolean("part has_color");
    p.color = r.color("part color");
    p.faces = r.u32("part faces");
    p.bbox.lo = r.vec3("part bbox");
    p.bbox.hi = r.vec3("part bbox");
}

// Smallest possible encoded sizes, used to bound counts before allocating.
constexpr size_t kMinBodyBytes = 8 + 1 + 12 + 4 + 1;
constexpr size_t kMinPartBytes = 8 + 8 + 4 + 1 + 12 + 12 * 8 + 4 + 6 * 8;
constexpr size_t kMinFaceBytes = 4 + (16 + 1 + 8 + 8 + 8) + 32 + 1 + 8 + 8 + 8 + 8 + 8 + 1 + 1 + 12 + 8 + 4;

}  // namespace

std::string serialize_scene(const Scene& scene) {
    Writer w;
    w.out.append(kMagic, sizeof kMagic);
    w.u32(kSceneFormatVersion);
    w.u64(0);  // payload size, patched below
    const size_t payload_begin = w.out.size();

    w.str(scene.source_name);
    w.str(scene.format);
    w.str(scene.units);
    w.vec3(scene.bbox.lo);
    w.vec3(scene.bbox.hi);
    w.f64(scene.timings.read_ms);
    w.f64(scene.timings.nurbs_convert_ms);
    w.f64(scene.timings.mesh_ms);
    w.u64(scene.warnings.size());
    for (const std::string& s : scene.warnings) w.str(s);
    w.u64(scene.bodies.size());
    for (const Body& b : scene.bodies) {
        w.str(b.name);
        w.u8(b.has_color);
        w.color(b.color);
        w.i32(b.part);
        w.u8(b.closed);
    }
    w.u64(scene.parts.size());
    for (const Part& p : scene.parts) write_part(w, p);
    w.u64(scene.faces.size());
    for (const Face& f : scene.faces) write_face(w, f);

    const uint64_t payload_size = w.out.size() - payload_begin;
    std::memcpy(w.out.data() + 12, &payload_size, 8);
    w.u64(scene_checksum(w.out.data() + payload_begin, payload_size));
    return std::move(w.out);
}

Scene deserialize_scene(const std::string& bytes) {
    if (bytes.size() < kHeaderSize + kTrailerSize) {
        corrupt("only " + std::to_string(bytes.size()) + " bytes, shorter than header and checksum (" +
                std::to_string(kHeaderSize + kTrailerSize) + ")");
    }
    if (std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0) corrupt("bad magic (not an NRBSCENE file)");
    uint32_t version;
    std::memcpy(&version, bytes.data() + 8, 4);
    if (version != kSceneFormatVersion) {
        throw Error(ErrorCode::corrupt_scene, "corrupt scene: format version " + std::to_string(version) +
                                                  " but this build reads version " +
                                                  std::to_string(kSceneFormatVersion));
    }
    uint64_t payload_size;
    std::memcpy(&payload_size, bytes.data() + 12, 8);
    const size_t available = bytes.size() - kHeaderSize - kTrailerSize;
    if (payload_size != available) {
        corrupt("header declares a payload of " + std::to_string(payload_size) + " bytes but " +
                std::to_string(available) + " are present");
    }
    const char* payload = bytes.data() + kHeaderSize;
    uint64_t stored;
    std::memcpy(&stored, payload + payload_size, 8);
    if (stored != scene_checksum(payload, payload_size)) corrupt("checksum mismatch");

    Reader r(payload, payload_size);
    Scene scene;
    scene.source_name = r.str("source_name");
    scene.format = r.str("format");
    scene.units = r.str("units");
    scene.bbox.lo = r.vec3("bbox");
    scene.bbox.hi = r.vec3("bbox");
    scene.timings.read_ms = r.f64("timings");
    scene.timings.nurbs_convert_ms = r.f64("timings");
    scene.timings.mesh_ms = r.f64("timings");
    scene.warnings.resize(r.count("warnings", 8));
    for (std::string& s : scene.warnings) s = r.str("warning");
    scene.bodies.resize(r.count("bodies", kMinBodyBytes));
    for (Body& b : scene.bodies) {
        b.name = r.str("body name");
        b.has_color = r.boolean("body has_color");
        b.color = r.color("body color");
        b.part = r.i32("body part");
        b.closed = r.boolean("body closed");
    }
    scene.parts.resize(r.count("parts", kMinPartBytes));
    for (size_t i = 0; i < scene.parts.size(); ++i) read_part(r, scene.parts[i], i);
    for (size_t i = 0; i < scene.bodies.size(); ++i)
        if (scene.bodies[i].part < -1 || scene.bodies[i].part >= static_cast<int64_t>(scene.parts.size()))
            corrupt("body " + std::to_string(i) + " names part " + std::to_string(scene.bodies[i].part));
    scene.faces.resize(r.count("faces", kMinFaceBytes));
    for (size_t i = 0; i < scene.faces.size(); ++i) read_face(r, scene.faces[i], i);
    if (r.remaining() != 0) corrupt(std::to_string(r.remaining()) + " unexpected bytes after the last face");
    return scene;
}

void write_scene_file(const Scene& scene, const std::string& path) {
    const std::string bytes = serialize_scene(scene);
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) {
        throw Error(ErrorCode::io, "cannot open scene file '" + path + "' for writing: " + std::strerror(errno));
    }
    const size_t n = std::fwrite(bytes.data(), 1, bytes.size(), f);
    const int write_errno = errno;
    if (n != bytes.size()) {
        std::fclose(f);
        throw Error(ErrorCode::io, "cannot write scene file '" + path + "': " + std::strerror(write_errno));
    }
    if (std::fclose(f) != 0) {
        throw Error(ErrorCode::io, "cannot write scene file '" + path + "': " + std::strerror(errno));
    }
}

Scene read_scene_file(const std::string& path) {
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (!f) {
        throw Error(ErrorCode::io, "cannot open scene file '" + path + "' for reading: " + std::strerror(errno));
    }
    std::string bytes;
    char buf[1 << 16];
    size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) bytes.append(buf, n);
    const bool failed = std::ferror(f) != 0;
    const int read_errno = errno;
    std::fclose(f);
    if (failed) {
        throw Error(ErrorCode::io, "cannot read scene file '" + path + "': " + std::strerror(read_errno));
    }
    return deserialize_scene(bytes);
}

}  // namespace nurbsrt
