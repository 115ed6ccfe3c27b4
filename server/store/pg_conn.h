// A small wrapper over one libpq connection: connect with a clear error,
// reconnect after the server went away, run statements with text parameters,
// transactions that roll back when left by an exception. libpq-fe.h stays in
// pg_conn.cpp (only the opaque types are named here). Not thread-safe: the
// owner serializes use.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

struct pg_conn;
struct pg_result;

namespace nurbsrt::server {

// Rows of one statement (owns the PGresult).
class PgResult {
public:
    explicit PgResult(pg_result* r) : r_(r) {}
    ~PgResult();
    PgResult(PgResult&& o) noexcept : r_(o.r_) { o.r_ = nullptr; }
    PgResult(const PgResult&) = delete;
    PgResult& operator=(const PgResult&) = delete;
    PgResult& operator=(PgResult&&) = delete;

    int rows() const;
    int64_t affected() const;  // rows changed by INSERT/UPDATE/DELETE
    std::string text(int row, int col) const;
    int64_t i64(int row, int col) const;
    double real(int row, int col) const;

    // One row, read by column alone (the row readers of job_schema.h).
    struct Row {
        const PgResult& result;
        int row;
        std::string text(int col) const { return result.text(row, col); }
        int64_t i64(int col) const { return result.i64(row, col); }
        double real(int col) const { return result.real(row, col); }
    };
    Row row(int i) const { return {*this, i}; }

private:
    pg_result* r_;
};

class PgConn {
public:
    // Connects (5 s timeout unless the URL sets one). Throws Error(io) naming
    // `where` (the URL without its password) and libpq's reason.
    explicit PgConn(const std::string& url);
    ~PgConn();
    PgConn(const PgConn&) = delete;
    PgConn& operator=(const PgConn&) = delete;

    // Runs one statement ($1, $2, ... bound to `params` as text; without
    // parameters, several statements may follow each other). Reconnects first
    // when the connection was lost. Throws Error(io) on failure.
    PgResult exec(const char* sql, const std::vector<std::string>& params = {});
    const std::string& where() const { return where_; }

    // BEGIN ... COMMIT; rolled back when destroyed uncommitted.
    class Transaction {
    public:
        explicit Transaction(PgConn& c) : c_(c) { c_.exec("BEGIN"); }
        ~Transaction();
        void commit();
        Transaction(const Transaction&) = delete;
        Transaction& operator=(const Transaction&) = delete;

    private:
        PgConn& c_;
        bool done_ = false;
    };

private:
    void ensure_connected();
    pg_conn* conn_ = nullptr;
    std::string url_, where_;
};

// The URL as it may be shown: any password replaced by ***.
std::string redact_pg_url(const std::string& url);

}  // namespace nurbsrt::server
