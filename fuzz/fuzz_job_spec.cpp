// The `job` part of POST /v1/jobs: the outputs of a job for two uploaded files
// (one STEP, one IGES), with the service's default limits.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "fuzz/fuzz_common.h"
#include "server/config.h"
#include "server/job_spec.h"

using namespace nurbsrt;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const std::vector<server::JobInput> inputs = {{0, "part.stp", "STEP", 1000}, {1, "part.igs", "IGES", 2000}};
    static const server::ServerConfig config;
    const std::string text = fuzz::as_string(data, size);
    fuzz::expect_only_errors([&] {
        const std::vector<server::JobOutput> outputs = server::parse_job_spec(text, inputs, config).outputs;
        for (const server::JobOutput& o : outputs)
            if (!server::valid_artifact_name(o.artifact)) __builtin_trap();  // a name the service would not serve
    });
    return 0;
}
