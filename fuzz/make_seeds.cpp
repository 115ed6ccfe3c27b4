// Writes seed inputs that only our own writers can make: binary scenes (as the
// payload the scene harness wraps, and as whole files) of a few small faces
// built here. Usage: nurbsrt_fuzz_seeds DIR (writes DIR/*.bin).
#include <cstdio>
#include <fstream>
#include <string>

#include "core/scene/scene.h"
#include "core/io/scene_io.h"

using namespace nurbsrt;

namespace {

// A degree (p, q) patch over [0,1]^2 with clamped uniform knots, z = x * y.
Face patch(uint32_t index, int p, int q, int nu, int nv, bool rational) {
    Face f;
    f.index = index;
    NurbsSurface& s = f.surface;
    s.degree_u = p, s.degree_v = q, s.num_u = nu, s.num_v = nv, s.rational = rational;
    auto knots = [](int n, int d) {
        std::vector<double> k;
        for (int i = 0; i <= d; ++i) k.push_back(0);
        for (int i = 1; i < n - d; ++i) k.push_back(static_cast<double>(i) / (n - d));
        for (int i = 0; i <= d; ++i) k.push_back(1);
        return k;
    };
    s.knots_u = knots(nu, p);
    s.knots_v = knots(nv, q);
    for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j) {
            const double x = static_cast<double>(i) / (nu - 1), y = static_cast<double>(j) / (nv - 1);
            const double w = rational && (i + j) % 2 ? 0.5 : 1.0;
            s.cp.push_back(Vec4{x * w, y * w, x * y * w, w});
        }
    f.u_min = f.v_min = 0;
    f.u_max = f.v_max = 1;
    f.mesh.uv = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    f.mesh.xyz = {{0, 0, 0}, {1, 0, 0}, {1, 1, 1}, {0, 1, 0}};
    f.mesh.triangles = {0, 1, 2, 0, 2, 3};
    f.trim_tolerance_uv = 1e-6;
    f.name = "face " + std::to_string(index);
    return f;
}

void write(const std::string& path, const std::string& bytes) {
    std::ofstream out(path, std::ios::binary);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: %s DIR\n", argv[0]);
        return 2;
    }
    const std::string dir = argv[1];
    Scene empty;
    Scene one;
    one.source_name = "one.stp";
    one.format = "STEP";
    one.units = "mm";
    one.faces.push_back(patch(1, 1, 1, 2, 2, false));
    one.bodies.push_back({"body", true, {0.2f, 0.4f, 0.6f}});
    Scene trimmed = one;
    trimmed.faces[0].loops.push_back({{{0.1, 0.1}, {0.9, 0.1}, {0.9, 0.9}, {0.1, 0.9}}, true});
    trimmed.faces[0].loops.push_back({{{0.4, 0.4}, {0.6, 0.4}, {0.5, 0.6}}, false});
    trimmed.warnings.push_back("mesh fallback on face 1");
    Scene several;
    several.source_name = "several.igs";
    several.format = "IGES";
    several.units = "inch";
    several.faces.push_back(patch(1, 3, 3, 4, 4, true));
    several.faces.push_back(patch(2, 2, 3, 5, 6, false));
    several.faces.push_back(patch(3, 1, 2, 3, 3, true));
    several.faces[1].reversed = true;
    several.faces[2].mesh.fallback_grid = true;
    several.bodies = {{"a", false, {}}, {"b", true, {1, 0, 0}}};
    several.faces[2].body = 1;
    int n = 0;
    for (const Scene* s : {&empty, &one, &trimmed, &several}) {
        const std::string file = serialize_scene(*s);
        // The payload alone: between the 20-byte header and the 8-byte checksum.
        write(dir + "/payload-" + std::to_string(n) + ".bin", file.substr(20, file.size() - 28));
        write(dir + "/file-" + std::to_string(n) + ".bin", file);
        ++n;
    }
    return 0;
}
