// What every handler shares: the configuration, the admission gates, the scene
// cache, the metrics, the scratch directory, the stored files and the batch jobs. Free of HTTP and JSON headers.
#pragma once

#include <atomic>
#include <string_view>

#include "server/render/admission.h"
#include "server/common/config.h"
#include "server/store/file_store.h"
#include "server/common/metrics.h"
#include "server/render/scene_cache.h"
#include "server/common/scratch.h"

namespace nurbsrt::server {

class JobService;

struct ServerContext {
    explicit ServerContext(const ServerConfig& c)
        : config(c),
          gate(c.workers, c.max_queue),
          render_gate(c.max_renders, c.max_queue, c.render_memory_capacity()),
          cache(c.cache_bytes),
          // A shared job store: scratch files apart per instance in the shared data dir.
          scratch(c.data_dir, c.job_store.empty() ? std::string() : c.instance_id),
          files(c.data_dir + "/files", static_cast<int64_t>(c.max_stored_bytes)) {}
    const ServerConfig config;
    AdmissionGate gate;         // imports and conversions: child processes, by count
    AdmissionGate render_gate;  // renders: by estimated memory within the budget
    SceneCache cache;
    Metrics metrics;
    ScratchDir scratch;
    FileStore files;             // POST /v1/files: shared with every instance on the same data dir
    JobService* jobs = nullptr;  // set by run_server once the job store is open
    // GET /v1/jobs/{id}/events: streams open now (capped by
    // config.event_stream_cap()), and the stop that ends them (set before the
    // HTTP server stops: it waits for every connection's thread).
    std::atomic<int> event_streams{0};
    std::atomic<bool> stopping{false};
};

// The OpenAPI document, embedded at build time from api_schema/openapi.json.
std::string_view openapi_document();

}  // namespace nurbsrt::server
