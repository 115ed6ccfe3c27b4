#include "server/common/config.h"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <string>

#include "core/error.h"
#include "server/common/cors.h"

namespace nurbsrt::server {
namespace {

// The service's own memory besides renders and the cache: code and libraries,
// OCCT's and Mesa's static state, the HTTP threads and uploads in flight. Idle
// RSS measured at 190-200 MiB (Debian 12, 2 cores); rounded up for uploads.
constexpr size_t kServiceBaseBytes = size_t(320) << 20;
// The automatic budget leaves a quarter of the machine (or of the container's
// limit) to the import/conversion children, the page cache and other processes.
constexpr double kAutoBudgetShare = 0.75;

size_t physical_memory() {
    const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
    size_t bytes = pages > 0 && page > 0 ? size_t(pages) * size_t(page) : size_t(8) << 30;
    // A cgroup v2 limit (a container) is what the kernel enforces: "max" or bytes.
    std::ifstream cg("/sys/fs/cgroup/memory.max");
    std::string limit;
    if (cg >> limit && limit != "max") {
        try {
            bytes = std::min<size_t>(bytes, std::stoull(limit));
        } catch (const std::exception&) {
            // Unreadable: keep the machine's size.
        }
    }
    return bytes;
}

}  // namespace

size_t ServerConfig::effective_memory_budget() const {
    return memory_budget_bytes ? memory_budget_bytes : static_cast<size_t>(kAutoBudgetShare * physical_memory());
}

size_t ServerConfig::render_memory_capacity() const {
    const size_t budget = effective_memory_budget(), reserved = cache_bytes + kServiceBaseBytes;
    return budget > reserved ? budget - reserved : 0;
}

int ServerConfig::event_stream_cap() const {
    return max_event_streams ? max_event_streams : std::max(1, connection.max_connections / kEventStreamShare);
}

void ServerConfig::validate() const {
    auto fail = [](const std::string& what) { throw Error(ErrorCode::invalid_argument, what); };
    if (host.empty()) fail("host must not be empty");
    if (port < 0 || port > 65535) fail("port must be in 0..65535");
    if (data_dir.empty()) fail("data dir must not be empty");
    if (workers < 1 || workers > 256) fail("workers must be in 1..256");
    if (max_queue < 0 || max_queue > 10000) fail("max queue must be in 0..10000");
    if (!(queue_timeout_s > 0)) fail("queue timeout must be positive");
    if (retry_after_s < 1) fail("retry-after must be at least 1 s");
    if (render_threads < 0) fail("render threads must be >= 0");
    if (max_renders < 1 || max_renders > 256) fail("max renders must be in 1..256");
    if (max_render_bytes < 1) fail("max render memory must be positive");
    if (!(max_render_cost_s > 0)) fail("max render cost must be positive");
    if (render_memory_capacity() < (size_t(64) << 20))
        fail("the memory budget (" + std::to_string(effective_memory_budget() >> 20) +
             " MiB) leaves less than 64 MiB for renders after the scene cache (" + std::to_string(cache_bytes >> 20) +
             " MiB) and the service's base (" + std::to_string(kServiceBaseBytes >> 20) + " MiB)");
    if (max_upload_bytes < 1) fail("max upload size must be positive");
    if (max_dimension < 1 || max_dimension > 16384) fail("max dimension must be in 1..16384");
    if (max_pixels < 1) fail("max pixels must be positive");
    if (max_faces < 1) fail("max faces must be positive");
    if (!(render_timeout_s > 0)) fail("render timeout must be positive");
    if (!(import_timeout_s > 0)) fail("import timeout must be positive");
    if (!(connection.header_timeout_s > 0)) fail("header timeout must be positive");
    if (!(connection.min_body_rate > 0)) fail("minimum body rate must be positive");
    if (connection.max_connections < 1 || connection.max_connections > 100000)
        fail("max connections must be in 1..100000");
    if (connection.max_connections_per_client < 1 || connection.max_connections_per_client > connection.max_connections)
        fail("max connections per client must be in 1..max connections");
    if (import_max_entities < 1 || import_max_list_items < 1) fail("import pre-scan limits must be positive");
    if (import_max_nesting < 1 || import_max_nesting > 10000) fail("import max nesting must be in 1..10000");
    if (job_runners < 1 || job_runners > 256) fail("job runners must be in 1..256");
    if (max_queued_jobs < 1) fail("max queued jobs must be positive");
    if (max_event_streams < 0 || (max_event_streams > 0 && max_event_streams >= connection.max_connections))
        fail("max event streams must be in 1..max connections - 1 (0: a quarter of max connections)");
    if (max_output_attempts < 1 || max_output_attempts > 100) fail("max output attempts must be in 1..100");
    if (max_job_files < 1 || max_job_files > 10000) fail("max job files must be in 1..10000");
    if (max_job_outputs < 1 || max_job_outputs > 10000) fail("max job outputs must be in 1..10000");
    if (!(job_retention_s > 0)) fail("job retention must be positive");
    if (!(lease_s >= 1 && lease_s <= 86400)) fail("lease seconds must be in 1..86400");
    if (webhook_attempts < 1 || webhook_attempts > 100) fail("webhook attempts must be in 1..100");
    if (!(webhook_backoff_s >= 0.01 && webhook_backoff_s <= 3600)) fail("webhook backoff must be in 0.01..3600 s");
    if (!(webhook_timeout_s >= 0.1 && webhook_timeout_s <= 300)) fail("webhook timeout must be in 0.1..300 s");
    if (!job_store.empty() && job_store.rfind("postgresql://", 0) != 0 && job_store.rfind("postgres://", 0) != 0)
        fail("job store must be a postgresql:// URL (or empty for SQLite in the data dir)");
    for (const std::string& origin : cors_origins) (void)normalized_origin(origin);
    for (const char ch : instance_id)
        if (!std::isalnum(static_cast<unsigned char>(ch)) && ch != '-' && ch != '_' && ch != '.')
            fail("instance id may hold only letters, digits, '-', '_' and '.'");
}

}  // namespace nurbsrt::server
