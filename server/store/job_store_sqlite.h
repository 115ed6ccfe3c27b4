// The SQLite job store: DATA_DIR/jobs.db (WAL, busy timeout, schema version
// table, prepared statements, every state change in one transaction), for one
// service process. sqlite3.h stays in job_store_sqlite.cpp. Thread-safe (one
// connection behind a mutex).
#pragma once

#include <memory>
#include <mutex>

#include "server/store/job_store.h"

namespace nurbsrt::server {

class SqliteJobStore final : public JobStore {
public:
    explicit SqliteJobStore(const std::string& db_path);
    ~SqliteJobStore() override;
    SqliteJobStore(const SqliteJobStore&) = delete;
    SqliteJobStore& operator=(const SqliteJobStore&) = delete;

    NURBSRT_JOB_STORE_OVERRIDES;
    void requeue(const std::string& id);
    bool renew(const JobClaim& claim) override { return running(claim.id); }
    RecoveryReport recover(int max_attempts, int64_t now_ms) override;
    bool shared() const override { return false; }
    int64_t lease_ms() const override { return 0; }
    std::string describe() const override;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
    std::mutex m_;
};

}  // namespace nurbsrt::server
