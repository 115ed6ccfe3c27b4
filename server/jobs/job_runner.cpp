#include "server/jobs/job_runner.h"

#include <nlohmann/json.hpp>

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <cctype>
#include <map>
#include <set>
#include <thread>

#include "importer/isolated.h"
#include "core/error.h"
#include "server/render/context.h"
#include "server/jobs/artifact_quota.h"
#include "server/store/durable_file.h"
#include "server/jobs/job_spec.h"
#include "server/common/redact.h"
#include "options/render_request.h"
#include "server/render/render_service.h"
#include "server/common/request_log.h"
#include "server/common/scratch.h"
#include "server/common/service_error.h"
#include "server/render/stage_timings.h"
#include "server/render/work.h"

namespace nurbsrt::server {
namespace fs = std::filesystem;
namespace {

// Messages of exceptions caught in the runner's own loops may carry bytes that
// are not UTF-8 (a path, a library's text): dumping them must not throw there,
// where an escaping exception would end the process.
constexpr auto kReplaceBadUtf8 = nlohmann::json::error_handler_t::replace;

std::string input_name(int index) { return "input-" + std::to_string(index) + ".cad"; }
// Beside a job's inputs when its spec asked `force` (no artifact reuse).
constexpr const char* kForceMarker = "force";

// An error message for the client: the service's own paths (the job and
// scratch directories) are cut out: job files keep their public names
// (artifacts, input-N.cad), scratch files are named by what they are.
std::string without_paths(const std::string& message, const std::string& dir, const std::string& scratch) {
    return without_prefixes(with_scratch_files_named(message, scratch), {dir + "/partial-", dir + "/"});
}

}  // namespace

JobService::JobService(ServerContext& ctx)
    : ctx_(ctx),
      jobs_dir_(ctx.config.data_dir + "/jobs"),
      instance_(ctx.config.instance_id),
      reuse_(ctx.config.data_dir + "/reuse") {
    std::error_code ec;
    fs::create_directories(jobs_dir_, ec);
    if (ec || ::chmod(jobs_dir_.c_str(), 0700) != 0)
        throw Error(ErrorCode::io, "cannot create the job directory " + jobs_dir_);
    // Inputs and artifacts go there: find out now, not at the first job.
    try {
        const std::string probe = jobs_dir_ + "/.write-test-" + new_request_id();
        write_durably(probe, "x");
        fs::remove(probe, ec);
    } catch (const Error&) {
        throw Error(ErrorCode::io, "the job directory " + jobs_dir_ + " is not writable");
    }
    if (is_postgres_url(ctx.config.job_store))
        store_ = open_postgres_job_store(ctx.config.job_store, instance_, ctx.config.lease_s);
    else
        store_ = open_sqlite_job_store(ctx.config.job_store.empty() ? ctx.config.data_dir + "/jobs.db"
                                                                    : ctx.config.job_store);
    webhooks_ = std::make_unique<WebhookSender>(*store_, ctx.config, ctx.metrics);
    log_event("job_store", nlohmann::json{{"store", store_->describe()},
                                          {"instance", instance_},
                                          {"shared", store_->shared()},
                                          {"lease_ms", store_->lease_ms()}}
                               .dump());
    if (store_->shared()) {
        sweep();
        return;  // every other instance's files are in flight in the shared directory
    }
    const RecoveryReport r = store_->recover(ctx_.config.max_output_attempts, unix_now_ms());
    for (const std::string& id : r.removed) remove_files(id);
    if (!r.requeued.empty() || !r.failed.empty() || !r.removed.empty())
        log_event("jobs_recovered",
                  nlohmann::json{{"requeued", r.requeued}, {"failed", r.failed}, {"removed", r.removed}}.dump());
    // Directories without a job row: a submission or deletion cut short. Only
    // names the service generates are touched.
    const std::vector<std::string> ids = store_->all_ids();
    const std::set<std::string> known(ids.begin(), ids.end());
    std::vector<std::string> orphans;
    for (const auto& entry : fs::directory_iterator(jobs_dir_, ec)) {
        const std::string name = entry.path().filename().string();
        if (valid_job_id(name) && !known.count(name)) orphans.push_back(name);
    }
    for (const std::string& id : orphans) remove_files(id);
    // Partial artifacts of outputs cut short (a killed service): no output runs
    // before start(), so none of them belongs to anyone.
    for (const std::string& id : ids) {
        for (const auto& entry : fs::directory_iterator(job_dir(id), ec))
            if (entry.path().filename().string().rfind("partial-", 0) == 0) fs::remove(entry.path(), ec);
    }
    sweep();
}

JobService::~JobService() { stop(); }

std::string JobService::job_dir(const std::string& id) const { return jobs_dir_ + "/" + id; }

std::string JobService::artifact_path(const std::string& id, const std::string& artifact) const {
    return job_dir(id) + "/" + artifact;
}

void JobService::remove_files(const std::string& id) const {
    std::error_code ec;
    fs::remove_all(job_dir(id), ec);
}

void JobService::start() {
    std::lock_guard<std::mutex> lock(m_);
    stopping_ = false;
    for (int i = 0; i < ctx_.config.job_runners; ++i) runners_.emplace_back([this] { run_loop(); });
    sweeper_ = std::thread([this] { sweep_loop(); });
    if (store_->lease_ms() > 0) heartbeat_ = std::thread([this] { heartbeat_loop(); });
    webhooks_->start();
}

void JobService::stop() {
    {
        std::lock_guard<std::mutex> lock(m_);
        if (stopping_ && runners_.empty()) return;
        stopping_ = true;
        for (auto& [key, a] : active_) a.cancel->store(true);
    }
    cv_.notify_all();
    for (std::thread& t : runners_) t.join();
    runners_.clear();
    if (sweeper_.joinable()) sweeper_.join();
    if (heartbeat_.joinable()) heartbeat_.join();
    webhooks_->stop();
}

void JobService::submit(JobRecord& job, const std::vector<const std::string*>& input_bytes, bool force) {
    // One submission at a time, so the queue bound holds exactly.
    std::lock_guard<std::mutex> submit_lock(submit_m_);
    if (store_->count_by_state()[JobState::queued] >= ctx_.config.max_queued_jobs)
        throw ServiceError(ServiceCode::overloaded,
                           std::to_string(ctx_.config.max_queued_jobs) + " jobs are already waiting; retry later");
    job.id = new_request_id();
    job.created_ms = unix_now_ms();
    const std::string dir = job_dir(job.id);
    try {
        fs::create_directory(dir);
        for (size_t i = 0; i < input_bytes.size(); ++i)
            write_durably(dir + "/" + input_name(static_cast<int>(i)), *input_bytes[i]);
        if (force) write_durably(dir + "/" + kForceMarker, "");
        sync_dir(dir);
        sync_dir(jobs_dir_);
        store_->create(job);
    } catch (const std::exception& e) {
        remove_files(job.id);
        if (const auto* err = dynamic_cast<const Error*>(&e)) throw *err;
        throw Error(ErrorCode::io, std::string("cannot store the job: ") + e.what());
    }
    {
        std::lock_guard<std::mutex> lock(m_);
        ++submissions_;
    }
    cv_.notify_all();  // the sweeper and the heartbeat wait on cv_ too: notify_one could wake only them
}

JobStore::DeleteOutcome JobService::remove(const std::string& id) {
    const JobStore::DeleteOutcome outcome = store_->delete_job(id, unix_now_ms());
    if (outcome == JobStore::DeleteOutcome::removed) {
        remove_files(id);
    } else if (outcome == JobStore::DeleteOutcome::canceling) {
        // The runner registered its flag before it checks the job's state for
        // the next output, so either it sees `canceled` there or the flag here.
        // Runners on other instances see it at their next heartbeat.
        std::lock_guard<std::mutex> lock(m_);
        for (auto& [key, a] : active_)
            if (a.claim.id == id) a.cancel->store(true);
    }
    return outcome;
}

int JobService::sweep() {
    const auto retention_ms = static_cast<int64_t>(ctx_.config.job_retention_s * 1000);
    int removed = 0;
    for (const std::string& id : store_->finished_before(unix_now_ms() - retention_ms))
        if (store_->remove(id)) {
            remove_files(id);
            ++removed;
        }
    if (removed) log_event("jobs_expired", nlohmann::json{{"removed", removed}}.dump());
    // Stored files expire with the same retention, counted from their upload (pinned ones never).
    if (const int files = ctx_.files.expire(unix_now_ms() - retention_ms))
        log_event("files_expired", nlohmann::json{{"removed", files}}.dump());
    // Artifacts kept for reuse likewise, counted from when they were made.
    if (const int artifacts = reuse_.expire(unix_now_ms() - retention_ms))
        log_event("reusable_artifacts_expired", nlohmann::json{{"removed", artifacts}}.dump());
    if (store_->shared()) sweep_shared_leftovers();
    return removed;
}

void JobService::sweep_shared_leftovers() {
    // No start-up sweep runs on a shared data dir (other instances' files are in
    // flight there), so what a killed instance left is removed by age instead:
    // a partial artifact once no run could still be writing it (a conversion
    // writes for at most the import time limit, a render writes at its end), a
    // directory without a job once its submission must have ended or failed.
    using clock = fs::file_time_type::clock;
    const auto partial_age = std::chrono::duration_cast<clock::duration>(std::chrono::duration<double>(
        ctx_.config.import_timeout_s + ctx_.config.render_timeout_s + ctx_.config.lease_s + 60));
    const auto orphan_age = std::chrono::duration_cast<clock::duration>(std::chrono::hours(1));
    const auto now = clock::now();
    std::error_code ec;
    std::vector<std::string> dirs;
    for (const auto& entry : fs::directory_iterator(jobs_dir_, ec))
        if (valid_job_id(entry.path().filename().string())) dirs.push_back(entry.path().filename().string());
    for (const std::string& id : dirs) {
        const auto dir_time = fs::last_write_time(job_dir(id), ec);
        if (!ec && now - dir_time > orphan_age && !store_->exists(id)) {
            remove_files(id);
            continue;
        }
        for (const auto& entry : fs::directory_iterator(job_dir(id), ec)) {
            if (entry.path().filename().string().rfind("partial-", 0) != 0) continue;
            const auto t = fs::last_write_time(entry.path(), ec);
            if (!ec && now - t > partial_age) fs::remove(entry.path(), ec);
        }
    }
}

void JobService::sweep_loop() {
    // Often enough that a job outlives its retention by at most a quarter of it (and at most a minute).
    const double interval_s = std::clamp(ctx_.config.job_retention_s / 4, 0.5, 60.0);
    std::unique_lock<std::mutex> lock(m_);
    while (!stopping_) {
        cv_.wait_for(lock, std::chrono::duration<double>(interval_s), [this] { return stopping_; });
        if (stopping_) break;
        lock.unlock();
        try {
            sweep();
        } catch (const std::exception& e) {
            log_event("jobs_sweep_failed", nlohmann::json{{"error", e.what()}}.dump(-1, ' ', false, kReplaceBadUtf8));
        }
        lock.lock();
    }
}

void JobService::run_loop() {
    // Linux's nice is per thread and inherited by the threads this one starts.
    setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), kJobNice);
    while (true) {
        {
            std::lock_guard<std::mutex> lock(m_);
            if (stopping_) return;
        }
        // A store that fails (disk full, database locked for long, database
        // unreachable) must not end the runner thread, which would end the
        // process: log, pause, go on. The job stays `running` and is recovered
        // at the next start (SQLite) or when its lease expires (PostgreSQL).
        std::optional<JobClaim> claim;
        bool failed = false;
        uint64_t seen = 0;
        {
            std::lock_guard<std::mutex> lock(m_);
            seen = submissions_;
        }
        try {
            claim = store_->claim_next(unix_now_ms(), ctx_.config.max_output_attempts);
            if (claim) run_claim(*claim);
        } catch (const std::exception& e) {
            failed = true;
            log_event("job_runner_error",
                      nlohmann::json{{"job_id", claim ? claim->id : std::string()}, {"error", e.what()}}.dump(
                          -1, ' ', false, kReplaceBadUtf8));
        }
        if (!claim || failed) {
            // Idle: a submission to this instance wakes the runner at once; work
            // submitted to other instances (a shared store) is found by the poll.
            std::unique_lock<std::mutex> lock(m_);
            cv_.wait_for(lock, std::chrono::seconds(1),
                         [this, seen, failed] { return stopping_ || (!failed && submissions_ != seen); });
        }
    }
}

void JobService::heartbeat_loop() {
    // A third of the lease: two renewals may fail (a slow database, a long
    // pause) before another instance may take the work over.
    const auto interval = std::chrono::milliseconds(std::max<int64_t>(store_->lease_ms() / 3, 100));
    std::unique_lock<std::mutex> lock(m_);
    while (!stopping_) {
        cv_.wait_for(lock, interval, [this] { return stopping_; });
        if (stopping_) break;
        std::vector<Active> now;
        for (const auto& [key, a] : active_) now.push_back(a);
        lock.unlock();
        for (const Active& a : now) {
            try {
                if (!store_->renew(a.claim)) {
                    a.cancel->store(true);  // canceled (from any instance) or the lease is lost
                    log_event("job_claim_stopped", nlohmann::json{{"job_id", a.claim.id}}.dump());
                }
            } catch (const std::exception& e) {
                // The database is unreachable: keep working; the fenced final update decides.
                log_event("job_heartbeat_failed",
                          nlohmann::json{{"error", e.what()}}.dump(-1, ' ', false, kReplaceBadUtf8));
            }
        }
        lock.lock();
    }
}

void JobService::run_claim(JobClaim& claim) {
    auto cancel = std::make_shared<std::atomic<bool>>(false);
    uint64_t key = 0;
    {
        std::lock_guard<std::mutex> lock(m_);
        key = next_active_++;
        active_[key] = Active{claim, cancel};
        if (stopping_) cancel->store(true);
    }
    // The flag is unregistered however this ends.
    struct Unregister {
        JobService& s;
        uint64_t key;
        ~Unregister() {
            std::lock_guard<std::mutex> lock(s.m_);
            s.active_.erase(key);
        }
    } unregister{*this, key};
    log_event("job_started",
              nlohmann::json{{"job_id", claim.id}, {"attempt", claim.attempts}, {"outputs", claim.run}}.dump());
    // By file, in the order of their first output: each file is read once for
    // all its outputs, and files run side by side up to the service's workers
    // (each takes an import slot for its child, so the gate still bounds them).
    std::vector<std::vector<int>> files;
    std::map<int, size_t> file_slot;
    for (const int index : claim.run) {
        const int file = claim.outputs.at(static_cast<size_t>(index)).file;
        const auto [it, added] = file_slot.try_emplace(file, files.size());
        if (added) files.emplace_back();
        files[it->second].push_back(index);
    }
    // Largest files first (by their bytes, which their parsing follows): the last
    // file to start is a small one, so the cores idle least at the end.
    auto bytes_of = [&claim](const std::vector<int>& outs) {
        const int file = claim.outputs.at(static_cast<size_t>(outs.front())).file;
        for (const JobInput& in : claim.inputs)
            if (in.index == file) return in.bytes;
        return int64_t(0);
    };
    std::stable_sort(files.begin(), files.end(),
                     [&](const std::vector<int>& a, const std::vector<int>& b) { return bytes_of(a) > bytes_of(b); });
    std::atomic<size_t> next{0};
    auto take_files = [&] {
        for (size_t k = next++; k < files.size(); k = next++) {
            if (cancel->load() || !store_->running(claim.id)) return;
            try {
                run_file(claim, files[k], cancel);
            } catch (const std::exception& e) {
                // A store that failed mid-file: the claim ends as a store failure does.
                log_event("job_runner_error", nlohmann::json{{"job_id", claim.id}, {"error", e.what()}}.dump(
                                                  -1, ' ', false, kReplaceBadUtf8));
            }
        }
    };
    // One lane more than the import slots: a file's child holds a slot only
    // while it runs, so while one lane renders the scene its child handed
    // back, another lane's child already reads the next file. The children
    // stay within the slots; the renders pass the render gate.
    const size_t lanes = static_cast<size_t>(std::max(1, ctx_.config.workers)) + 1;
    const size_t helpers = std::min(files.size(), lanes) - 1;
    std::vector<std::thread> threads;
    for (size_t i = 0; i < helpers; ++i) threads.emplace_back(take_files);
    take_files();
    for (std::thread& t : threads) t.join();
    end_claim(claim);
}

void JobService::end_claim(const JobClaim& claim) {
    bool interrupted_by_stop = false;
    {
        std::lock_guard<std::mutex> lock(m_);
        interrupted_by_stop = stopping_;
    }
    if (store_->running(claim.id) && interrupted_by_stop) {
        // Stopped with work left: back to the queue, not counted as an interrupted run.
        const auto now = store_->get(claim.id);
        bool left = false;
        for (const JobOutput& o : now ? now->outputs : std::vector<JobOutput>{})
            for (const int index : claim.run) left = left || (o.index == index && !is_finished(o.state));
        if (left) {
            store_->requeue(claim);
            log_event("job_requeued", nlohmann::json{{"job_id", claim.id}}.dump());
            return;
        }
    }
    const std::optional<JobState> state = store_->finish(claim.id, unix_now_ms());
    if (!state) {  // deleted while running
        store_->remove(claim.id);
        remove_files(claim.id);
        ctx_.metrics.count_job_finished("canceled");
        log_event("job_canceled", nlohmann::json{{"job_id", claim.id}}.dump());
        return;
    }
    if (*state == JobState::running) return;  // other outputs are still at work (shared store)
    ctx_.metrics.count_job_finished(job_state_name(*state));
    log_event("job_finished", nlohmann::json{{"job_id", claim.id}, {"state", job_state_name(*state)}}.dump());
    webhooks_->notify();  // its callback (if any) became due with the finish
}

bool JobService::forced(const std::string& id) const {
    std::error_code ec;
    return fs::exists(job_dir(id) + "/" + kForceMarker, ec);
}

std::string JobService::input_path(const std::string& id, int file) const {
    return job_dir(id) + "/" + input_name(file);
}

std::string JobService::partial_path(const JobClaim& job, const std::string& artifact) const {
    // Written under a temporary name with the same extension (the converter
    // picks the format from it), then renamed: an artifact exists only complete.
    // With leases the name holds the claim's token: a run that lost its lease
    // and the one that took over never write the same temporary file.
    return job_dir(job.id) + "/partial-" + (job.lease.empty() ? std::string() : job.lease.substr(0, 12) + "-") +
           artifact;
}

std::vector<std::string> JobService::partial_paths(const JobClaim& job, const JobOutput& out) const {
    std::vector<std::string> paths;
    for (const ArtifactFile& f : output_artifacts(out)) paths.push_back(partial_path(job, f.name));
    return paths;
}

void JobService::output_failed(const JobClaim& job, const JobOutput& out, const std::exception& e) {
    const auto* error = dynamic_cast<const Error*>(&e);
    const auto* service_error = dynamic_cast<const ServiceError*>(&e);  // the render's time limit
    bool recorded = false;
    if (!error && !service_error) {
        recorded = store_->output_failed(job.id, out.index, "internal", e.what(), unix_now_ms(), job.lease);
    } else {
        const ProblemCode code = error ? ProblemCode(error->code()) : ProblemCode(service_error->code());
        recorded = store_->output_failed(job.id, out.index, code.name(),
                                         without_paths(e.what(), job_dir(job.id), ctx_.scratch.path()), unix_now_ms(),
                                         job.lease);
    }
    // The files it placed before it failed (the first views of a separate
    // layout) go with it: a failed output has no artifact. Not those of a run
    // that took its lease over (recorded is false then).
    if (!recorded) return;
    std::error_code ec;
    for (const ArtifactFile& f : output_artifacts(out)) fs::remove(artifact_path(job.id, f.name), ec);
}

int64_t JobService::place_artifact(const JobClaim& job, const std::string& name, const std::string& partial,
                                   int64_t placed_bytes, const std::shared_ptr<std::atomic<bool>>& cancel) {
    std::error_code ec;
    // A run whose lease was lost meanwhile leaves the artifact to the run that took over.
    if (!job.lease.empty() && !store_->renew(job)) {
        fs::remove(partial, ec);
        cancel->store(true);
        throw Error(ErrorCode::canceled, "the lease of this output was lost or its job canceled");
    }
    try {
        // The output's files placed already count before its success records them.
        check_artifact_quota(store_->artifact_bytes() + placed_bytes, static_cast<int64_t>(fs::file_size(partial, ec)),
                             ctx_.config.max_artifact_bytes, "the artifact " + name);
    } catch (const Error&) {
        fs::remove(partial, ec);
        throw;
    }
    const std::string final_path = artifact_path(job.id, name);
    fs::rename(partial, final_path, ec);
    if (ec) throw Error(ErrorCode::io, "cannot store the artifact " + name + ": " + ec.message());
    sync_dir(job_dir(job.id));
    return static_cast<int64_t>(fs::file_size(final_path, ec));
}

void JobService::output_stored(const JobClaim& job, const JobOutput& out, const std::vector<int64_t>& sizes,
                               const std::string& made_json, const std::string& content_sha256) {
    const std::vector<ArtifactFile> files = output_artifacts(out);
    std::string result_json = made_json;
    int64_t bytes = 0;
    for (const int64_t size : sizes) bytes += size;
    if (files.size() > 1) {  // the size of each file, for the job document
        nlohmann::json result = nlohmann::json::parse(made_json, nullptr, false);
        if (!result.is_object()) result = nlohmann::json::object();
        result["artifacts"] = nlohmann::json::array();
        for (size_t i = 0; i < files.size() && i < sizes.size(); ++i)
            result["artifacts"].push_back({{"name", files[i].name}, {"bytes", sizes[i]}});
        result_json = result.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
    }
    if (!store_->output_succeeded(job.id, out.index, bytes, result_json, unix_now_ms(), job.lease)) {
        if (!job.lease.empty())
            log_event("job_output_fenced", nlohmann::json{{"job_id", job.id}, {"output", out.index}}.dump());
        return;
    }
    if (content_sha256.empty()) return;
    for (const ArtifactFile& f : files)
        reuse_.remember(ArtifactReuse::key(content_sha256, out, f.name), artifact_path(job.id, f.name), result_json);
}

void JobService::store_artifact(const JobClaim& job, const JobOutput& out, const std::vector<std::string>& partials,
                                const std::string& result_json, const std::shared_ptr<std::atomic<bool>>& cancel,
                                const std::string& content_sha256) {
    const std::vector<ArtifactFile> files = output_artifacts(out);
    std::vector<int64_t> sizes;
    int64_t bytes = 0;
    for (size_t i = 0; i < files.size(); ++i) {
        try {
            sizes.push_back(place_artifact(job, files[i].name, partials.at(i), bytes, cancel));
            bytes += sizes.back();
        } catch (const std::exception&) {
            std::error_code ec;
            for (size_t k = i + 1; k < partials.size(); ++k) fs::remove(partials[k], ec);
            throw;
        }
    }
    output_stored(job, out, sizes, result_json, content_sha256);
}

}  // namespace nurbsrt::server
