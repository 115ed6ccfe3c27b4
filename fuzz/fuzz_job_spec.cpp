// The `job` part of POST /v1/jobs: the outputs of a job for two uploaded files
// (one STEP, one IGES), with the service's default limits.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "fuzz/fuzz_common.h"
#include "server/common/config.h"
#include "server/jobs/job_spec.h"

using namespace nurbsrt;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const std::vector<server::JobInput> inputs = {{0, "part.stp", "STEP", 1000}, {1, "part.igs", "IGES", 2000}};
    // With a webhook secret, so that a callback_url in the input reaches its parser.
    static const server::ServerConfig config = [] {
        server::ServerConfig c;
        c.webhook_secret = "fuzz-webhook-secret-0123456789";
        return c;
    }();
    const std::string text = fuzz::as_string(data, size);
    fuzz::expect_only_errors([&] {
        const std::vector<server::JobOutput> outputs = server::parse_job_spec(text, inputs, config).outputs;
        for (const server::JobOutput& o : outputs)
            if (!server::valid_artifact_name(o.artifact)) __builtin_trap();  // a name the service would not serve
    });
    return 0;
}
