// The job tables as both job stores (SQLite, PostgreSQL) define and read them:
// one definition of the tables, of the columns a read selects and of how a row
// becomes a record. The dialects differ only in column types and in the lease
// columns of job_outputs, which PostgreSQL's instances share and SQLite's one
// process does not need.
#pragma once

#include <string>

#include "server/store/job_store.h"

namespace nurbsrt::server {

enum class SqlDialect { sqlite, postgres };

// Schema version 1 (jobs, job_inputs, job_outputs) and version 2 (the webhook
// columns of jobs) in `dialect`, as the migrations apply them.
std::string job_schema_v1(SqlDialect dialect);
std::string job_schema_v2(SqlDialect dialect);

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

}  // namespace nurbsrt::server
