// nurbsrt serve: the HTTP service (server/). Every flag can also be set by an
// environment variable NURBSRT_<FLAG> (a flag on the command line wins).
#include <CLI/CLI.hpp>

#include <cstdlib>

#include "cli/commands.h"
#include "server/server.h"
#include "cli/validators.h"

namespace nurbsrt::cli {

namespace {

// The service's configuration as the options fill it; sizes are given in MiB
// (KiB/s for the body rate) on the command line and set in bytes once parsed.
struct ServeArgs {
    server::ServerConfig c;
    double upload_mb = static_cast<double>(c.max_upload_bytes) / (1 << 20);
    double import_memory_mb = static_cast<double>(c.import_memory_bytes >> 20);
    double cache_mb = static_cast<double>(c.cache_bytes >> 20);
    double stored_mb = static_cast<double>(c.max_stored_bytes >> 20);
    double artifacts_mb = 0.0;  // 0: half the data directory's file system
    double budget_mb = 0.0;
    double render_mb = static_cast<double>(c.max_render_bytes >> 20);
    double body_rate_kib = c.connection.min_body_rate / 1024;
};

// Where it listens and keeps its data.
void add_listen_options(CLI::App* cmd, ServeArgs& a) {
    cmd->add_option("--host", a.c.host, "address to listen on")->envname("NURBSRT_HOST")->capture_default_str();
    cmd->add_option("--port", a.c.port, "TCP port (0: any free port, see --port-file)")
        ->envname("NURBSRT_PORT")
        ->check(in_range(0, 65535))
        ->capture_default_str();
    cmd->add_option("--port-file", a.c.port_file, "write the bound port to this file once listening")
        ->envname("NURBSRT_PORT_FILE");
    cmd->add_option("--data-dir", a.c.data_dir,
                    "data directory (uploads staged in DATA_DIR/tmp; jobs in DATA_DIR/jobs.db, DATA_DIR/jobs/)")
        ->envname("NURBSRT_DATA_DIR")
        ->capture_default_str();
}

// How much work runs at once, and how long work may wait.
void add_capacity_options(CLI::App* cmd, ServeArgs& a) {
    cmd->add_option("--workers", a.c.workers, "imports/conversions running at once")
        ->envname("NURBSRT_WORKERS")
        ->check(in_range(1, 256))
        ->capture_default_str();
    cmd->add_option("--max-queue", a.c.max_queue, "requests waiting for a worker; beyond: 503 + Retry-After")
        ->envname("NURBSRT_MAX_QUEUE")
        ->check(in_range(0, 10000))
        ->capture_default_str();
    cmd->add_option("--queue-timeout", a.c.queue_timeout_s, "longest wait for a worker, seconds; then 503")
        ->envname("NURBSRT_QUEUE_TIMEOUT")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    cmd->add_option("--retry-after", a.c.retry_after_s, "Retry-After seconds on 503")
        ->envname("NURBSRT_RETRY_AFTER")
        ->check(in_range(1, 3600))
        ->capture_default_str();
    cmd->add_option("--render-threads", a.c.render_threads, "threads per render (0: all cores)")
        ->envname("NURBSRT_RENDER_THREADS")
        ->check(in_range(0, 1024))
        ->capture_default_str();
    cmd->add_option("--max-renders", a.c.max_renders, "renders at once, sharing the cores (cheap ones first)")
        ->envname("NURBSRT_MAX_RENDERS")
        ->check(in_range(1, 256))
        ->capture_default_str();
    cmd->add_option("--memory-budget-mb", a.budget_mb,
                    "memory of the whole service, MiB: renders wait (or 503) rather than exceed it "
                    "(0: 3/4 of RAM or of the cgroup limit)")
        ->envname("NURBSRT_MEMORY_BUDGET_MB")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
}

// The largest render and upload one request may ask for.
void add_render_limit_options(CLI::App* cmd, ServeArgs& a) {
    cmd->add_option("--max-render-mb", a.render_mb, "largest estimated memory of one render, MiB (422 beyond)")
        ->envname("NURBSRT_MAX_RENDER_MB")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    cmd->add_option("--max-render-cost", a.c.max_render_cost_s,
                    "largest estimated work of one render, core-seconds (422 beyond)")
        ->envname("NURBSRT_MAX_RENDER_COST")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    cmd->add_option("--max-upload-mb", a.upload_mb, "largest upload, MiB (413 beyond)")
        ->envname("NURBSRT_MAX_UPLOAD_MB")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    cmd->add_option("--max-dimension", a.c.max_dimension, "largest image width or height, pixels")
        ->envname("NURBSRT_MAX_DIMENSION")
        ->check(in_range(1, 16384))
        ->capture_default_str();
    cmd->add_option("--max-pixels", a.c.max_pixels, "largest image, width x height")
        ->envname("NURBSRT_MAX_PIXELS")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    cmd->add_option("--max-faces", a.c.max_faces, "most faces a rendered model may have")
        ->envname("NURBSRT_MAX_FACES")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    cmd->add_option("--render-timeout", a.c.render_timeout_s, "time limit of a render, seconds (504 beyond)")
        ->envname("NURBSRT_RENDER_TIMEOUT")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
}

// The bounds of an import or conversion (its own process), and the scene cache.
void add_import_options(CLI::App* cmd, ServeArgs& a) {
    cmd->add_option("--import-timeout", a.c.import_timeout_s, "time limit of an import or conversion, seconds")
        ->envname("NURBSRT_IMPORT_TIMEOUT")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    cmd->add_option("--import-memory-mb", a.import_memory_mb, "memory limit of an import/conversion process, MiB")
        ->envname("NURBSRT_IMPORT_MEMORY_MB")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    cmd->add_option("--import-max-entities", a.c.import_max_entities,
                    "most entities a STEP/IGES upload may hold (checked before it is parsed; 422 beyond)")
        ->envname("NURBSRT_IMPORT_MAX_ENTITIES")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    cmd->add_option("--import-max-list-items", a.c.import_max_list_items,
                    "most items in one STEP list or IGES parameter list of an upload (422 beyond)")
        ->envname("NURBSRT_IMPORT_MAX_LIST_ITEMS")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    cmd->add_option("--import-max-nesting", a.c.import_max_nesting,
                    "deepest nesting of parentheses in a STEP upload (422 beyond)")
        ->envname("NURBSRT_IMPORT_MAX_NESTING")
        ->check(in_range(1, 10000))
        ->capture_default_str();
    cmd->add_option("--cache-mb", a.cache_mb, "scene cache capacity, MiB (0: no cache)")
        ->envname("NURBSRT_CACHE_MB")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
}

// Connections: slow clients, how many, who may call.
void add_connection_options(CLI::App* cmd, ServeArgs& a) {
    cmd->add_option("--header-timeout", a.c.connection.header_timeout_s,
                    "seconds for a request's line and headers to arrive (408 beyond); also the grace\n"
                    "before --min-body-rate-kib applies")
        ->envname("NURBSRT_HEADER_TIMEOUT")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    cmd->add_option("--min-body-rate-kib", a.body_rate_kib,
                    "KiB/s a request body must arrive at on average after the grace (408 below)")
        ->envname("NURBSRT_MIN_BODY_RATE_KIB")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    cmd->add_option("--max-connections", a.c.connection.max_connections, "open connections at once; beyond: 503")
        ->envname("NURBSRT_MAX_CONNECTIONS")
        ->check(in_range(1, 100000))
        ->capture_default_str();
    cmd->add_option("--max-connections-per-client", a.c.connection.max_connections_per_client,
                    "open connections from one client address; beyond: 503")
        ->envname("NURBSRT_MAX_CONNECTIONS_PER_CLIENT")
        ->check(in_range(1, 100000))
        ->capture_default_str();
    cmd->add_option("--api-keys-file", a.c.api_keys_file,
                    "require 'Authorization: Bearer <key>' (or 'X-Api-Key: <key>') with a key from this\n"
                    "file (one per line, '#' comments, at least 16 characters) on every route but\n"
                    "/healthz, /readyz, /v1/openapi.json and the web page; keys can also be given\n"
                    "comma-separated in NURBSRT_API_KEYS")
        ->envname("NURBSRT_API_KEYS_FILE");
    cmd->add_option("--cors-origin", a.c.cors_origins,
                    "a web origin (scheme://host[:port]) whose pages may call the API from a browser;\n"
                    "repeat for several (the environment variable: comma-separated). None: no CORS headers")
        ->envname("NURBSRT_CORS_ORIGIN")
        ->delimiter(',');
}

// Batch jobs and stored files, and the queue they share between instances.
void add_job_options(CLI::App* cmd, ServeArgs& a) {
    cmd->add_option("--job-runners", a.c.job_runners, "batch jobs running at once (their work shares --workers)")
        ->envname("NURBSRT_JOB_RUNNERS")
        ->check(in_range(1, 256))
        ->capture_default_str();
    cmd->add_option("--max-queued-jobs", a.c.max_queued_jobs, "batch jobs waiting to run; beyond: 503 + Retry-After")
        ->envname("NURBSRT_MAX_QUEUED_JOBS")
        ->check(in_range(1, 1000000))
        ->capture_default_str();
    cmd->add_option("--max-event-streams", a.c.max_event_streams,
                    "GET /v1/jobs/{id}/events streams open at once, each holding one of\n"
                    "--max-connections; beyond: 503 + Retry-After (0: a quarter of --max-connections)")
        ->envname("NURBSRT_MAX_EVENT_STREAMS")
        ->check(in_range(0, 100000))
        ->capture_default_str();
    cmd->add_option("--max-job-files", a.c.max_job_files, "most files in one batch job")
        ->envname("NURBSRT_MAX_JOB_FILES")
        ->check(in_range(1, 10000))
        ->capture_default_str();
    cmd->add_option("--max-job-outputs", a.c.max_job_outputs, "most outputs (renders + conversions) of one batch job")
        ->envname("NURBSRT_MAX_JOB_OUTPUTS")
        ->check(in_range(1, 10000))
        ->capture_default_str();
    cmd->add_option("--max-output-attempts", a.c.max_output_attempts,
                    "runs of one job output that a crash of the service (or a lost instance) may cut\n"
                    "short before the output fails with code interrupted; a graceful stop does not count")
        ->envname("NURBSRT_MAX_OUTPUT_ATTEMPTS")
        ->check(in_range(1, 100))
        ->capture_default_str();
    cmd->add_option("--job-retention", a.c.job_retention_s,
                    "seconds a finished job (and its artifacts) is kept before it is deleted")
        ->envname("NURBSRT_JOB_RETENTION")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    cmd->add_option("--max-stored-mb", a.stored_mb,
                    "stored files (POST /v1/files) together, MiB (507 beyond); unpinned ones expire\n"
                    "with --job-retention")
        ->envname("NURBSRT_MAX_STORED_MB")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    cmd->add_option("--max-artifacts-mb", a.artifacts_mb,
                    "job artifacts of all kept jobs together, MiB: a job beyond it is refused (507), an\n"
                    "output whose artifact would pass it fails; 0: half the data directory's file system")
        ->envname("NURBSRT_MAX_ARTIFACTS_MB")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    cmd->add_option("--job-store", a.c.job_store,
                    "where batch jobs are queued: empty = SQLite in DATA_DIR/jobs.db (one instance);\n"
                    "postgresql://user[:password]@host[:port]/db = one queue for every instance started\n"
                    "with it and the same --data-dir (a shared volume: inputs and artifacts live there);\n"
                    "give a password in PGPASSWORD or ~/.pgpass rather than here (ps shows arguments)")
        ->envname("NURBSRT_JOB_STORE");
    cmd->add_option("--lease-seconds", a.c.lease_s,
                    "PostgreSQL job store: an output a dead instance was running is taken over by another\n"
                    "this long after its last heartbeat (renewed every third of it)")
        ->envname("NURBSRT_LEASE_SECONDS")
        ->check(in_range(1.0, 86400.0))
        ->capture_default_str();
    cmd->add_option("--instance-id", a.c.instance_id,
                    "this instance's name in leases, logs and metrics (default: host name + random suffix)")
        ->envname("NURBSRT_INSTANCE_ID");
}

// Job callbacks.
void add_webhook_options(CLI::App* cmd, ServeArgs& a) {
    cmd->add_option("--webhook-secret-file", a.c.webhook_secret_file,
                    "the key that signs job callbacks (HMAC-SHA256, X-Nurbsrt-Signature), read from this\n"
                    "file; or give it in NURBSRT_WEBHOOK_SECRET. None: jobs naming a callback_url are refused")
        ->envname("NURBSRT_WEBHOOK_SECRET_FILE");
    cmd->add_flag("--webhook-allow-private", a.c.webhook_allow_private,
                  "let callbacks reach loopback, private and link-local addresses (refused by default:\n"
                  "an upload must not make the service call into the network it runs in)")
        ->envname("NURBSRT_WEBHOOK_ALLOW_PRIVATE");
    cmd->add_option("--webhook-attempts", a.c.webhook_attempts, "attempts per job callback before it is given up")
        ->envname("NURBSRT_WEBHOOK_ATTEMPTS")
        ->check(in_range(1, 100))
        ->capture_default_str();
    cmd->add_option("--webhook-backoff", a.c.webhook_backoff_s,
                    "seconds before the second attempt of a callback; doubled after each (at most an hour)")
        ->envname("NURBSRT_WEBHOOK_BACKOFF")
        ->check(in_range(0.01, 3600.0))
        ->capture_default_str();
    cmd->add_option("--webhook-timeout", a.c.webhook_timeout_s, "seconds a callback receiver has to connect and answer")
        ->envname("NURBSRT_WEBHOOK_TIMEOUT")
        ->check(in_range(0.1, 300.0))
        ->capture_default_str();
}

void run_serve(ServeArgs& a) {
    server::ServerConfig& c = a.c;
    c.memory_budget_bytes = static_cast<size_t>(a.budget_mb * (1 << 20));
    c.max_render_bytes = static_cast<size_t>(a.render_mb * (1 << 20));
    // Keys themselves only from the environment: a command line shows in `ps`.
    if (const char* k = std::getenv("NURBSRT_API_KEYS")) c.api_keys = k;
    if (const char* k = std::getenv("NURBSRT_WEBHOOK_SECRET")) c.webhook_secret = k;
    c.max_upload_bytes = static_cast<size_t>(a.upload_mb * (1 << 20));
    c.import_memory_bytes = static_cast<size_t>(a.import_memory_mb * (1 << 20));
    c.cache_bytes = static_cast<size_t>(a.cache_mb * (1 << 20));
    c.max_stored_bytes = static_cast<size_t>(a.stored_mb * (1 << 20));
    c.max_artifact_bytes = static_cast<size_t>(a.artifacts_mb * (1 << 20));
    c.connection.min_body_rate = a.body_rate_kib * 1024;
    const int rc = server::run_server(c);
    if (rc != 0) std::exit(rc);
}

}  // namespace

void add_serve_command(CLI::App& app) {
    auto a = std::make_shared<ServeArgs>();
    auto* cmd = app.add_subcommand("serve",
                                   "Run the HTTP service: POST /v1/renders, POST /v1/conversions, /v1/jobs (batch\n"
                                   "jobs, kept in DATA_DIR/jobs.db and DATA_DIR/jobs/), GET /healthz, /readyz,\n"
                                   "/metrics, /v1/openapi.json (the API document). Logs one JSON line per request\n"
                                   "on stderr. Every option can also be set by the environment variable shown,\n"
                                   "e.g. NURBSRT_PORT=9000. Stop with SIGINT or SIGTERM.\n"
                                   "Example: nurbsrt serve --host 127.0.0.1 --port 8080 --data-dir ./data");
    add_listen_options(cmd, *a);
    add_capacity_options(cmd, *a);
    add_render_limit_options(cmd, *a);
    add_import_options(cmd, *a);
    add_connection_options(cmd, *a);
    add_job_options(cmd, *a);
    add_webhook_options(cmd, *a);
    cmd->callback([a] { run_serve(*a); });
}

}  // namespace nurbsrt::cli
