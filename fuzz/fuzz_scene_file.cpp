// The JSON scene file of `nurbsrt render` (models with translate, rotate_deg,
// scale): the text only, no CAD file is read.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <sstream>

#include "cli/scene_placements.h"
#include "fuzz/fuzz_common.h"

using namespace nurbsrt;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    std::istringstream in(fuzz::as_string(data, size));
    fuzz::expect_only_errors([&] {
        for (const cli::Placement& p : cli::parse_scene_file(in, "scenes/fuzz.json")) {
            // Every placement is applied to the models' control points.
            (void)p.xf.apply_h(Vec4{1, 2, 3, 1});
            (void)p.xf.determinant();
        }
    });
    return 0;
}
