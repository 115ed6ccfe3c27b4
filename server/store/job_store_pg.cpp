// The PostgreSQL job store: connection, schema and its version, submission,
// reads, deletion and the retention query. Claims, leases and output
// transitions are in job_store_pg_work.cpp.
#include "server/store/job_store_pg.h"

#include "core/error.h"
#include "server/store/job_schema.h"

namespace nurbsrt::server {
namespace {

// 1: jobs, inputs, outputs (with the leases); 2: the webhook columns of jobs;
// 3: events (all job_schema.h).
constexpr int kPgSchemaVersion = 3;
// Any constant: instances starting together migrate one after the other.
constexpr const char* kMigrationLock = "7353021";

// "SELECT <the columns job_of_row reads> FROM jobs <where>".
std::string jobs_query(const char* where) { return std::string("SELECT ") + kJobColumns + " FROM jobs " + where; }

}  // namespace

bool is_postgres_url(const std::string& spec) {
    return spec.rfind("postgresql://", 0) == 0 || spec.rfind("postgres://", 0) == 0;
}

std::unique_ptr<JobStore> open_postgres_job_store(const std::string& url, const std::string& instance, double lease_s) {
    return std::make_unique<PgJobStore>(url, instance, lease_s);
}

PgJobStore::PgJobStore(const std::string& url, std::string instance, double lease_s)
    : conn_(std::make_unique<PgConn>(url)),
      instance_(std::move(instance)),
      lease_ms_(static_cast<int64_t>(lease_s * 1000)) {
    migrate();
}

PgJobStore::~PgJobStore() = default;

void PgJobStore::migrate() {
    PgConn::Transaction t(*conn_);
    conn_->exec("SELECT pg_advisory_xact_lock($1)", {kMigrationLock});
    conn_->exec("CREATE TABLE IF NOT EXISTS schema_version (version INTEGER NOT NULL)");
    const PgResult r = conn_->exec("SELECT COALESCE(MAX(version), 0) FROM schema_version");
    const int version = static_cast<int>(r.i64(0, 0));
    if (version > kPgSchemaVersion)
        throw Error(ErrorCode::io, "job store " + conn_->where() + " has schema version " + std::to_string(version) +
                                       ", newer than this nurbsrt's " + std::to_string(kPgSchemaVersion) +
                                       ": run the newer nurbsrt, or point --job-store at another database");
    if (version < kPgSchemaVersion) {
        if (version < 1) conn_->exec(job_schema_v1(SqlDialect::postgres).c_str());
        if (version < 2) conn_->exec(job_schema_v2(SqlDialect::postgres).c_str());
        if (version < 3) conn_->exec(job_schema_events(SqlDialect::postgres).c_str());
        conn_->exec("DELETE FROM schema_version");
        conn_->exec("INSERT INTO schema_version(version) VALUES ($1)", {std::to_string(kPgSchemaVersion)});
    }
    t.commit();
}

void PgJobStore::create(JobRecord& job) {
    std::lock_guard<std::mutex> lock(m_);
    PgConn::Transaction t(*conn_);
    job.callback = {};
    if (!job.callback_url.empty()) job.callback.state = CallbackState::waiting;
    const PgResult r = conn_->exec(
        "INSERT INTO jobs(id, state, created_ms, callback_url, callback_state) VALUES ($1, 'queued', $2, $3, $4) "
        "RETURNING seq",
        {job.id, std::to_string(job.created_ms), job.callback_url, callback_state_name(job.callback.state)});
    job.seq = r.i64(0, 0);
    job.state = JobState::queued;
    for (const JobInput& in : job.inputs)
        conn_->exec("INSERT INTO job_inputs(job_id, idx, filename, format, bytes) VALUES ($1, $2, $3, $4, $5)",
                    {job.id, std::to_string(in.index), in.filename, in.format, std::to_string(in.bytes)});
    for (const JobOutput& o : job.outputs)
        conn_->exec(
            "INSERT INTO job_outputs(job_id, idx, file, kind, options, artifact, content_type, state) "
            "VALUES ($1, $2, $3, $4, $5, $6, $7, 'queued')",
            {job.id, std::to_string(o.index), std::to_string(o.file), output_kind_name(o.kind), o.options_json,
             o.artifact, o.content_type});
    append_state(job.id, job.created_ms);
    t.commit();
}

void PgJobStore::load_children(JobRecord& j) {
    const std::string inputs =
        std::string("SELECT ") + kInputColumns + " FROM job_inputs WHERE job_id = $1 ORDER BY idx";
    const PgResult in = conn_->exec(inputs.c_str(), {j.id});
    for (int i = 0; i < in.rows(); ++i) j.inputs.push_back(input_of_row(in.row(i)));
    const std::string outputs =
        std::string("SELECT ") + kOutputColumns + " FROM job_outputs WHERE job_id = $1 ORDER BY idx";
    const PgResult r = conn_->exec(outputs.c_str(), {j.id});
    for (int i = 0; i < r.rows(); ++i) j.outputs.push_back(output_of_row(r.row(i)));
}

std::optional<JobRecord> PgJobStore::read(const std::string& id) {
    const PgResult r = conn_->exec(jobs_query("WHERE id = $1").c_str(), {id});
    if (r.rows() == 0) return std::nullopt;
    JobRecord j = job_of_row(r.row(0));
    load_children(j);
    return j;
}

std::optional<JobRecord> PgJobStore::get(const std::string& id) {
    std::lock_guard<std::mutex> lock(m_);
    // One snapshot for the job and its outputs: a GET never sees half a transition.
    PgConn::Transaction t(*conn_);
    conn_->exec("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ");
    auto j = read(id);
    t.commit();
    return j;
}

bool PgJobStore::exists(const std::string& id) {
    std::lock_guard<std::mutex> lock(m_);
    return conn_->exec("SELECT 1 FROM jobs WHERE id = $1", {id}).rows() > 0;
}

JobPage PgJobStore::list(const std::optional<JobState>& state, bool newest_first, int limit,
                         std::optional<int64_t> after_seq) {
    std::lock_guard<std::mutex> lock(m_);
    const std::string sql =
        jobs_query(newest_first ? "WHERE ($1 = '' OR state = $1) AND seq < $2 ORDER BY seq DESC LIMIT $3"
                                : "WHERE ($1 = '' OR state = $1) AND seq > $2 ORDER BY seq ASC LIMIT $3");
    PgConn::Transaction t(*conn_);
    conn_->exec("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ");
    // One more than asked tells whether a next page exists.
    const PgResult r = conn_->exec(sql.c_str(), {state ? job_state_name(*state) : "",
                                                 std::to_string(after_seq.value_or(newest_first ? INT64_MAX : 0)),
                                                 std::to_string(static_cast<int64_t>(limit) + 1)});
    JobPage page;
    for (int i = 0; i < r.rows(); ++i) page.jobs.push_back(job_of_row(r.row(i)));
    if (page.jobs.size() > static_cast<size_t>(limit)) {
        page.jobs.resize(static_cast<size_t>(limit));
        page.next_after = page.jobs.back().seq;
    }
    for (JobRecord& j : page.jobs) load_children(j);
    t.commit();
    return page;
}

std::map<JobState, int64_t> PgJobStore::count_by_state() {
    std::lock_guard<std::mutex> lock(m_);
    std::map<JobState, int64_t> counts;
    for (JobState s : kJobStates) counts[s] = 0;
    const PgResult r = conn_->exec("SELECT state, COUNT(*) FROM jobs GROUP BY state");
    for (int i = 0; i < r.rows(); ++i) counts[stored_job_state(r.text(i, 0))] = r.i64(i, 1);
    return counts;
}

int64_t PgJobStore::artifact_bytes() {
    std::lock_guard<std::mutex> lock(m_);
    const PgResult r =
        conn_->exec("SELECT COALESCE(SUM(artifact_bytes), 0) FROM job_outputs WHERE state = 'succeeded'");
    return r.i64(0, 0);
}

void PgJobStore::lock_outputs(const std::string& id) {
    conn_->exec("SELECT 1 FROM job_outputs WHERE job_id = $1 ORDER BY idx FOR UPDATE", {id});
}

JobStore::DeleteOutcome PgJobStore::delete_job(const std::string& id, int64_t now_ms) {
    std::lock_guard<std::mutex> lock(m_);
    PgConn::Transaction t(*conn_);
    lock_outputs(id);
    const PgResult r = conn_->exec("SELECT state FROM jobs WHERE id = $1 FOR UPDATE", {id});
    if (r.rows() == 0) return DeleteOutcome::not_found;
    const JobState state = stored_job_state(r.text(0, 0));
    if (state == JobState::canceled) return DeleteOutcome::canceling;
    if (state == JobState::running) {
        // The runners see it at their next heartbeat (renew() fails), on whichever instance they are.
        conn_->exec(
            "UPDATE jobs SET state = 'canceled', finished_ms = $1, error_code = 'canceled', "
            "error_message = 'deleted while running; removed once its current step stops' WHERE id = $2",
            {std::to_string(now_ms), id});
        conn_->exec(
            "UPDATE job_outputs SET state = 'canceled', finished_ms = $1 WHERE job_id = $2 AND "
            "state IN ('queued', 'running')",
            {std::to_string(now_ms), id});
        append_state(id, now_ms);
        t.commit();
        return DeleteOutcome::canceling;
    }
    conn_->exec("DELETE FROM jobs WHERE id = $1", {id});  // inputs and outputs by ON DELETE CASCADE
    t.commit();
    return DeleteOutcome::removed;
}

bool PgJobStore::remove(const std::string& id) {
    std::lock_guard<std::mutex> lock(m_);
    PgConn::Transaction t(*conn_);
    lock_outputs(id);
    const bool removed = conn_->exec("DELETE FROM jobs WHERE id = $1", {id}).affected() > 0;
    t.commit();
    return removed;
}

bool PgJobStore::running(const std::string& id) {
    std::lock_guard<std::mutex> lock(m_);
    const PgResult r = conn_->exec("SELECT state FROM jobs WHERE id = $1", {id});
    return r.rows() > 0 && stored_job_state(r.text(0, 0)) == JobState::running;
}

std::vector<std::string> PgJobStore::finished_before(int64_t before_ms) {
    std::lock_guard<std::mutex> lock(m_);
    // Canceled jobs are normally removed by their runner; one whose runners all
    // died (no lease alive any more) is removed here.
    const PgResult r = conn_->exec(
        "SELECT id FROM jobs j WHERE (state IN ('succeeded', 'failed') AND finished_ms < $1) OR "
        "(state = 'canceled' AND NOT EXISTS (SELECT 1 FROM job_outputs o WHERE o.job_id = j.id AND "
        "o.lease_token <> '' AND o.lease_expires_ms >= (extract(epoch FROM clock_timestamp()) * 1000)::bigint)) "
        "ORDER BY seq",
        {std::to_string(before_ms)});
    std::vector<std::string> ids;
    for (int i = 0; i < r.rows(); ++i) ids.push_back(r.text(i, 0));
    return ids;
}

std::vector<std::string> PgJobStore::all_ids() {
    std::lock_guard<std::mutex> lock(m_);
    const PgResult r = conn_->exec("SELECT id FROM jobs ORDER BY seq");
    std::vector<std::string> ids;
    for (int i = 0; i < r.rows(); ++i) ids.push_back(r.text(i, 0));
    return ids;
}

std::optional<JobRecord> PgJobStore::claim_callback(int64_t now_ms, int64_t hold_ms) {
    std::lock_guard<std::mutex> lock(m_);
    PgConn::Transaction t(*conn_);
    // SKIP LOCKED: instances polling at once each take a different delivery.
    const PgResult r = conn_->exec(
        "SELECT id FROM jobs WHERE callback_state = 'pending' AND callback_due_ms <= $1 "
        "ORDER BY callback_due_ms, seq LIMIT 1 FOR UPDATE SKIP LOCKED",
        {std::to_string(now_ms)});
    if (r.rows() == 0) return std::nullopt;
    const std::string id = r.text(0, 0);
    conn_->exec("UPDATE jobs SET callback_due_ms = $1 WHERE id = $2", {std::to_string(now_ms + hold_ms), id});
    auto job = read(id);
    t.commit();
    return job;
}

bool PgJobStore::callback_attempted(const std::string& id, const CallbackAttempt& a) {
    std::lock_guard<std::mutex> lock(m_);
    const bool done = a.state != CallbackState::pending;
    return conn_
               ->exec(
                   "UPDATE jobs SET callback_attempts = callback_attempts + 1, callback_state = $1, "
                   "callback_due_ms = $2, callback_status = $3, callback_error = $4, callback_done_ms = $5 "
                   "WHERE id = $6 AND callback_state = 'pending'",
                   {callback_state_name(a.state), std::to_string(done ? 0 : a.next_ms), std::to_string(a.status),
                    a.error, std::to_string(done ? a.now_ms : 0), id})
               .affected() > 0;
}

void PgJobStore::append(const std::string& id, JobEventType type, const std::string& data, int64_t now_ms) {
    const PgResult r = conn_->exec(kNextEventSeqSql, {id});
    if (r.rows() == 0) return;  // the job is gone
    conn_->exec(kInsertEventSql, {id, r.text(0, 0), job_event_type_name(type), data, std::to_string(now_ms)});
}

void PgJobStore::append_state(const std::string& id, int64_t now_ms) {
    const PgResult r = conn_->exec(kJobStateSql, {id});
    if (r.rows() == 0) return;
    append(id, JobEventType::state, state_event_data(stored_job_state(r.text(0, 0)), r.text(0, 1), r.text(0, 2)),
           now_ms);
}

std::optional<JobOutput> PgJobStore::output_row(const std::string& id, int index) {
    const PgResult r = conn_->exec(select_output_sql().c_str(), {id, std::to_string(index)});
    if (r.rows() == 0) return std::nullopt;
    return output_of_row(r.row(0));
}

std::array<int64_t, 3> PgJobStore::progress_row(const std::string& id) {
    const PgResult r = conn_->exec(kProgressSql, {id});
    return {r.i64(0, 0), r.i64(0, 1), r.i64(0, 2)};
}

std::optional<std::vector<JobEvent>> PgJobStore::events(const std::string& id, int64_t after_seq, int limit) {
    std::lock_guard<std::mutex> lock(m_);
    // One statement while events come (every stream polls this); the job's
    // existence is asked only when none did: events go with their job.
    const PgResult r = conn_->exec(kSelectEventsSql, {id, std::to_string(after_seq), std::to_string(limit)});
    if (r.rows() == 0 && conn_->exec("SELECT 1 FROM jobs WHERE id = $1", {id}).rows() == 0) return std::nullopt;
    std::vector<JobEvent> events;
    for (int i = 0; i < r.rows(); ++i) events.push_back(event_of_row(r.row(i)));
    return events;
}

}  // namespace nurbsrt::server
