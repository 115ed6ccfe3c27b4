// The PostgreSQL job store's work side: claiming outputs under a lease,
// renewing it, the fenced output transitions, finishing a job once its last
// output is done (on whichever instance), and putting work back on a stop.
#include "core/check.h"
#include "server/store/job_store_pg.h"

#include "core/error.h"
#include "server/common/request_log.h"
#include "server/store/job_schema.h"

namespace nurbsrt::server {
namespace {

// Now in the database server's clock, Unix ms: every instance measures leases
// against the same clock.
#define NURBSRT_PG_NOW "(extract(epoch FROM clock_timestamp()) * 1000)::bigint"

std::string str(int64_t v) { return std::to_string(v); }

}  // namespace

std::optional<JobState> PgJobStore::finish_locked(const std::string& id, int64_t now_ms) {
    const PgResult job = conn_->exec("SELECT state FROM jobs WHERE id = $1 FOR UPDATE", {id});
    if (job.rows() == 0) return std::nullopt;
    const JobState now = stored_job_state(job.text(0, 0));
    if (now == JobState::canceled) return std::nullopt;
    if (now != JobState::running) return JobState::running;  // another instance finished it (or it was requeued)
    const PgResult r =
        conn_->exec("SELECT state, error_code, error_message FROM job_outputs WHERE job_id = $1 ORDER BY idx", {id});
    int64_t total = 0, failed = 0;
    std::string first_code, first_message;
    for (int i = 0; i < r.rows(); ++i) {
        const JobState s = stored_job_state(r.text(i, 0));
        if (!is_finished(s)) return JobState::running;
        ++total;
        if (s != JobState::succeeded && ++failed == 1) {
            first_code = r.text(i, 1).empty() ? "internal" : r.text(i, 1);
            first_message = r.text(i, 2);
        }
    }
    NURBSRT_CHECK(total > 0);  // a job has outputs: with none it would "succeed" having made nothing
    const JobState state = failed ? JobState::failed : JobState::succeeded;
    const std::string message =
        failed ? str(failed) + " of " + str(total) + " outputs failed; first: " + first_message : std::string();
    // The callback becomes due in the same transaction (server/jobs/webhooks.h).
    conn_->exec(
        "UPDATE jobs SET state = $1, finished_ms = $2, error_code = $3, error_message = $4, "
        "callback_state = CASE WHEN callback_url <> '' THEN 'pending' ELSE '' END, callback_due_ms = $2 "
        "WHERE id = $5",
        {job_state_name(state), str(now_ms), failed ? first_code : std::string(), message, id});
    append_state(id, now_ms);
    return state;
}

std::optional<JobState> PgJobStore::finish(const std::string& id, int64_t now_ms) {
    std::lock_guard<std::mutex> lock(m_);
    PgConn::Transaction t(*conn_);
    auto state = finish_locked(id, now_ms);
    t.commit();
    return state;
}

void PgJobStore::fail_interrupted(const std::string& id, int output, int max_attempts, int64_t now_ms) {
    const std::string reason = "interrupted by a service restart or a lost instance (" + str(max_attempts) +
                               " attempts; its lease expired each time)";
    conn_->exec(
        "UPDATE job_outputs SET state = 'failed', error_code = 'interrupted', error_message = $1, "
        "finished_ms = $2, lease_token = '', lease_expires_ms = 0 WHERE job_id = $3 AND idx = $4",
        {reason, str(now_ms), id, str(output)});
    append_output_events(*this, id, output, now_ms);
    log_event("job_output_interrupted", "{\"job_id\":\"" + id + "\",\"output\":" + str(output) + "}");
}

std::optional<JobClaim> PgJobStore::claim_outputs(const std::string& id, const std::vector<Claimable>& outputs,
                                                  int64_t now_ms) {
    JobClaim claim;
    claim.lease = new_request_id();  // 128 random bits
    int attempts = 0;
    std::vector<int> run;
    for (const Claimable& o : outputs) {
        conn_->exec(
            "UPDATE job_outputs SET attempts = $3, lease_token = $4, lease_owner = $5, "
            "lease_expires_ms = " NURBSRT_PG_NOW
            " + $6, state = 'queued', progress = 0, started_ms = 0 "
            "WHERE job_id = $1 AND idx = $2",
            {id, str(o.index), str(o.attempts + 1), claim.lease, instance_, str(lease_ms_)});
        attempts = std::max(attempts, o.attempts + 1);
        run.push_back(o.index);
    }
    // Exactly one claim of a queued job reports it running: the update waits
    // for the job row's lock and sees the state another claim committed.
    if (conn_->exec("UPDATE jobs SET state = 'running' WHERE id = $1 AND state = 'queued'", {id}).affected() > 0)
        append_state(id, now_ms);
    conn_->exec(
        "UPDATE jobs SET state = 'running', attempts = GREATEST(attempts, $2), "
        "started_ms = CASE WHEN started_ms = 0 THEN $3 ELSE started_ms END WHERE id = $1",
        {id, str(attempts), str(now_ms)});
    auto job = read(id);
    if (!job) return std::nullopt;
    static_cast<JobRecord&>(claim) = std::move(*job);
    claim.run = std::move(run);
    return claim;
}

std::optional<JobClaim> PgJobStore::claim_next(int64_t now_ms, int max_attempts) {
    std::lock_guard<std::mutex> lock(m_);
    // Each pass either claims, finds nothing, or settles one stranded item and looks again.
    for (int pass = 0; pass < 64; ++pass) {
        PgConn::Transaction t(*conn_);
        // A job whose outputs are all finished but whose runner died before finishing it.
        const PgResult done = conn_->exec(
            "SELECT id FROM jobs j WHERE state = 'running' AND NOT EXISTS (SELECT 1 FROM job_outputs o "
            "WHERE o.job_id = j.id AND o.state IN ('queued', 'running')) ORDER BY seq LIMIT 1 FOR UPDATE SKIP LOCKED");
        if (done.rows() > 0) {
            finish_locked(done.text(0, 0), now_ms);
            t.commit();
            continue;
        }
        // The oldest job's first output that is queued, or whose lease expired ...
        const PgResult first = conn_->exec(
            "SELECT o.job_id, o.file FROM job_outputs o JOIN jobs j ON j.id = o.job_id "
            "WHERE j.state IN ('queued', 'running') AND o.state IN ('queued', 'running') "
            "AND o.lease_expires_ms < " NURBSRT_PG_NOW " ORDER BY j.seq, o.idx LIMIT 1 FOR UPDATE OF o SKIP LOCKED");
        if (first.rows() == 0) return std::nullopt;
        const std::string id = first.text(0, 0);
        // ... with every other such output of its file: one claim reads the file once for all of them.
        const PgResult r = conn_->exec(
            "SELECT idx, attempts, lease_token <> '' FROM job_outputs WHERE job_id = $1 AND file = $2 "
            "AND state IN ('queued', 'running') AND lease_expires_ms < " NURBSRT_PG_NOW
            " ORDER BY idx FOR UPDATE SKIP LOCKED",
            {id, first.text(0, 1)});
        std::vector<Claimable> take;
        bool interrupted = false;
        for (int i = 0; i < r.rows(); ++i) {
            const Claimable o{static_cast<int>(r.i64(i, 0)), static_cast<int>(r.i64(i, 1))};
            if (r.text(i, 2) == "t") {  // its lease expired: a run of it was cut short
                log_event("job_lease_expired", "{\"job_id\":\"" + id + "\",\"output\":" + str(o.index) +
                                                   ",\"attempts\":" + str(o.attempts) + "}");
                if (o.attempts >= max_attempts) {
                    fail_interrupted(id, o.index, max_attempts, now_ms);
                    interrupted = true;
                    continue;
                }
            }
            take.push_back(o);
        }
        if (take.empty()) {
            if (interrupted) finish_locked(id, now_ms);
            t.commit();
            continue;
        }
        auto claim = claim_outputs(id, take, now_ms);
        t.commit();
        return claim;
    }
    return std::nullopt;
}

bool PgJobStore::renew(const JobClaim& claim) {
    if (claim.run.empty()) return false;
    std::lock_guard<std::mutex> lock(m_);
    // Every output of the claim still open: they share its lease.
    return conn_
               ->exec("UPDATE job_outputs o SET lease_expires_ms = " NURBSRT_PG_NOW
                      " + $3 FROM jobs j "
                      "WHERE o.job_id = $1 AND o.lease_token = $2 AND j.id = o.job_id "
                      "AND j.state = 'running' AND o.state IN ('queued', 'running')",
                      {claim.id, claim.lease, str(lease_ms_)})
               .affected() > 0;
}

bool PgJobStore::output_running(const std::string& id, int output, int64_t now_ms, const std::string& lease) {
    std::lock_guard<std::mutex> lock(m_);
    return output_transition(
        "UPDATE job_outputs SET state = 'running', progress = 0, started_ms = $1 "
        "WHERE job_id = $2 AND idx = $3 AND lease_token = $4 AND state = 'queued'",
        {str(now_ms), id, str(output), lease}, id, output, now_ms);
}

bool PgJobStore::output_transition(const char* sql, const std::vector<std::string>& params, const std::string& id,
                                   int output, int64_t now_ms) {
    PgConn::Transaction t(*conn_);
    const bool changed = conn_->exec(sql, params).affected() > 0;
    if (changed) append_output_events(*this, id, output, now_ms);
    t.commit();
    return changed;
}

bool PgJobStore::output_progress(const std::string& id, int output, double progress, const std::string& lease) {
    std::lock_guard<std::mutex> lock(m_);
    return conn_
               ->exec(
                   "UPDATE job_outputs SET progress = $1 WHERE job_id = $2 AND idx = $3 AND lease_token = $4 "
                   "AND state = 'running'",
                   {std::to_string(progress), id, str(output), lease})
               .affected() > 0;
}

bool PgJobStore::output_succeeded(const std::string& id, int output, int64_t artifact_bytes,
                                  const std::string& result_json, int64_t now_ms, const std::string& lease) {
    std::lock_guard<std::mutex> lock(m_);
    // Fenced: only the run holding the lease finishes the output, once (and so reports it once).
    return output_transition(
        "UPDATE job_outputs SET state = 'succeeded', progress = 1, artifact_bytes = $1, result = $2, "
        "finished_ms = $3, completions = completions + 1, lease_token = '', lease_expires_ms = 0 "
        "WHERE job_id = $4 AND idx = $5 AND lease_token = $6 AND state = 'running'",
        {str(artifact_bytes), result_json, str(now_ms), id, str(output), lease}, id, output, now_ms);
}

bool PgJobStore::output_failed(const std::string& id, int output, const std::string& code, const std::string& message,
                               int64_t now_ms, const std::string& lease) {
    std::lock_guard<std::mutex> lock(m_);
    return output_transition(
        "UPDATE job_outputs SET state = 'failed', error_code = $1, error_message = $2, finished_ms = $3, "
        "completions = completions + 1, lease_token = '', lease_expires_ms = 0 "
        "WHERE job_id = $4 AND idx = $5 AND lease_token = $6 AND state IN ('queued', 'running')",
        {code, message, str(now_ms), id, str(output), lease}, id, output, now_ms);
}

void PgJobStore::requeue(const JobClaim& claim) {
    std::lock_guard<std::mutex> lock(m_);
    PgConn::Transaction t(*conn_);
    lock_outputs(claim.id);
    conn_->exec(
        "UPDATE job_outputs SET state = 'queued', progress = 0, started_ms = 0, "
        "attempts = GREATEST(attempts - 1, 0), lease_token = '', lease_expires_ms = 0 "
        "WHERE job_id = $1 AND lease_token = $2 AND state IN ('queued', 'running')",
        {claim.id, claim.lease});
    // Back to the queue unless another instance runs one of its outputs.
    const bool requeued =
        conn_
            ->exec(
                "UPDATE jobs SET state = 'queued', attempts = (SELECT COALESCE(MAX(attempts), 0) FROM job_outputs "
                "WHERE job_id = $1) WHERE id = $1 AND state = 'running' AND NOT EXISTS (SELECT 1 FROM job_outputs "
                "WHERE job_id = $1 AND lease_token <> '' AND lease_expires_ms >= " NURBSRT_PG_NOW ")",
                {claim.id})
            .affected() > 0;
    if (requeued) append_state(claim.id, unix_now_ms());
    t.commit();
}

}  // namespace nurbsrt::server
