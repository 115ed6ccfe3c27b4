// Internal to the SQLite job store (job_store_sqlite.cpp and
// job_store_sqlite_admin.cpp): the schema, the connection with its prepared
// statements and transactions. Includes sqlite3.h: include nowhere else.
#pragma once

#include <sqlite3.h>

#include <array>
#include <optional>
#include <string>
#include <unordered_map>

#include "core/check.h"
#include "core/error.h"
#include "server/store/job_schema.h"
#include "server/store/job_store_sqlite.h"

namespace nurbsrt::server {
namespace sqlite_store {

// 1: jobs, inputs, outputs; 2: the webhook columns of jobs (both job_schema.h);
// 3: the runs started of each output (below); 4: events (job_schema.h).
inline constexpr int kSchemaVersion = 4;

// Version 3: runs started of each output, so that a crash counts against the
// output it cut short only (SqliteJobStore::recover).
inline constexpr const char* kSchemaV3 = R"sql(
ALTER TABLE job_outputs ADD COLUMN attempts INTEGER NOT NULL DEFAULT 0;
)sql";

// "SELECT <the columns job_of_row reads> FROM jobs " (job_schema.h).
inline const std::string& select_jobs() {
    static const std::string sql = std::string("SELECT ") + kJobColumns + " FROM jobs ";
    return sql;
}

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

    void load_children(JobRecord& j) {
        {
            Stmt s(*this,
                   (std::string("SELECT ") + kInputColumns + " FROM job_inputs WHERE job_id = ? ORDER BY idx").c_str());
            s.bind(1, j.id);
            while (s.step()) j.inputs.push_back(input_of_row(s));
        }
        Stmt s(*this,
               (std::string("SELECT ") + kOutputColumns + " FROM job_outputs WHERE job_id = ? ORDER BY idx").c_str());
        s.bind(1, j.id);
        while (s.step()) j.outputs.push_back(output_of_row(s));
    }

    // Runs `sql`, an UPDATE of one output whose last two parameters are its key
    // (job id, index) after `values`, in a transaction with the events of the
    // change (job_schema.h); whether it changed it.
    template <class... Values>
    bool update_output(const char* sql, const std::string& id, int output, int64_t now_ms, const Values&... values) {
        Transaction t(*this);
        bool changed = false;
        {
            Stmt s(*this, sql);
            int k = 1;
            (s.bind(k++, values), ...);
            s.bind(k, id).bind(k + 1, output).run();
            NURBSRT_CHECK(s.changes() <= 1);  // (job_id, idx) is the key
            changed = s.changes() > 0;
        }
        if (changed) append_output_events(*this, id, output, now_ms);
        t.commit();
        return changed;
    }

    // Events (job_schema.h), in the caller's transaction.
    void append(const std::string& id, JobEventType type, const std::string& data, int64_t now_ms) {
        int64_t seq = 0;
        {
            Stmt s(*this, kNextEventSeqSql);
            s.bind(1, id);
            if (!s.step()) return;  // the job is gone
            seq = s.i64(0);
        }
        Stmt(*this, kInsertEventSql)
            .bind(1, id)
            .bind(2, seq)
            .bind(3, std::string(job_event_type_name(type)))
            .bind(4, data)
            .bind(5, now_ms)
            .run();
    }
    void append_state(const std::string& id, int64_t now_ms) {
        std::string data;
        {
            Stmt s(*this, kJobStateSql);
            s.bind(1, id);
            if (!s.step()) return;
            data = state_event_data(stored_job_state(s.text(0)), s.text(1), s.text(2));
        }
        append(id, JobEventType::state, data, now_ms);
    }
    std::optional<JobOutput> output_row(const std::string& id, int index) {
        Stmt s(*this, select_output_sql().c_str());
        s.bind(1, id).bind(2, index);
        if (!s.step()) return std::nullopt;
        return output_of_row(s);
    }
    std::array<int64_t, 3> progress_row(const std::string& id) {
        Stmt s(*this, kProgressSql);
        s.bind(1, id);
        if (!s.step()) return {0, 0, 0};
        return {s.i64(0), s.i64(1), s.i64(2)};
    }

    std::optional<JobRecord> get(const std::string& id) {
        std::optional<JobRecord> j;
        {
            Stmt s(*this, (sqlite_store::select_jobs() + "WHERE id = ?").c_str());
            s.bind(1, id);
            if (s.step()) j = job_of_row(s);
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
