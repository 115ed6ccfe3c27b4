#include "server/job_store.h"

#include <sqlite3.h>

#include <unordered_map>

#include "renderer/error.h"

namespace nurbsrt::server {
namespace {

constexpr int kSchemaVersion = 1;

const char* kSchema = R"sql(
CREATE TABLE IF NOT EXISTS jobs (
  seq INTEGER PRIMARY KEY AUTOINCREMENT,
  id TEXT NOT NULL UNIQUE,
  state TEXT NOT NULL,
  created_ms INTEGER NOT NULL,
  started_ms INTEGER NOT NULL DEFAULT 0,
  finished_ms INTEGER NOT NULL DEFAULT 0,
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
  bytes INTEGER NOT NULL,
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
  progress REAL NOT NULL DEFAULT 0,
  error_code TEXT NOT NULL DEFAULT '',
  error_message TEXT NOT NULL DEFAULT '',
  artifact_bytes INTEGER NOT NULL DEFAULT 0,
  started_ms INTEGER NOT NULL DEFAULT 0,
  finished_ms INTEGER NOT NULL DEFAULT 0,
  result TEXT NOT NULL DEFAULT '',
  PRIMARY KEY (job_id, idx)
);
)sql";

}  // namespace

bool is_finished_state(const std::string& s) { return s == "succeeded" || s == "failed" || s == "canceled"; }

struct JobStore::Impl {
    sqlite3* db = nullptr;
    std::string path;
    std::unordered_map<std::string, sqlite3_stmt*> statements;

    ~Impl() {
        for (auto& [sql, st] : statements) sqlite3_finalize(st);
        if (db) sqlite3_close(db);
    }

    [[noreturn]] void fail(const std::string& what) const {
        throw Error(ErrorCode::io, "job database " + path + ": " + what + ": " + (db ? sqlite3_errmsg(db) : "?"));
    }

    void exec(const char* sql) {
        char* msg = nullptr;
        if (sqlite3_exec(db, sql, nullptr, nullptr, &msg) != SQLITE_OK) {
            const std::string m = msg ? msg : "?";
            sqlite3_free(msg);
            throw Error(ErrorCode::io, "job database " + path + ": " + m);
        }
    }

    // A prepared statement, compiled once and reused (reset on every use).
    class Stmt {
    public:
        Stmt(Impl& impl, const char* sql) : impl_(impl) {
            auto it = impl.statements.find(sql);
            if (it == impl.statements.end()) {
                sqlite3_stmt* st = nullptr;
                if (sqlite3_prepare_v3(impl.db, sql, -1, SQLITE_PREPARE_PERSISTENT, &st, nullptr) != SQLITE_OK)
                    impl.fail(std::string("cannot prepare statement"));
                it = impl.statements.emplace(sql, st).first;
            }
            st_ = it->second;
        }
        ~Stmt() {
            sqlite3_reset(st_);
            sqlite3_clear_bindings(st_);
        }
        Stmt& bind(int i, const std::string& v) {
            sqlite3_bind_text(st_, i, v.data(), static_cast<int>(v.size()), SQLITE_TRANSIENT);
            return *this;
        }
        Stmt& bind(int i, int64_t v) {
            sqlite3_bind_int64(st_, i, v);
            return *this;
        }
        Stmt& bind(int i, int v) { return bind(i, static_cast<int64_t>(v)); }
        Stmt& bind(int i, double v) {
            sqlite3_bind_double(st_, i, v);
            return *this;
        }
        // True while a row is available.
        bool step() {
            const int rc = sqlite3_step(st_);
            if (rc == SQLITE_ROW) return true;
            if (rc == SQLITE_DONE) return false;
            impl_.fail("statement failed");
        }
        void run() {
            while (step()) {
            }
        }
        int64_t i64(int c) const { return sqlite3_column_int64(st_, c); }
        double real(int c) const { return sqlite3_column_double(st_, c); }
        std::string text(int c) const {
            const auto* p = reinterpret_cast<const char*>(sqlite3_column_text(st_, c));
            return p ? std::string(p, static_cast<size_t>(sqlite3_column_bytes(st_, c))) : std::string();
        }
        int changes() const { return sqlite3_changes(impl_.db); }

    private:
        Impl& impl_;
        sqlite3_stmt* st_ = nullptr;
    };

    // Every state change is one transaction: committed at the end of the scope,
    // rolled back when it is left by an exception.
    class Transaction {
    public:
        explicit Transaction(Impl& impl) : impl_(impl) { impl_.exec("BEGIN IMMEDIATE"); }
        ~Transaction() {
            if (!done_) sqlite3_exec(impl_.db, "ROLLBACK", nullptr, nullptr, nullptr);
        }
        void commit() {
            impl_.exec("COMMIT");
            done_ = true;
        }

    private:
        Impl& impl_;
        bool done_ = false;
    };

    JobRecord read_job(Stmt& s) {
        JobRecord j;
        j.seq = s.i64(0);
        j.id = s.text(1);
        j.state = s.text(2);
        j.created_ms = s.i64(3);
        j.started_ms = s.i64(4);
        j.finished_ms = s.i64(5);
        j.attempts = static_cast<int>(s.i64(6));
        j.error_code = s.text(7);
        j.error_message = s.text(8);
        return j;
    }

    void load_children(JobRecord& j) {
        {
            Stmt s(*this, "SELECT idx, filename, format, bytes FROM job_inputs WHERE job_id = ? ORDER BY idx");
            s.bind(1, j.id);
            while (s.step()) j.inputs.push_back({static_cast<int>(s.i64(0)), s.text(1), s.text(2), s.i64(3)});
        }
        Stmt s(*this,
               "SELECT idx, file, kind, options, artifact, content_type, state, progress, error_code, error_message, "
               "artifact_bytes, started_ms, finished_ms, result FROM job_outputs WHERE job_id = ? ORDER BY idx");
        s.bind(1, j.id);
        while (s.step()) {
            JobOutput o;
            o.index = static_cast<int>(s.i64(0));
            o.file = static_cast<int>(s.i64(1));
            o.kind = s.text(2);
            o.options_json = s.text(3);
            o.artifact = s.text(4);
            o.content_type = s.text(5);
            o.state = s.text(6);
            o.progress = s.real(7);
            o.error_code = s.text(8);
            o.error_message = s.text(9);
            o.artifact_bytes = s.i64(10);
            o.started_ms = s.i64(11);
            o.finished_ms = s.i64(12);
            o.result_json = s.text(13);
            j.outputs.push_back(std::move(o));
        }
    }

    std::optional<JobRecord> get(const std::string& id) {
        std::optional<JobRecord> j;
        {
            Stmt s(*this,
                   "SELECT seq, id, state, created_ms, started_ms, finished_ms, attempts, error_code, "
                   "error_message FROM jobs WHERE id = ?");
            s.bind(1, id);
            if (s.step()) j = read_job(s);
        }
        if (j) load_children(*j);
        return j;
    }

    void remove_rows(const std::string& id);

    bool job_running(const std::string& id) {
        Stmt s(*this, "SELECT state FROM jobs WHERE id = ?");
        s.bind(1, id);
        return s.step() && s.text(0) == "running";
    }
};

JobStore::JobStore(const std::string& db_path) : impl_(std::make_unique<Impl>()) {
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
            impl_->exec(kSchema);
            impl_->exec("DELETE FROM schema_version");
            Impl::Stmt(*impl_, "INSERT INTO schema_version(version) VALUES (?)").bind(1, kSchemaVersion).run();
            t.commit();
        }
    } catch (const Error& e) {
        throw Error(ErrorCode::io, std::string(e.what()) + " (is it a nurbsrt job database, and writable?)");
    }
}

JobStore::~JobStore() = default;

void JobStore::create(JobRecord& job) {
    std::lock_guard<std::mutex> lock(m_);
    Impl::Transaction t(*impl_);
    {
        Impl::Stmt s(*impl_, "INSERT INTO jobs(id, state, created_ms) VALUES (?, 'queued', ?)");
        s.bind(1, job.id).bind(2, job.created_ms).run();
    }
    job.seq = sqlite3_last_insert_rowid(impl_->db);
    job.state = "queued";
    for (const JobInput& in : job.inputs) {
        Impl::Stmt s(*impl_, "INSERT INTO job_inputs(job_id, idx, filename, format, bytes) VALUES (?, ?, ?, ?, ?)");
        s.bind(1, job.id).bind(2, in.index).bind(3, in.filename).bind(4, in.format).bind(5, in.bytes).run();
    }
    for (const JobOutput& o : job.outputs) {
        Impl::Stmt s(*impl_,
                     "INSERT INTO job_outputs(job_id, idx, file, kind, options, artifact, content_type, state) "
                     "VALUES (?, ?, ?, ?, ?, ?, ?, 'queued')");
        s.bind(1, job.id).bind(2, o.index).bind(3, o.file).bind(4, o.kind).bind(5, o.options_json);
        s.bind(6, o.artifact).bind(7, o.content_type).run();
    }
    t.commit();
}

std::optional<JobRecord> JobStore::get(const std::string& id) {
    std::lock_guard<std::mutex> lock(m_);
    return impl_->get(id);
}

bool JobStore::exists(const std::string& id) {
    std::lock_guard<std::mutex> lock(m_);
    Impl::Stmt s(*impl_, "SELECT 1 FROM jobs WHERE id = ?");
    s.bind(1, id);
    return s.step();
}

JobPage JobStore::list(const std::optional<std::string>& state, bool newest_first, int limit,
                       std::optional<int64_t> after_seq) {
    std::lock_guard<std::mutex> lock(m_);
    // One more than asked tells whether a next page exists.
    const char* sql = newest_first
                          ? "SELECT seq, id, state, created_ms, started_ms, finished_ms, attempts, error_code, "
                            "error_message FROM jobs WHERE (?1 = '' OR state = ?1) AND seq < ?2 ORDER BY seq DESC "
                            "LIMIT ?3"
                          : "SELECT seq, id, state, created_ms, started_ms, finished_ms, attempts, error_code, "
                            "error_message FROM jobs WHERE (?1 = '' OR state = ?1) AND seq > ?2 ORDER BY seq ASC "
                            "LIMIT ?3";
    JobPage page;
    {
        Impl::Stmt s(*impl_, sql);
        s.bind(1, state.value_or(""));
        s.bind(2, after_seq.value_or(newest_first ? INT64_MAX : 0));
        s.bind(3, static_cast<int64_t>(limit) + 1);
        while (s.step()) page.jobs.push_back(impl_->read_job(s));
    }
    if (page.jobs.size() > static_cast<size_t>(limit)) {
        page.jobs.resize(static_cast<size_t>(limit));
        page.next_after = page.jobs.back().seq;
    }
    for (JobRecord& j : page.jobs) impl_->load_children(j);
    return page;
}

std::map<std::string, int64_t> JobStore::count_by_state() {
    std::lock_guard<std::mutex> lock(m_);
    std::map<std::string, int64_t> counts;
    for (const char* s : kJobStates) counts[s] = 0;
    Impl::Stmt s(*impl_, "SELECT state, COUNT(*) FROM jobs GROUP BY state");
    while (s.step()) counts[s.text(0)] = s.i64(1);
    return counts;
}

std::optional<JobRecord> JobStore::claim_next(int64_t now_ms) {
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
    auto job = impl_->get(id);
    t.commit();
    return job;
}

bool JobStore::output_running(const std::string& id, int output, int64_t now_ms) {
    std::lock_guard<std::mutex> lock(m_);
    Impl::Transaction t(*impl_);
    Impl::Stmt s(*impl_,
                 "UPDATE job_outputs SET state = 'running', progress = 0, started_ms = ? "
                 "WHERE job_id = ? AND idx = ? AND state = 'queued'");
    s.bind(1, now_ms).bind(2, id).bind(3, output).run();
    const bool ok = s.changes() > 0;
    t.commit();
    return ok;
}

bool JobStore::output_progress(const std::string& id, int output, double progress) {
    std::lock_guard<std::mutex> lock(m_);
    Impl::Stmt s(*impl_, "UPDATE job_outputs SET progress = ? WHERE job_id = ? AND idx = ? AND state = 'running'");
    s.bind(1, progress).bind(2, id).bind(3, output).run();  // one statement: its own transaction
    return s.changes() > 0;
}

bool JobStore::output_succeeded(const std::string& id, int output, int64_t artifact_bytes,
                                const std::string& result_json, int64_t now_ms) {
    std::lock_guard<std::mutex> lock(m_);
    Impl::Transaction t(*impl_);
    Impl::Stmt s(*impl_,
                 "UPDATE job_outputs SET state = 'succeeded', progress = 1, artifact_bytes = ?, result = ?, "
                 "finished_ms = ? WHERE job_id = ? AND idx = ? AND state = 'running'");
    s.bind(1, artifact_bytes).bind(2, result_json).bind(3, now_ms).bind(4, id).bind(5, output).run();
    const bool ok = s.changes() > 0;
    t.commit();
    return ok;
}

bool JobStore::output_failed(const std::string& id, int output, const std::string& code, const std::string& message,
                             int64_t now_ms) {
    std::lock_guard<std::mutex> lock(m_);
    Impl::Transaction t(*impl_);
    Impl::Stmt s(*impl_,
                 "UPDATE job_outputs SET state = 'failed', error_code = ?, error_message = ?, finished_ms = ? "
                 "WHERE job_id = ? AND idx = ? AND state IN ('queued', 'running')");
    s.bind(1, code).bind(2, message).bind(3, now_ms).bind(4, id).bind(5, output).run();
    const bool ok = s.changes() > 0;
    t.commit();
    return ok;
}

std::optional<std::string> JobStore::finish(const std::string& id, int64_t now_ms) {
    std::lock_guard<std::mutex> lock(m_);
    Impl::Transaction t(*impl_);
    if (!impl_->job_running(id)) return std::nullopt;
    int64_t total = 0, failed = 0;
    std::string first_code, first_message;
    {
        Impl::Stmt s(*impl_, "SELECT state, error_code, error_message FROM job_outputs WHERE job_id = ? ORDER BY idx");
        s.bind(1, id);
        while (s.step()) {
            ++total;
            if (s.text(0) != "succeeded") {
                if (++failed == 1) {
                    first_code = s.text(1).empty() ? "internal" : s.text(1);
                    first_message = s.text(2);
                }
            }
        }
    }
    const std::string state = failed ? "failed" : "succeeded";
    std::string message;
    if (failed)
        message = std::to_string(failed) + " of " + std::to_string(total) + " outputs failed; first: " + first_message;
    Impl::Stmt s(*impl_, "UPDATE jobs SET state = ?, finished_ms = ?, error_code = ?, error_message = ? WHERE id = ?");
    s.bind(1, state).bind(2, now_ms).bind(3, failed ? first_code : std::string()).bind(4, message).bind(5, id).run();
    t.commit();
    return state;
}

void JobStore::requeue(const std::string& id) {
    std::lock_guard<std::mutex> lock(m_);
    Impl::Transaction t(*impl_);
    Impl::Stmt(*impl_,
               "UPDATE jobs SET state = 'queued', attempts = MAX(attempts - 1, 0) WHERE id = ? AND "
               "state = 'running'")
        .bind(1, id)
        .run();
    Impl::Stmt(*impl_,
               "UPDATE job_outputs SET state = 'queued', progress = 0, started_ms = 0 WHERE job_id = ? AND "
               "state = 'running'")
        .bind(1, id)
        .run();
    t.commit();
}

void JobStore::Impl::remove_rows(const std::string& id) {
    Stmt(*this, "DELETE FROM job_outputs WHERE job_id = ?").bind(1, id).run();
    Stmt(*this, "DELETE FROM job_inputs WHERE job_id = ?").bind(1, id).run();
    Stmt(*this, "DELETE FROM jobs WHERE id = ?").bind(1, id).run();
}

JobStore::DeleteOutcome JobStore::delete_job(const std::string& id, int64_t now_ms) {
    std::lock_guard<std::mutex> lock(m_);
    Impl::Transaction t(*impl_);
    std::string state;
    {
        Impl::Stmt s(*impl_, "SELECT state FROM jobs WHERE id = ?");
        s.bind(1, id);
        if (!s.step()) return DeleteOutcome::not_found;
        state = s.text(0);
    }
    if (state == "canceled") return DeleteOutcome::canceling;
    if (state == "running") {
        Impl::Stmt(*impl_,
                   "UPDATE jobs SET state = 'canceled', finished_ms = ?, error_code = 'canceled', "
                   "error_message = 'deleted while running; removed once its current step stops' "
                   "WHERE id = ?")
            .bind(1, now_ms)
            .bind(2, id)
            .run();
        Impl::Stmt(*impl_,
                   "UPDATE job_outputs SET state = 'canceled', finished_ms = ? WHERE job_id = ? AND "
                   "state IN ('queued', 'running')")
            .bind(1, now_ms)
            .bind(2, id)
            .run();
        t.commit();
        return DeleteOutcome::canceling;
    }
    impl_->remove_rows(id);
    t.commit();
    return DeleteOutcome::removed;
}

bool JobStore::remove(const std::string& id) {
    std::lock_guard<std::mutex> lock(m_);
    Impl::Transaction t(*impl_);
    impl_->remove_rows(id);
    const int n = sqlite3_changes(impl_->db);
    t.commit();
    return n > 0;
}

bool JobStore::running(const std::string& id) {
    std::lock_guard<std::mutex> lock(m_);
    return impl_->job_running(id);
}

RecoveryReport JobStore::recover(int max_attempts, int64_t now_ms) {
    std::lock_guard<std::mutex> lock(m_);
    Impl::Transaction t(*impl_);
    RecoveryReport r;
    {
        Impl::Stmt s(*impl_, "SELECT id, attempts FROM jobs WHERE state = 'running' ORDER BY seq");
        while (s.step()) (s.i64(1) >= max_attempts ? r.failed : r.requeued).push_back(s.text(0));
    }
    {
        Impl::Stmt s(*impl_, "SELECT id FROM jobs WHERE state = 'canceled' ORDER BY seq");
        while (s.step()) r.removed.push_back(s.text(0));
    }
    for (const std::string& id : r.removed) impl_->remove_rows(id);
    const std::string reason = "interrupted by a service restart (" + std::to_string(max_attempts) + " attempts)";
    for (const std::string& id : r.requeued) {
        Impl::Stmt(*impl_, "UPDATE jobs SET state = 'queued' WHERE id = ?").bind(1, id).run();
        Impl::Stmt(*impl_,
                   "UPDATE job_outputs SET state = 'queued', progress = 0, started_ms = 0 "
                   "WHERE job_id = ? AND state = 'running'")
            .bind(1, id)
            .run();
    }
    for (const std::string& id : r.failed) {
        Impl::Stmt(*impl_,
                   "UPDATE jobs SET state = 'failed', finished_ms = ?, error_code = 'interrupted', "
                   "error_message = ? WHERE id = ?")
            .bind(1, now_ms)
            .bind(2, reason)
            .bind(3, id)
            .run();
        Impl::Stmt(*impl_,
                   "UPDATE job_outputs SET state = 'failed', finished_ms = ?, error_code = 'interrupted', "
                   "error_message = ? WHERE job_id = ? AND state IN ('queued', 'running')")
            .bind(1, now_ms)
            .bind(2, reason)
            .bind(3, id)
            .run();
    }
    t.commit();
    return r;
}

std::vector<std::string> JobStore::finished_before(int64_t before_ms) {
    std::lock_guard<std::mutex> lock(m_);
    std::vector<std::string> ids;
    Impl::Stmt s(*impl_,
                 "SELECT id FROM jobs WHERE state IN ('succeeded', 'failed') AND finished_ms < ? "
                 "ORDER BY seq");
    s.bind(1, before_ms);
    while (s.step()) ids.push_back(s.text(0));
    return ids;
}

std::vector<std::string> JobStore::all_ids() {
    std::lock_guard<std::mutex> lock(m_);
    std::vector<std::string> ids;
    Impl::Stmt s(*impl_, "SELECT id FROM jobs ORDER BY seq");
    while (s.step()) ids.push_back(s.text(0));
    return ids;
}

}  // namespace nurbsrt::server
