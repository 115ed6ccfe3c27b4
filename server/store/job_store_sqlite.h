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

    void create(JobRecord& job) override;
    std::optional<JobRecord> get(const std::string& id) override;
    bool exists(const std::string& id) override;
    JobPage list(const std::optional<JobState>& state, bool newest_first, int limit,
                 std::optional<int64_t> after_seq) override;
    std::map<JobState, int64_t> count_by_state() override;
    int64_t artifact_bytes() override;
    // The oldest queued job with all its queued outputs (attempts + 1).
    std::optional<JobClaim> claim_next(int64_t now_ms, int max_attempts = 3) override;
    bool output_running(const std::string& id, int output, int64_t now_ms, const std::string& lease = {}) override;
    bool output_progress(const std::string& id, int output, double progress, const std::string& lease = {}) override;
    bool output_succeeded(const std::string& id, int output, int64_t artifact_bytes, const std::string& result_json,
                          int64_t now_ms, const std::string& lease = {}) override;
    bool output_failed(const std::string& id, int output, const std::string& code, const std::string& message,
                       int64_t now_ms, const std::string& lease = {}) override;
    std::optional<JobState> finish(const std::string& id, int64_t now_ms) override;
    void requeue(const JobClaim& claim) override;
    void requeue(const std::string& id);
    DeleteOutcome delete_job(const std::string& id, int64_t now_ms) override;
    bool remove(const std::string& id) override;
    bool running(const std::string& id) override;
    bool renew(const JobClaim& claim) override { return running(claim.id); }
    RecoveryReport recover(int max_attempts, int64_t now_ms) override;
    std::vector<std::string> finished_before(int64_t before_ms) override;
    std::vector<std::string> all_ids() override;
    std::optional<JobRecord> claim_callback(int64_t now_ms, int64_t hold_ms) override;
    bool callback_attempted(const std::string& id, const CallbackAttempt& a) override;
    bool shared() const override { return false; }
    int64_t lease_ms() const override { return 0; }
    std::string describe() const override;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
    std::mutex m_;
};

}  // namespace nurbsrt::server
