#include "server/store/job_store_sqlite.h"

#include "core/check.h"

#include "server/store/job_store_sqlite_impl.h"

namespace nurbsrt::server {

using sqlite_store::kSchemaV3;
using sqlite_store::kSchemaVersion;

SqliteJobStore::SqliteJobStore(const std::string& db_path) : impl_(std::make_unique<Impl>()) {
    impl_->path = db_path;
    const int rc = sqlite3_open_v2(db_path.c_str(), &impl_->db,
                                   SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_NOMUTEX, nullptr);
    if (rc != SQLITE_OK) impl_->fail("cannot open");
    sqlite3_extended_result_codes(impl_->db, 1);
    // Several threads of this process share the connection (behind m_); the
    // timeout covers another process (a second server on the same data dir, the
    // sqlite3 shell) holding the lock for a moment.
    sqlite3_busy_timeout(impl_->db, 5000);
    try {
        // The first statement reads the file: a file that is not a database fails here.
        impl_->exec("PRAGMA journal_mode=WAL");
        // FULL: a commit (an accepted job, a finished output) survives a power
        // loss too, not only a crash of the process; commits are few per job.
        impl_->exec("PRAGMA synchronous=FULL");
        impl_->exec("PRAGMA foreign_keys=ON");
        impl_->exec("CREATE TABLE IF NOT EXISTS schema_version (version INTEGER NOT NULL)");
        int version = 0;
        {
            Impl::Stmt s(*impl_, "SELECT MAX(version) FROM schema_version");
            if (s.step()) version = static_cast<int>(s.i64(0));
        }
        if (version > kSchemaVersion)
            throw Error(ErrorCode::io, "job database " + db_path + " has schema version " + std::to_string(version) +
                                           ", newer than this nurbsrt's " + std::to_string(kSchemaVersion));
        if (version < kSchemaVersion) {
            Impl::Transaction t(*impl_);
            if (version < 1) impl_->exec(job_schema_v1(SqlDialect::sqlite).c_str());
            if (version < 2) impl_->exec(job_schema_v2(SqlDialect::sqlite).c_str());
            if (version < 3) impl_->exec(kSchemaV3);
            if (version < 4) impl_->exec(job_schema_events(SqlDialect::sqlite).c_str());
            impl_->exec("DELETE FROM schema_version");
            Impl::Stmt(*impl_, "INSERT INTO schema_version(version) VALUES (?)").bind(1, kSchemaVersion).run();
            t.commit();
        }
    } catch (const Error& e) {
        throw Error(ErrorCode::io, std::string(e.what()) + " (is it a nurbsrt job database, and writable?)");
    }
}

SqliteJobStore::~SqliteJobStore() = default;

std::string SqliteJobStore::describe() const { return "sqlite:" + impl_->path; }

std::unique_ptr<JobStore> open_sqlite_job_store(const std::string& db_path) {
    return std::make_unique<SqliteJobStore>(db_path);
}

void SqliteJobStore::create(JobRecord& job) {
    std::lock_guard<std::mutex> lock(m_);
    Impl::Transaction t(*impl_);
    {
        Impl::Stmt s(
            *impl_,
            "INSERT INTO jobs(id, state, created_ms, callback_url, callback_state) VALUES (?, 'queued', ?, ?, ?)");
        job.callback = {};
        if (!job.callback_url.empty()) job.callback.state = CallbackState::waiting;
        s.bind(1, job.id).bind(2, job.created_ms).bind(3, job.callback_url);
        s.bind(4, std::string(callback_state_name(job.callback.state))).run();
    }
    job.seq = sqlite3_last_insert_rowid(impl_->db);
    job.state = JobState::queued;
    for (const JobInput& in : job.inputs) {
        Impl::Stmt s(*impl_, "INSERT INTO job_inputs(job_id, idx, filename, format, bytes) VALUES (?, ?, ?, ?, ?)");
        s.bind(1, job.id).bind(2, in.index).bind(3, in.filename).bind(4, in.format).bind(5, in.bytes).run();
    }
    for (const JobOutput& o : job.outputs) {
        Impl::Stmt s(*impl_,
                     "INSERT INTO job_outputs(job_id, idx, file, kind, options, artifact, content_type, state) "
                     "VALUES (?, ?, ?, ?, ?, ?, ?, 'queued')");
        s.bind(1, job.id)
            .bind(2, o.index)
            .bind(3, o.file)
            .bind(4, std::string(output_kind_name(o.kind)))
            .bind(5, o.options_json);
        s.bind(6, o.artifact).bind(7, o.content_type).run();
    }
    impl_->append_state(job.id, job.created_ms);
    t.commit();
}

std::optional<JobRecord> SqliteJobStore::get(const std::string& id) {
    std::lock_guard<std::mutex> lock(m_);
    return impl_->get(id);
}

bool SqliteJobStore::exists(const std::string& id) {
    std::lock_guard<std::mutex> lock(m_);
    Impl::Stmt s(*impl_, "SELECT 1 FROM jobs WHERE id = ?");
    s.bind(1, id);
    return s.step();
}

JobPage SqliteJobStore::list(const std::optional<JobState>& state, bool newest_first, int limit,
                             std::optional<int64_t> after_seq) {
    std::lock_guard<std::mutex> lock(m_);
    // One more than asked tells whether a next page exists.
    const std::string sql = sqlite_store::select_jobs() +
                            (newest_first ? "WHERE (?1 = '' OR state = ?1) AND seq < ?2 ORDER BY seq DESC LIMIT ?3"
                                          : "WHERE (?1 = '' OR state = ?1) AND seq > ?2 ORDER BY seq ASC LIMIT ?3");
    JobPage page;
    {
        Impl::Stmt s(*impl_, sql.c_str());
        s.bind(1, std::string(state ? job_state_name(*state) : ""));
        s.bind(2, after_seq.value_or(newest_first ? INT64_MAX : 0));
        s.bind(3, static_cast<int64_t>(limit) + 1);
        while (s.step()) page.jobs.push_back(job_of_row(s));
    }
    if (page.jobs.size() > static_cast<size_t>(limit)) {
        page.jobs.resize(static_cast<size_t>(limit));
        page.next_after = page.jobs.back().seq;
    }
    for (JobRecord& j : page.jobs) impl_->load_children(j);
    return page;
}

std::map<JobState, int64_t> SqliteJobStore::count_by_state() {
    std::lock_guard<std::mutex> lock(m_);
    std::map<JobState, int64_t> counts;
    for (JobState s : kJobStates) counts[s] = 0;
    Impl::Stmt s(*impl_, "SELECT state, COUNT(*) FROM jobs GROUP BY state");
    while (s.step()) counts[stored_job_state(s.text(0))] = s.i64(1);
    return counts;
}

int64_t SqliteJobStore::artifact_bytes() {
    std::lock_guard<std::mutex> lock(m_);
    Impl::Stmt s(*impl_, "SELECT COALESCE(SUM(artifact_bytes), 0) FROM job_outputs WHERE state = 'succeeded'");
    return s.step() ? s.i64(0) : 0;
}

std::optional<JobClaim> SqliteJobStore::claim_next(int64_t now_ms, int) {
    std::lock_guard<std::mutex> lock(m_);
    Impl::Transaction t(*impl_);
    std::string id;
    {
        Impl::Stmt s(*impl_, "SELECT id FROM jobs WHERE state = 'queued' ORDER BY seq LIMIT 1");
        if (!s.step()) return std::nullopt;
        id = s.text(0);
    }
    {
        Impl::Stmt s(*impl_,
                     "UPDATE jobs SET state = 'running', attempts = attempts + 1, "
                     "started_ms = CASE WHEN started_ms = 0 THEN ?2 ELSE started_ms END WHERE id = ?1");
        s.bind(1, id).bind(2, now_ms).run();
    }
    impl_->append_state(id, now_ms);
    std::optional<JobClaim> claim;
    if (auto job = impl_->get(id)) {
        claim.emplace();
        static_cast<JobRecord&>(*claim) = std::move(*job);
        for (const JobOutput& o : claim->outputs)
            if (o.state == JobState::queued) claim->run.push_back(o.index);
    }
    t.commit();
    return claim;
}

bool SqliteJobStore::output_running(const std::string& id, int output, int64_t now_ms, const std::string&) {
    std::lock_guard<std::mutex> lock(m_);
    Impl::Transaction t(*impl_);
    Impl::Stmt s(*impl_,
                 "UPDATE job_outputs SET state = 'running', progress = 0, started_ms = ?, attempts = attempts + 1 "
                 "WHERE job_id = ? AND idx = ? AND state = 'queued'");
    s.bind(1, now_ms).bind(2, id).bind(3, output).run();
    NURBSRT_CHECK(s.changes() <= 1);  // (job_id, idx) is the key
    const bool ok = s.changes() > 0;
    if (ok) append_output_events(*impl_, id, output, now_ms);
    t.commit();
    return ok;
}

bool SqliteJobStore::output_progress(const std::string& id, int output, double progress, const std::string&) {
    std::lock_guard<std::mutex> lock(m_);
    Impl::Stmt s(*impl_, "UPDATE job_outputs SET progress = ? WHERE job_id = ? AND idx = ? AND state = 'running'");
    s.bind(1, progress).bind(2, id).bind(3, output).run();  // one statement: its own transaction
    return s.changes() > 0;
}

bool SqliteJobStore::output_succeeded(const std::string& id, int output, int64_t artifact_bytes,
                                      const std::string& result_json, int64_t now_ms, const std::string&) {
    std::lock_guard<std::mutex> lock(m_);
    return impl_->update_output(
        "UPDATE job_outputs SET state = 'succeeded', progress = 1, artifact_bytes = ?, result = ?, "
        "finished_ms = ? WHERE job_id = ? AND idx = ? AND state = 'running'",
        id, output, now_ms, artifact_bytes, result_json, now_ms);
}

bool SqliteJobStore::output_failed(const std::string& id, int output, const std::string& code,
                                   const std::string& message, int64_t now_ms, const std::string&) {
    std::lock_guard<std::mutex> lock(m_);
    return impl_->update_output(
        "UPDATE job_outputs SET state = 'failed', error_code = ?, error_message = ?, finished_ms = ? "
        "WHERE job_id = ? AND idx = ? AND state IN ('queued', 'running')",
        id, output, now_ms, code, message, now_ms);
}

std::optional<JobState> SqliteJobStore::finish(const std::string& id, int64_t now_ms) {
    std::lock_guard<std::mutex> lock(m_);
    Impl::Transaction t(*impl_);
    if (!impl_->job_running(id)) return std::nullopt;
    const JobState state = impl_->finish_job(id, now_ms);
    t.commit();
    return state;
}

JobState SqliteJobStore::Impl::finish_job(const std::string& id, int64_t now_ms) {
    int64_t total = 0, failed = 0;
    std::string first_code, first_message;
    {
        Stmt s(*this, "SELECT state, error_code, error_message FROM job_outputs WHERE job_id = ? ORDER BY idx");
        s.bind(1, id);
        while (s.step()) {
            ++total;
            if (stored_job_state(s.text(0)) != JobState::succeeded) {
                if (++failed == 1) {
                    first_code = s.text(1).empty() ? "internal" : s.text(1);
                    first_message = s.text(2);
                }
            }
        }
    }
    NURBSRT_CHECK(total > 0);  // a job has outputs: with none it would "succeed" having made nothing
    const JobState state = failed ? JobState::failed : JobState::succeeded;
    std::string message;
    if (failed)
        message = std::to_string(failed) + " of " + std::to_string(total) + " outputs failed; first: " + first_message;
    Stmt s(*this,
           "UPDATE jobs SET state = ?, finished_ms = ?, error_code = ?, error_message = ?, " NURBSRT_SQLITE_CALLBACK_DUE
           " WHERE id = ?");
    s.bind(1, std::string(job_state_name(state)))
        .bind(2, now_ms)
        .bind(3, failed ? first_code : std::string())
        .bind(4, message)
        .bind(5, now_ms);
    s.bind(6, id).run();
    append_state(id, now_ms);
    return state;
}

void SqliteJobStore::requeue(const JobClaim& claim) { requeue(claim.id); }

void SqliteJobStore::requeue(const std::string& id) {
    std::lock_guard<std::mutex> lock(m_);
    Impl::Transaction t(*impl_);
    {
        Impl::Stmt s(*impl_,
                     "UPDATE jobs SET state = 'queued', attempts = MAX(attempts - 1, 0) WHERE id = ? AND "
                     "state = 'running'");
        s.bind(1, id).run();
        if (s.changes() > 0) impl_->append_state(id, unix_now_ms());
    }
    Impl::Stmt(*impl_,
               "UPDATE job_outputs SET state = 'queued', progress = 0, started_ms = 0, "
               "attempts = MAX(attempts - 1, 0) WHERE job_id = ? AND state = 'running'")
        .bind(1, id)
        .run();
    t.commit();
}

std::optional<std::vector<JobEvent>> SqliteJobStore::events(const std::string& id, int64_t after_seq, int limit) {
    std::lock_guard<std::mutex> lock(m_);
    std::vector<JobEvent> events;
    {
        Impl::Stmt s(*impl_, kSelectEventsSql);
        s.bind(1, id).bind(2, after_seq).bind(3, limit);
        while (s.step()) events.push_back(event_of_row(s));
    }
    if (events.empty()) {  // none: is the job there at all? (its events go with it)
        Impl::Stmt s(*impl_, "SELECT 1 FROM jobs WHERE id = ?");
        s.bind(1, id);
        if (!s.step()) return std::nullopt;
    }
    return events;
}

}  // namespace nurbsrt::server
