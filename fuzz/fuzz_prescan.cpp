// The STEP/IGES text pre-scan that runs before OCCT sees an upload, after the
// format detection by content: with the default limits, and with small ones
// so that every refusal is reached by small inputs too.
#include <cstddef>
#include <cstdint>
#include <sstream>

#include "fuzz/fuzz_common.h"
#include "importer/importer.h"
#include "importer/prescan.h"

using namespace nurbsrt;

namespace {

void scan(const std::string& text, CadFormat format, const PrescanLimits& limits) {
    std::istringstream in(text);
    fuzz::expect_only_errors([&] {
        const PrescanReport r = prescan_cad_stream(in, format, limits);
        // Whatever it accepts is within the limits it was given.
        if (r.entities > limits.max_entities || r.longest_list > limits.max_list_items ||
            r.deepest_nesting > limits.max_nesting)
            __builtin_trap();
    });
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string text = fuzz::as_string(data, size);
    (void)detect_format_bytes(text.data(), text.size());  // what the service runs first
    PrescanLimits small;
    small.max_entities = 20;
    small.max_list_items = 16;
    small.max_nesting = 4;
    for (CadFormat f : {CadFormat::step, CadFormat::iges}) {
        // The service scans only the detected format; both are cheap and both
        // scanners must cope with anything.
        scan(text, f, PrescanLimits{});
        scan(text, f, small);
    }
    return 0;
}
