#include "server/store/pg_conn.h"

#include <libpq-fe.h>

#include <cstdlib>
#include <regex>

#include "core/error.h"

namespace nurbsrt::server {

PgResult::~PgResult() {
    if (r_) PQclear(r_);
}
int PgResult::rows() const { return PQntuples(r_); }
int64_t PgResult::affected() const {
    const char* n = PQcmdTuples(r_);
    return n && *n ? std::strtoll(n, nullptr, 10) : 0;
}
std::string PgResult::text(int row, int col) const {
    return std::string(PQgetvalue(r_, row, col), static_cast<size_t>(PQgetlength(r_, row, col)));
}
int64_t PgResult::i64(int row, int col) const { return std::strtoll(PQgetvalue(r_, row, col), nullptr, 10); }
double PgResult::real(int row, int col) const { return std::strtod(PQgetvalue(r_, row, col), nullptr); }

std::string redact_pg_url(const std::string& url) {
    static const std::regex uri_password(R"(^([a-z]+://[^:/@]*):[^@]*@)");
    static const std::regex kv_password(R"((password\s*=\s*)('[^']*'|\S+))");
    return std::regex_replace(std::regex_replace(url, uri_password, "$1:***@"), kv_password, "$1***");
}

namespace {

std::string trimmed(const char* s) {
    std::string m = s ? s : "";
    while (!m.empty() && (m.back() == '\n' || m.back() == ' ')) m.pop_back();
    return m;
}

}  // namespace

PgConn::PgConn(const std::string& url) : url_(url), where_(redact_pg_url(url)) {
    // The URL comes as "dbname" with expand_dbname: anything it sets (its own
    // connect_timeout too) overrides the defaults listed before it.
    const char* keys[] = {"connect_timeout", "application_name", "dbname", nullptr};
    const char* values[] = {"5", "nurbsrt", url.c_str(), nullptr};
    conn_ = PQconnectdbParams(keys, values, 1);
    if (!conn_ || PQstatus(conn_) != CONNECTION_OK)
        throw Error(ErrorCode::io, "job store " + where_ + ": cannot connect: " +
                                       (conn_ ? trimmed(PQerrorMessage(conn_)) : std::string("out of memory")));
    // Notices (CREATE ... IF NOT EXISTS "already exists, skipping") are not ours to print.
    PQsetNoticeProcessor(
        conn_, [](void*, const char*) {}, nullptr);
}

PgConn::~PgConn() {
    if (conn_) PQfinish(conn_);
}

void PgConn::ensure_connected() {
    if (PQstatus(conn_) == CONNECTION_OK) return;
    PQreset(conn_);
    if (PQstatus(conn_) != CONNECTION_OK)
        throw Error(ErrorCode::io, "job store " + where_ + ": connection lost: " + trimmed(PQerrorMessage(conn_)));
}

PgResult PgConn::exec(const char* sql, const std::vector<std::string>& params) {
    ensure_connected();
    std::vector<const char*> values;
    values.reserve(params.size());
    for (const std::string& p : params) values.push_back(p.c_str());
    // Without parameters the simple protocol: it takes several statements (the schema).
    PGresult* raw = params.empty() ? PQexec(conn_, sql)
                                   : PQexecParams(conn_, sql, static_cast<int>(values.size()), nullptr, values.data(),
                                                  nullptr, nullptr, 0);
    const ExecStatusType status = raw ? PQresultStatus(raw) : PGRES_FATAL_ERROR;
    if (status != PGRES_COMMAND_OK && status != PGRES_TUPLES_OK) {
        const std::string why = trimmed(raw ? PQresultErrorMessage(raw) : PQerrorMessage(conn_));
        if (raw) PQclear(raw);
        throw Error(ErrorCode::io, "job store " + where_ + ": " + why);
    }
    return PgResult(raw);
}

PgConn::Transaction::~Transaction() {
    if (done_) return;
    try {
        c_.exec("ROLLBACK");
    } catch (const Error&) {
        // The connection is gone: the server rolled the transaction back itself.
    }
}

void PgConn::Transaction::commit() {
    c_.exec("COMMIT");
    done_ = true;
}

}  // namespace nurbsrt::server
