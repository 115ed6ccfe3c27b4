#include "server/store/job_schema.h"

#include <nlohmann/json.hpp>

#include <string_view>

namespace nurbsrt::server {
namespace {

// The tables of version 1 with the dialect's types in place of $SERIAL (the
// submission order key), $INT64 (Unix ms and byte counts: 64 bits; SQLite's
// INTEGER is), $REAL and $LEASES (job_outputs' lease columns, PostgreSQL only).
constexpr const char* kTablesV1 = R"sql(
CREATE TABLE IF NOT EXISTS jobs (
  seq $SERIAL,
  id TEXT NOT NULL UNIQUE,
  state TEXT NOT NULL,
  created_ms $INT64 NOT NULL,
  started_ms $INT64 NOT NULL DEFAULT 0,
  finished_ms $INT64 NOT NULL DEFAULT 0,
  attempts INTEGER NOT NULL DEFAULT 0,
  error_code TEXT NOT NULL DEFAULT '',
  error_message TEXT NOT NULL DEFAULT ''
);
CREATE INDEX IF NOT EXISTS jobs_state ON jobs(state, seq);
CREATE TABLE IF NOT EXISTS job_inputs (
  job_id TEXT NOT NULL REFERENCES jobs(id) ON DELETE CASCADE,
  idx INTEGER NOT NULL,
  filename TEXT NOT NULL,
  format TEXT NOT NULL,
  bytes $INT64 NOT NULL,
  PRIMARY KEY (job_id, idx)
);
CREATE TABLE IF NOT EXISTS job_outputs (
  job_id TEXT NOT NULL REFERENCES jobs(id) ON DELETE CASCADE,
  idx INTEGER NOT NULL,
  file INTEGER NOT NULL,
  kind TEXT NOT NULL,
  options TEXT NOT NULL,
  artifact TEXT NOT NULL,
  content_type TEXT NOT NULL,
  state TEXT NOT NULL,
  progress $REAL NOT NULL DEFAULT 0,
  error_code TEXT NOT NULL DEFAULT '',
  error_message TEXT NOT NULL DEFAULT '',
  artifact_bytes $INT64 NOT NULL DEFAULT 0,
  started_ms $INT64 NOT NULL DEFAULT 0,
  finished_ms $INT64 NOT NULL DEFAULT 0,
  result TEXT NOT NULL DEFAULT '',$LEASES
  PRIMARY KEY (job_id, idx)
);
)sql";

// Lease expiries are in the database server's clock, so instances whose clocks
// disagree still agree on when a lease ran out. `completions` counts the final
// updates of an output: fencing keeps it at 1, and tests read it to prove that.
constexpr const char* kPostgresLeases = R"sql(
  attempts INTEGER NOT NULL DEFAULT 0,
  lease_token TEXT NOT NULL DEFAULT '',
  lease_owner TEXT NOT NULL DEFAULT '',
  lease_expires_ms BIGINT NOT NULL DEFAULT 0,
  completions INTEGER NOT NULL DEFAULT 0,)sql";
constexpr const char* kPostgresLeaseIndex =
    "CREATE INDEX IF NOT EXISTS job_outputs_open ON job_outputs(state, lease_expires_ms);\n";

// Version 2: a job's callback URL and its delivery (server/jobs/webhooks.h).
constexpr const char* kColumnsV2 = R"sql(
ALTER TABLE jobs ADD COLUMN callback_url TEXT NOT NULL DEFAULT '';
ALTER TABLE jobs ADD COLUMN callback_state TEXT NOT NULL DEFAULT '';
ALTER TABLE jobs ADD COLUMN callback_attempts INTEGER NOT NULL DEFAULT 0;
ALTER TABLE jobs ADD COLUMN callback_due_ms $INT64 NOT NULL DEFAULT 0;
ALTER TABLE jobs ADD COLUMN callback_status INTEGER NOT NULL DEFAULT 0;
ALTER TABLE jobs ADD COLUMN callback_error TEXT NOT NULL DEFAULT '';
ALTER TABLE jobs ADD COLUMN callback_done_ms $INT64 NOT NULL DEFAULT 0;
CREATE INDEX IF NOT EXISTS jobs_callback_due ON jobs(callback_state, callback_due_ms);
)sql";

// Events (job_store.h, JobEvent), with a per-job counter in jobs. Deleting a
// job deletes its events (ON DELETE CASCADE, and SQLite's explicit deletion).
constexpr const char* kEvents = R"sql(
ALTER TABLE jobs ADD COLUMN event_seq $INT64 NOT NULL DEFAULT 0;
CREATE TABLE IF NOT EXISTS job_events (
  job_id TEXT NOT NULL REFERENCES jobs(id) ON DELETE CASCADE,
  seq $INT64 NOT NULL,
  type TEXT NOT NULL,
  data TEXT NOT NULL,
  time_ms $INT64 NOT NULL,
  PRIMARY KEY (job_id, seq)
);
)sql";

void replace_all(std::string& s, std::string_view token, std::string_view by) {
    for (size_t at = s.find(token); at != std::string::npos; at = s.find(token, at + by.size()))
        s.replace(at, token.size(), by);
}

std::string in_dialect(const char* sql, SqlDialect d) {
    const bool pg = d == SqlDialect::postgres;
    std::string s = sql;
    replace_all(s, "$SERIAL", pg ? "BIGSERIAL PRIMARY KEY" : "INTEGER PRIMARY KEY AUTOINCREMENT");
    replace_all(s, "$INT64", pg ? "BIGINT" : "INTEGER");
    replace_all(s, "$REAL", pg ? "DOUBLE PRECISION" : "REAL");
    replace_all(s, "$LEASES", pg ? kPostgresLeases : "");
    return s;
}

}  // namespace

std::string job_schema_v1(SqlDialect dialect) {
    std::string s = in_dialect(kTablesV1, dialect);
    if (dialect == SqlDialect::postgres) s += kPostgresLeaseIndex;
    return s;
}

std::string job_schema_v2(SqlDialect dialect) { return in_dialect(kColumnsV2, dialect); }

std::string job_schema_events(SqlDialect dialect) { return in_dialect(kEvents, dialect); }

const std::string& select_output_sql() {
    static const std::string sql =
        std::string("SELECT ") + kOutputColumns + " FROM job_outputs WHERE job_id = $1 AND idx = $2";
    return sql;
}

namespace {

using nlohmann::json;

json error_json(const std::string& code, const std::string& message) { return {{"code", code}, {"message", message}}; }

}  // namespace

std::string state_event_data(JobState state, const std::string& error_code, const std::string& error_message) {
    json d = {{"state", job_state_name(state)}};
    if (!error_code.empty()) d["error"] = error_json(error_code, error_message);
    return d.dump();
}

std::string output_event_data(const JobOutput& o) {
    json d = {{"output", o.index},
              {"file", o.file},
              {"kind", output_kind_name(o.kind)},
              {"artifact", o.artifact},
              {"state", job_state_name(o.state)}};
    if (o.started_ms) d["started_ms"] = o.started_ms;
    if (o.finished_ms) d["finished_ms"] = o.finished_ms;
    if (o.started_ms && o.finished_ms) d["duration_ms"] = o.finished_ms - o.started_ms;
    if (!o.error_code.empty()) d["error"] = error_json(o.error_code, o.error_message);
    return d.dump();
}

std::string artifact_event_data(const std::string& job_id, const JobOutput& o) {
    // The same URL as the job document's (GET /v1/jobs/{id}/artifacts/{name}).
    return json{{"output", o.index},
                {"name", o.artifact},
                {"bytes", o.artifact_bytes},
                {"content_type", o.content_type},
                {"url", "/v1/jobs/" + job_id + "/artifacts/" + o.artifact}}
        .dump();
}

std::string progress_event_data(int64_t done, int64_t total, int64_t artifact_bytes) {
    return json{{"outputs_done", done},
                {"outputs_total", total},
                {"fraction", total > 0 ? static_cast<double>(done) / static_cast<double>(total) : 0.0},
                {"artifact_bytes", artifact_bytes}}
        .dump();
}

}  // namespace nurbsrt::server
