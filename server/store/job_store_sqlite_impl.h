// Internal to the SQLite job store (job_store_sqlite.cpp and
// job_store_sqlite_admin.cpp): the schema, the connection with its prepared
// statements and transactions. Includes sqlite3.h: include nowhere else.
#pragma once

#include <sqlite3.h>

#include <string>
#include <unordered_map>

#include "core/error.h"
#include "server/store/job_store_sqlite.h"

namespace nurbsrt::server {
namespace sqlite_store {

// 1: jobs, inputs, outputs. 2: the webhook columns of jobs.
inline constexpr int kSchemaVersion = 3;

inline constexpr const char* kSchema = R"sql(
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

// Version 2: a job's callback URL and its delivery (server/jobs/webhooks.h).
inline constexpr const char* kSchemaV2 = R"sql(
ALTER TABLE jobs ADD COLUMN callback_url TEXT NOT NULL DEFAULT '';
ALTER TABLE jobs ADD COLUMN callback_state TEXT NOT NULL DEFAULT '';
ALTER TABLE jobs ADD COLUMN callback_attempts INTEGER NOT NULL DEFAULT 0;
ALTER TABLE jobs ADD COLUMN callback_due_ms INTEGER NOT NULL DEFAULT 0;
ALTER TABLE jobs ADD COLUMN callback_status INTEGER NOT NULL DEFAULT 0;
ALTER TABLE jobs ADD COLUMN callback_error TEXT NOT NULL DEFAULT '';
ALTER TABLE jobs ADD COLUMN callback_done_ms INTEGER NOT NULL DEFAULT 0;
CREATE INDEX IF NOT EXISTS jobs_callback_due ON jobs(callback_state, callback_due_ms);
)sql";

// Version 3: runs started of each output, so that a crash counts against the
// output it cut short only (SqliteJobStore::recover).
inline constexpr const char* kSchemaV3 = R"sql(
ALTER TABLE job_outputs ADD COLUMN attempts INTEGER NOT NULL DEFAULT 0;
)sql";

// The columns read_job() reads, in its order.
#define NURBSRT_SQLITE_JOB_COLUMNS                                                                        \
    "seq, id, state, created_ms, started_ms, finished_ms, attempts, error_code, error_message, "          \
    "callback_url, callback_state, callback_attempts, callback_due_ms, callback_status, callback_error, " \
    "callback_done_ms"

// The SET clause that ends a job (succeeded or failed): its callback becomes
// due at the same time (the first parameter is the time).
#define NURBSRT_SQLITE_CALLBACK_DUE \
    "callback_state = CASE WHEN callback_url <> '' THEN 'pending' ELSE '' END, callback_due_ms = ?"

}  // namespace sqlite_store

struct SqliteJobStore::Impl {
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
            while (step()) {}
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
        j.state = stored_job_state(s.text(2));
        j.created_ms = s.i64(3);
        j.started_ms = s.i64(4);
        j.finished_ms = s.i64(5);
        j.attempts = static_cast<int>(s.i64(6));
        j.error_code = s.text(7);
        j.error_message = s.text(8);
        j.callback_url = s.text(9);
        j.callback.state = parse_callback_state(s.text(10));
        j.callback.attempts = static_cast<int>(s.i64(11));
        j.callback.due_ms = s.i64(12);
        j.callback.last_status = static_cast<int>(s.i64(13));
        j.callback.last_error = s.text(14);
        j.callback.done_ms = s.i64(15);
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
            o.kind = stored_output_kind(s.text(2));
            o.options_json = s.text(3);
            o.artifact = s.text(4);
            o.content_type = s.text(5);
            o.state = stored_job_state(s.text(6));
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
            Stmt s(*this, "SELECT " NURBSRT_SQLITE_JOB_COLUMNS " FROM jobs WHERE id = ?");
            s.bind(1, id);
            if (s.step()) j = read_job(s);
        }
        if (j) load_children(*j);
        return j;
    }

    void remove_rows(const std::string& id);

    // Ends a running job whose outputs are all finished (in the caller's
    // transaction); see JobStore::finish.
    JobState finish_job(const std::string& id, int64_t now_ms);

    bool job_running(const std::string& id) {
        Stmt s(*this, "SELECT state FROM jobs WHERE id = ?");
        s.bind(1, id);
        return s.step() && stored_job_state(s.text(0)) == JobState::running;
    }
};

}  // namespace nurbsrt::server
