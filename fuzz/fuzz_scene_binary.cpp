// The binary scene format (core/io/scene_io.h) that import children hand back
// to the service, and the NURBS scene JSON written from what it reads.
//
// An input that starts with the magic is taken as a whole file (header checks);
// any other input is taken as the payload and given a valid header and checksum
// here, so that mutations reach the payload reader instead of dying at the
// checksum. A scene that reads must write back to the same bytes, be evaluable
// over its knot ranges, and give JSON that parses.
#include <nlohmann/json.hpp>

#include <cstddef>
#include <cstdint>
#include <cstring>

#include "fuzz/fuzz_common.h"
#include "core/scene/nurbs.h"
#include "core/io/scene_io.h"
#include "core/io/scene_json.h"

using namespace nurbsrt;

namespace {

std::string with_header(const std::string& payload) {
    std::string file = "NRBSCENE";
    const uint32_t version = kSceneFormatVersion;
    const uint64_t size = payload.size(), sum = scene_checksum(payload.data(), payload.size());
    file.append(reinterpret_cast<const char*>(&version), 4);
    file.append(reinterpret_cast<const char*>(&size), 8);
    file += payload;
    file.append(reinterpret_cast<const char*>(&sum), 8);
    return file;
}

void check(const Scene& scene, const std::string& bytes) {
    if (serialize_scene(scene) != bytes) __builtin_trap();  // the format has one encoding per scene
    for (const Face& f : scene.faces) {
        const NurbsSurface& s = f.surface;
        const double u[3] = {s.u_begin(), s.u_begin() / 2 + s.u_end() / 2, s.u_end()};
        const double v[3] = {s.v_begin(), s.v_begin() / 2 + s.v_end() / 2, s.v_end()};
        for (double a : u)
            for (double b : v) (void)evaluate_d1(s, a, b);
    }
    const nlohmann::json doc = nlohmann::json::parse(scene_to_json(scene), nullptr, false);
    if (doc.is_discarded()) __builtin_trap();  // the writer promises text that parses
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    std::string bytes = fuzz::as_string(data, size);
    if (bytes.compare(0, 8, "NRBSCENE") != 0) bytes = with_header(bytes);
    fuzz::expect_only_errors([&] { check(deserialize_scene(bytes), bytes); });
    return 0;
}
