// The SQLite job store's deletions, restart recovery and retention queries.
#include "server/store/job_store_sqlite_impl.h"

namespace nurbsrt::server {

void SqliteJobStore::Impl::remove_rows(const std::string& id) {
    Stmt(*this, "DELETE FROM job_events WHERE job_id = ?").bind(1, id).run();
    Stmt(*this, "DELETE FROM job_outputs WHERE job_id = ?").bind(1, id).run();
    Stmt(*this, "DELETE FROM job_inputs WHERE job_id = ?").bind(1, id).run();
    Stmt(*this, "DELETE FROM jobs WHERE id = ?").bind(1, id).run();
}

JobStore::DeleteOutcome SqliteJobStore::delete_job(const std::string& id, int64_t now_ms) {
    std::lock_guard<std::mutex> lock(m_);
    Impl::Transaction t(*impl_);
    std::optional<JobState> state;
    {
        Impl::Stmt s(*impl_, "SELECT state FROM jobs WHERE id = ?");
        s.bind(1, id);
        if (!s.step()) return DeleteOutcome::not_found;
        state = stored_job_state(s.text(0));
    }
    if (state == JobState::canceled) return DeleteOutcome::canceling;
    if (state == JobState::running) {
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
        impl_->append_state(id, now_ms);
        t.commit();
        return DeleteOutcome::canceling;
    }
    impl_->remove_rows(id);
    t.commit();
    return DeleteOutcome::removed;
}

bool SqliteJobStore::remove(const std::string& id) {
    std::lock_guard<std::mutex> lock(m_);
    Impl::Transaction t(*impl_);
    impl_->remove_rows(id);
    const int n = sqlite3_changes(impl_->db);
    t.commit();
    return n > 0;
}

bool SqliteJobStore::running(const std::string& id) {
    std::lock_guard<std::mutex> lock(m_);
    return impl_->job_running(id);
}

RecoveryReport SqliteJobStore::recover(int max_attempts, int64_t now_ms) {
    std::lock_guard<std::mutex> lock(m_);
    Impl::Transaction t(*impl_);
    RecoveryReport r;
    std::vector<std::string> running;
    {
        Impl::Stmt s(*impl_, "SELECT id FROM jobs WHERE state = 'running' ORDER BY seq");
        while (s.step()) running.push_back(s.text(0));
    }
    {
        Impl::Stmt s(*impl_, "SELECT id FROM jobs WHERE state = 'canceled' ORDER BY seq");
        while (s.step()) r.removed.push_back(s.text(0));
    }
    for (const std::string& id : r.removed) impl_->remove_rows(id);
    // Only the outputs the crash cut short were running: each runs again unless
    // that was its last allowed run. Its siblings, finished or still queued, are
    // not charged: a crash is not the job's fault.
    const std::string reason = "interrupted by a service restart in each of its " + std::to_string(max_attempts) +
                               " runs (--max-output-attempts)";
    for (const std::string& id : running) {
        std::vector<int> cut;  // outputs that fail now: each reports it (job_schema.h)
        {
            Impl::Stmt s(*impl_,
                         "SELECT idx FROM job_outputs WHERE job_id = ? AND state = 'running' AND attempts >= ?");
            s.bind(1, id).bind(2, max_attempts);
            while (s.step()) cut.push_back(static_cast<int>(s.i64(0)));
        }
        Impl::Stmt(*impl_,
                   "UPDATE job_outputs SET state = 'failed', finished_ms = ?, error_code = 'interrupted', "
                   "error_message = ? WHERE job_id = ? AND state = 'running' AND attempts >= ?")
            .bind(1, now_ms)
            .bind(2, reason)
            .bind(3, id)
            .bind(4, max_attempts)
            .run();
        for (int output : cut) append_output_events(*impl_, id, output, now_ms);
        Impl::Stmt(*impl_,
                   "UPDATE job_outputs SET state = 'queued', progress = 0, started_ms = 0 "
                   "WHERE job_id = ? AND state = 'running'")
            .bind(1, id)
            .run();
        bool work_left = false;
        {
            Impl::Stmt s(*impl_, "SELECT 1 FROM job_outputs WHERE job_id = ? AND state = 'queued' LIMIT 1");
            s.bind(1, id);
            work_left = s.step();
        }
        if (work_left) {
            Impl::Stmt(*impl_, "UPDATE jobs SET state = 'queued' WHERE id = ?").bind(1, id).run();
            impl_->append_state(id, now_ms);
            r.requeued.push_back(id);
        } else if (impl_->finish_job(id, now_ms) == JobState::failed) {
            r.failed.push_back(id);  // (one that had finished every output but its own end is kept succeeded)
        }
    }
    t.commit();
    return r;
}

std::vector<std::string> SqliteJobStore::finished_before(int64_t before_ms) {
    std::lock_guard<std::mutex> lock(m_);
    std::vector<std::string> ids;
    Impl::Stmt s(*impl_,
                 "SELECT id FROM jobs WHERE state IN ('succeeded', 'failed') AND finished_ms < ? "
                 "ORDER BY seq");
    s.bind(1, before_ms);
    while (s.step()) ids.push_back(s.text(0));
    return ids;
}

std::vector<std::string> SqliteJobStore::all_ids() {
    std::lock_guard<std::mutex> lock(m_);
    std::vector<std::string> ids;
    Impl::Stmt s(*impl_, "SELECT id FROM jobs ORDER BY seq");
    while (s.step()) ids.push_back(s.text(0));
    return ids;
}

std::optional<JobRecord> SqliteJobStore::claim_callback(int64_t now_ms, int64_t hold_ms) {
    std::lock_guard<std::mutex> lock(m_);
    Impl::Transaction t(*impl_);
    std::string id;
    {
        Impl::Stmt s(*impl_,
                     "SELECT id FROM jobs WHERE callback_state = 'pending' AND callback_due_ms <= ? "
                     "ORDER BY callback_due_ms, seq LIMIT 1");
        s.bind(1, now_ms);
        if (!s.step()) return std::nullopt;
        id = s.text(0);
    }
    Impl::Stmt(*impl_, "UPDATE jobs SET callback_due_ms = ? WHERE id = ?").bind(1, now_ms + hold_ms).bind(2, id).run();
    auto job = impl_->get(id);
    t.commit();
    return job;
}

bool SqliteJobStore::callback_attempted(const std::string& id, const CallbackAttempt& a) {
    std::lock_guard<std::mutex> lock(m_);
    Impl::Stmt s(*impl_,
                 "UPDATE jobs SET callback_attempts = callback_attempts + 1, callback_state = ?, callback_due_ms = ?, "
                 "callback_status = ?, callback_error = ?, callback_done_ms = ? WHERE id = ? AND "
                 "callback_state = 'pending'");
    const bool done = a.state != CallbackState::pending;
    s.bind(1, std::string(callback_state_name(a.state))).bind(2, done ? int64_t(0) : a.next_ms).bind(3, a.status);
    s.bind(4, a.error).bind(5, done ? a.now_ms : int64_t(0)).bind(6, id).run();
    return s.changes() > 0;
}

}  // namespace nurbsrt::server
