// The PostgreSQL job store: one queue shared by many service instances.
// Outputs are claimed a file at a time (every claimable output of one input
// file, so that one run reads the file once for all of them) with SELECT ...
// FOR UPDATE SKIP LOCKED
// (PostgreSQL manual, "The Locking Clause": rows locked by another claimer
// are skipped, not waited for) under a lease: a random token and an expiry in
// the database's clock, renewed by the runner's heartbeat. An output whose
// lease expired (its instance died) is claimed again by another instance; the
// final update of an output names the token, so a run that lost its lease can
// never finish it (fencing). Lock order in every transaction: output rows
// before the job row, so claims, deletions and finishes cannot deadlock.
#pragma once

#include <array>
#include <memory>
#include <mutex>

#include "server/store/job_store.h"
#include "server/store/pg_conn.h"

namespace nurbsrt::server {

class PgJobStore final : public JobStore {
public:
    // Connects, then creates or migrates the schema (one instance at a time,
    // under an advisory lock). Throws Error(io) as open_postgres_job_store says.
    PgJobStore(const std::string& url, std::string instance, double lease_s);
    ~PgJobStore() override;

    NURBSRT_JOB_STORE_OVERRIDES;
    bool renew(const JobClaim& claim) override;
    RecoveryReport recover(int, int64_t) override { return {}; }
    bool shared() const override { return true; }
    int64_t lease_ms() const override { return lease_ms_; }
    std::string describe() const override { return conn_->where(); }

    // Events (job_schema.h), appended inside the caller's transaction.
    void append(const std::string& id, JobEventType type, const std::string& data, int64_t now_ms);
    void append_state(const std::string& id, int64_t now_ms);
    std::optional<JobOutput> output_row(const std::string& id, int index);
    std::array<int64_t, 3> progress_row(const std::string& id);

private:
    void migrate();
    // The job and its outputs, inside the caller's transaction.
    std::optional<JobRecord> read(const std::string& id);
    void load_children(JobRecord& j);
    // The job's final state when every output is finished (inside a transaction
    // holding the job row); "running" while outputs remain; nullopt when gone.
    std::optional<JobState> finish_locked(const std::string& id, int64_t now_ms);
    // Fails an output whose lease expired `max_attempts` times (in a transaction).
    void fail_interrupted(const std::string& id, int output, int max_attempts, int64_t now_ms);
    // Outputs of one job (of one file) under one new lease, as one claim.
    struct Claimable {
        int index = 0;
        int attempts = 0;  // runs started so far
    };
    std::optional<JobClaim> claim_outputs(const std::string& id, const std::vector<Claimable>& outputs, int64_t now_ms);
    void lock_outputs(const std::string& id);
    // One fenced output update (`sql` with `params`) and its events, in one transaction; whether it changed it.
    bool output_transition(const char* sql, const std::vector<std::string>& params, const std::string& id, int output,
                           int64_t now_ms);

    std::unique_ptr<PgConn> conn_;
    std::string instance_;
    int64_t lease_ms_;
    std::mutex m_;
};

}  // namespace nurbsrt::server
