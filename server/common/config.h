// Configuration of `nurbsrt serve`: where it listens, where it keeps data, and
// every limit. Set by command-line flags or NURBSRT_* environment variables
// (cli/cmd_serve.cpp binds both); validate() rejects nonsense before start.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace nurbsrt::server {

// What one connection and all of them together may take of the service
// (server/http/http_server.h enforces it).
struct ConnectionLimits {
    double header_timeout_s = 10;          // request line + headers, from the first byte
    double min_body_rate = 64 * 1024;      // bytes/s, averaged, after a grace of header_timeout_s
    size_t max_body_bytes = 64u << 20;     // the upload limit (payload_max_length)
    int max_connections = 512;             // open connections in total; beyond: 503
    int max_connections_per_client = 128;  // per client address; beyond: 503
    double keep_alive_timeout_s = 5;       // idle wait for the next request on a connection
    int max_requests_per_connection = 100;
    int retry_after_s = 2;  // Retry-After of the connection-cap 503
};

// The default event-stream cap: a quarter of the connections (128 of the
// default 512); three quarters stay for renders, uploads and polls.
inline constexpr int kEventStreamShare = 4;

struct ServerConfig {
    std::string host = "127.0.0.1";
    int port = 8080;                // 0: any free port (see port_file)
    std::string port_file;          // when set, the bound port is written there once listening
    std::string data_dir = "data";  // private temp dir for uploads lives in DATA_DIR/tmp

    // Work. Imports and conversions (child processes) are admitted by count;
    // renders by their memory estimate (renderer/frame_cost.h) against the
    // process's budget, and share the cores: cheap frames go first.
    int workers = 2;                            // concurrent imports/conversions
    int max_queue = 8;                          // requests waiting in each gate; beyond -> 503
    double queue_timeout_s = 30;                // longest wait for admission; then 503
    int retry_after_s = 2;                      // Retry-After on 503
    int render_threads = 0;                     // threads per render (0: all cores)
    int max_renders = 8;                        // renders at once (each also within the memory budget)
    size_t memory_budget_bytes = 0;             // the whole process (0: 3/4 of RAM or of the cgroup limit)
    size_t max_render_bytes = size_t(4) << 30;  // one render's estimated memory; beyond -> 422
    double max_render_cost_s = 900;             // one render's estimated work, core-seconds; beyond -> 422

    // Limits, all checked before work starts.
    size_t max_upload_bytes = size_t(64) << 20;
    int max_dimension = 8192;  // width and height each
    long long max_pixels = 16LL << 20;
    size_t max_faces = 100000;
    double render_timeout_s = 120;  // the render itself (Newton, map, shading)
    double import_timeout_s = 120;  // import / conversion child process, wall clock
    size_t import_memory_bytes = size_t(4) << 30;
    // Pre-scan of an upload's text before any import (importer/prescan.h: why these defaults).
    size_t import_max_entities = 20'000'000;
    size_t import_max_list_items = 500'000;
    int import_max_nesting = 32;

    size_t cache_bytes = size_t(512) << 20;  // scene cache capacity (0: no cache)

    // Connections (server/http/http_server.h): slow or numerous clients cost only
    // themselves. Its upload limit and Retry-After are max_upload_bytes and
    // retry_after_s above, which other answers use too.
    ConnectionLimits connection;

    // API keys (server/http/api_keys.h): a file of keys, and/or a comma-separated list
    // (from the environment only). Neither configured: no authentication. Either
    // configured but holding no key is a start-up error (fail closed), never an
    // open service.
    std::string api_keys_file;
    std::optional<std::string> api_keys;  // set when NURBSRT_API_KEYS is in the environment, even empty
    // Web origins whose pages may call the API from a browser (server/common/cors.h);
    // empty: no CORS headers at all.
    std::vector<std::string> cors_origins;
    // Batch jobs (POST /v1/jobs): kept in DATA_DIR/jobs.db and DATA_DIR/jobs/.
    int job_runners = 2;        // jobs run at once (their outputs still pass the admission gate)
    int max_queued_jobs = 100;  // jobs waiting; beyond -> 503
    // GET /v1/jobs/{id}/events streams open at once; beyond -> 503. Each holds
    // a connection and its thread for the job's life, within max_connections:
    // 0 (the default) takes a kEventStreamShare-th of them, so most
    // connections (and the pool's threads, sized above max_connections)
    // always remain for ordinary requests. A set value must leave at least one.
    int max_event_streams = 0;
    int max_job_files = 16;    // files per job
    int max_job_outputs = 64;  // outputs per job
    // Job artifacts of all kept jobs together (server/jobs/artifact_quota.h): checked
    // at submission against an estimate and when each artifact is written.
    // 0: half the size of the data directory's file system, taken at start.
    size_t max_artifact_bytes = 0;
    // Runs of one output that a crash or a lost instance may cut short before
    // it fails with `interrupted` (server/jobs/job_runner.h). A crash is not the
    // job's fault, so only runs of that output count, not its siblings' or a
    // graceful stop; 3 leaves room for two unrelated crashes in one long output.
    int max_output_attempts = 3;
    double job_retention_s = 7 * 86400.0;  // finished jobs are deleted this long after they finished
    // Stored files (POST /v1/files, server/store/file_store.h): the bytes they may
    // hold together; beyond -> 507. 1 GiB: sixteen uploads of the default
    // 64 MiB limit, or hundreds of typical parts of a few MiB, small next to
    // the disk a data directory of job artifacts needs anyway. Unpinned files
    // expire job_retention_s after their upload.
    size_t max_stored_bytes = size_t(1) << 30;
    // Where jobs are kept: empty = SQLite in DATA_DIR/jobs.db (one instance);
    // postgresql://user@host:port/db = a queue shared by every instance started
    // with it and the same DATA_DIR (a shared volume holding inputs and artifacts).
    std::string job_store;
    // PostgreSQL: how long a claimed output stays this instance's without a
    // heartbeat (renewed every third of it). It bounds how late a dead
    // instance's work resumes elsewhere; too short, and a stalled but live
    // instance (a database hiccup, a long GC-like pause of the machine) loses
    // work it then repeats. 30 s: an order of magnitude above a database
    // round trip under load, small next to the minutes a render may take.
    double lease_s = 30;
    std::string instance_id;  // names this process in leases, logs, metrics (default: host name + random)

    // Webhooks (server/jobs/webhooks.h). The HMAC-SHA256 key that signs every
    // callback body, from NURBSRT_WEBHOOK_SECRET or --webhook-secret-file
    // (never the command line: `ps` shows it); none: a job naming a
    // callback_url is refused (callbacks are never sent unsigned).
    std::string webhook_secret;
    std::string webhook_secret_file;
    // Callbacks to loopback, private, link-local and other non-public
    // addresses are refused unless allowed: an upload must not make the
    // service reach into the network it runs in (SSRF; the cloud metadata
    // address 169.254.169.254 is link-local).
    bool webhook_allow_private = false;
    // Attempts per callback, the first delay between them (doubling up to an
    // hour, plus up to 25 % jitter so receivers coming back are not hit by
    // every sender at once). 15 attempts from 2 s: the last one about four
    // hours after the job ended, long enough to ride out a receiver's
    // redeploy or a night's outage, well inside the job retention.
    int webhook_attempts = 15;
    double webhook_backoff_s = 2;
    // One attempt's connect / read timeout: a receiver should answer at once
    // and do its work later; 10 s tolerates a slow one without holding a
    // sender long.
    double webhook_timeout_s = 10;

    // Throws nurbsrt::Error(invalid_argument) with a message naming the setting.
    void validate() const;
    // memory_budget_bytes, or the automatic budget when it is 0.
    size_t effective_memory_budget() const;
    // What the renders may hold together: the budget less the scene cache and
    // the service's own base (kServiceBaseBytes in config.cpp).
    size_t render_memory_capacity() const;
    // max_event_streams, or its default share of the connections when it is 0.
    int event_stream_cap() const;
};

}  // namespace nurbsrt::server
