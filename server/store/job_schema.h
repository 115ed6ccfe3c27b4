// The job tables as both job stores (SQLite, PostgreSQL) define and read them:
// one definition of the tables, of the columns a read selects and of how a row
// becomes a record. The dialects differ only in column types and in the lease
// columns of job_outputs, which PostgreSQL's instances share and SQLite's one
// process does not need.
#pragma once

#include <optional>
#include <string>

#include "server/store/job_store.h"

namespace nurbsrt::server {

enum class SqlDialect { sqlite, postgres };

// Schema version 1 (jobs, job_inputs, job_outputs) and version 2 (the webhook
// columns of jobs) in `dialect`, as the migrations apply them.
std::string job_schema_v1(SqlDialect dialect);
std::string job_schema_v2(SqlDialect dialect);
// The events table (JobEvent) and the jobs' event counter: PostgreSQL's
// version 3, SQLite's version 4.
std::string job_schema_events(SqlDialect dialect);

// The columns job_of_row, input_of_row and output_of_row read, in their order.
inline constexpr const char* kJobColumns =
    "seq, id, state, created_ms, started_ms, finished_ms, attempts, error_code, error_message, callback_url, "
    "callback_state, callback_attempts, callback_due_ms, callback_status, callback_error, callback_done_ms";
inline constexpr const char* kInputColumns = "idx, filename, format, bytes";
inline constexpr const char* kOutputColumns =
    "idx, file, kind, options, artifact, content_type, state, progress, error_code, error_message, "
    "artifact_bytes, started_ms, finished_ms, result";

// A row of either store: i64(c), real(c) and text(c) of its column c.
template <class Row>
JobRecord job_of_row(const Row& r) {
    JobRecord j;
    j.seq = r.i64(0);
    j.id = r.text(1);
    j.state = stored_job_state(r.text(2));
    j.created_ms = r.i64(3);
    j.started_ms = r.i64(4);
    j.finished_ms = r.i64(5);
    j.attempts = static_cast<int>(r.i64(6));
    j.error_code = r.text(7);
    j.error_message = r.text(8);
    j.callback_url = r.text(9);
    j.callback.state = parse_callback_state(r.text(10));
    j.callback.attempts = static_cast<int>(r.i64(11));
    j.callback.due_ms = r.i64(12);
    j.callback.last_status = static_cast<int>(r.i64(13));
    j.callback.last_error = r.text(14);
    j.callback.done_ms = r.i64(15);
    return j;
}

template <class Row>
JobInput input_of_row(const Row& r) {
    return {static_cast<int>(r.i64(0)), r.text(1), r.text(2), r.i64(3)};
}

template <class Row>
JobOutput output_of_row(const Row& r) {
    return {.index = static_cast<int>(r.i64(0)),
            .file = static_cast<int>(r.i64(1)),
            .kind = stored_output_kind(r.text(2)),
            .options_json = r.text(3),
            .artifact = r.text(4),
            .content_type = r.text(5),
            .state = stored_job_state(r.text(6)),
            .progress = r.real(7),
            .error_code = r.text(8),
            .error_message = r.text(9),
            .artifact_bytes = r.i64(10),
            .started_ms = r.i64(11),
            .finished_ms = r.i64(12),
            .result_json = r.text(13)};
}

// Events (JobEvent). Parameters are written $1, $2 (PostgreSQL's form; SQLite
// reads $1 as a named parameter whose index is its order, also 1, 2, ...).
// The next seq of a job: its counter, bumped under the job row's lock, so
// appends of several instances are serialized and commit in seq order (a
// reader polling "after seq n" never skips one committed later).
inline constexpr const char* kNextEventSeqSql =
    "UPDATE jobs SET event_seq = event_seq + 1 WHERE id = $1 RETURNING event_seq";
inline constexpr const char* kInsertEventSql =
    "INSERT INTO job_events(job_id, seq, type, data, time_ms) VALUES ($1, $2, $3, $4, $5)";
inline constexpr const char* kSelectEventsSql =
    "SELECT seq, type, data, time_ms FROM job_events WHERE job_id = $1 AND seq > $2 ORDER BY seq LIMIT $3";
// Outputs finished, outputs in all, artifact bytes written: a progress event's numbers.
inline constexpr const char* kProgressSql =
    "SELECT COALESCE(SUM(CASE WHEN state IN ('succeeded', 'failed', 'canceled') THEN 1 ELSE 0 END), 0), COUNT(*), "
    "COALESCE(SUM(CASE WHEN state = 'succeeded' THEN artifact_bytes ELSE 0 END), 0) FROM job_outputs WHERE job_id = $1";
// "SELECT <the columns output_of_row reads> FROM job_outputs WHERE job_id = $1 AND idx = $2".
const std::string& select_output_sql();

std::string state_event_data(JobState state, const std::string& error_code, const std::string& error_message);
std::string output_event_data(const JobOutput& o);
std::string artifact_event_data(const std::string& job_id, const JobOutput& o);
std::string progress_event_data(int64_t done, int64_t total, int64_t artifact_bytes);

// A job's state and error: a state event's data.
inline constexpr const char* kJobStateSql = "SELECT state, error_code, error_message FROM jobs WHERE id = $1";

template <class Row>
JobEvent event_of_row(const Row& r) {
    return {.seq = r.i64(0), .type = stored_job_event_type(r.text(1)), .data_json = r.text(2), .time_ms = r.i64(3)};
}

// Appends the events of output `index` having changed (in the caller's
// transaction): the output itself, its artifact once it succeeded, then the
// job's progress. `store` reads the output's row (output_row(id, index):
// optional<JobOutput>), the progress numbers (progress_row(id): three
// int64_t) and appends (append(id, type, data, now_ms)).
template <class Store>
void append_output_events(Store& store, const std::string& id, int index, int64_t now_ms) {
    const std::optional<JobOutput> o = store.output_row(id, index);
    if (!o) return;
    store.append(id, JobEventType::output, output_event_data(*o), now_ms);
    if (o->state == JobState::succeeded) store.append(id, JobEventType::artifact, artifact_event_data(id, *o), now_ms);
    const auto [done, total, bytes] = store.progress_row(id);
    store.append(id, JobEventType::progress, progress_event_data(done, total, bytes), now_ms);
}

}  // namespace nurbsrt::server
