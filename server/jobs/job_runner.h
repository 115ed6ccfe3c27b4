// Batch jobs at run time: the job store (server/store/job_store.h), the files under
// DATA_DIR/jobs/<id>/ (input-<n>.cad and the artifacts), the runner threads
// that take queued jobs from the store in submission order and run their
// files in parallel (up to --workers; each file read once for all its
// outputs) through the same admission gates as synchronous renders and
// conversions, restart recovery at start, cancellation, and the retention
// sweep. With a shared store (PostgreSQL) several instances run the same
// queue: a heartbeat renews the leases of the outputs this one runs and stops
// a run whose job was canceled elsewhere or whose lease was lost. Free of HTTP
// and JSON headers.
#pragma once

#include <atomic>
#include <condition_variable>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "server/jobs/artifact_reuse.h"
#include "server/jobs/webhooks.h"
#include "server/store/job_store.h"

namespace nurbsrt {
class PreparedScene;
}  // namespace nurbsrt

namespace nurbsrt::server {

struct ServerContext;

// The niceness of a job's work: its runner threads (and so the threads they
// start, a job render's among them) and its children. At 19 the kernel's
// scheduler weights it about 1:68 against normal work (CFS's
// sched_prio_to_weight: 15 vs 1024), so a client's render gets the cores at
// once while a large job runs (bench/fairness.sh: at 10, 1:9, a job dense
// enough to fill both cores cost the clients' renders 33-41 ms at p99, at 19
// 26-32 ms), and the job still has them whole when nothing else runs.
inline constexpr int kJobNice = 19;
// The threads of a job's frame and of its scene's preparation: 1, so that all
// of that work runs in the job's own niced threads, never in oneTBB's shared
// workers (job_file_run.cpp, run_render).
inline constexpr int kJobRenderThreads = 1;

// The one read of an input file that served some of a job's outputs: each
// output's statistics or report names it, and the job's statistics count them.
struct FileRead {
    std::string id;  // unique per read; empty: no read (the scene came from the cache)
    int file = 0;
    int served = 0;  // the read's users in the child: the import and each conversion
    double read_ms = 0;
};

class JobService {
public:
    // Opens the job store (--job-store, or DATA_DIR/jobs.db; throws Error(io)
    // when it cannot), creates DATA_DIR/jobs and checks it is writable. With
    // SQLite (one process) it also recovers jobs a dead service left running and
    // removes directories without a job and partial artifacts; a shared store
    // skips those sweeps (other instances' files are in flight there) and gets
    // a lost instance's work back by lease expiry. Runs nothing until start().
    explicit JobService(ServerContext& ctx);
    ~JobService();  // stop()
    JobService(const JobService&) = delete;
    JobService& operator=(const JobService&) = delete;

    void start();
    // Stops the runners: a running render is canceled and its job goes back to
    // the queue without counting the run; a conversion child finishes first.
    void stop();

    // Stores the inputs and queues the job (id and created time are set here);
    // `force`: its outputs are made anew, never served from an earlier job's
    // artifact (kept as a file beside the inputs, so every instance sees it).
    // Throws Error(overloaded) when max_queued_jobs are already waiting.
    void submit(JobRecord& job, const std::vector<const std::string*>& input_bytes, bool force = false);
    // DELETE: see JobStore::delete_job; a running job's render is canceled.
    JobStore::DeleteOutcome remove(const std::string& id);
    JobStore& store() { return *store_; }
    // The path of a stored artifact; the name must have passed valid_artifact_name.
    std::string artifact_path(const std::string& id, const std::string& artifact) const;
    // Removes expired jobs (and expired stored files, server/store/file_store.h) now;
    // returns how many jobs.
    int sweep();

private:
    void run_loop();
    void sweep_loop();
    void heartbeat_loop();
    void sweep_shared_leftovers();
    void run_claim(JobClaim& claim);
    // The claim's outputs of one input file (job_file_run.cpp): one isolated
    // child reads the file once, writes its conversions and hands back the
    // scene, which every render of the file then uses.
    void run_file(const JobClaim& claim, const std::vector<int>& outputs,
                  const std::shared_ptr<std::atomic<bool>>& cancel);
    // Serves the outputs an earlier job made already (artifact_reuse.h) and
    // returns the rest. `content_sha256`: the file's.
    std::vector<int> reuse_artifacts(const JobClaim& claim, const std::vector<int>& outputs,
                                     const std::string& content_sha256,
                                     const std::shared_ptr<std::atomic<bool>>& cancel);
    // The file's child: its conversions stored (or failed), and its scene
    // prepared when `want_scene`. Throws when the file's work ends there: the
    // import's error (its conversions failed with it, its renders are the
    // caller's), or Error(canceled) when the job was canceled or deleted.
    std::shared_ptr<const PreparedScene> run_file_child(const JobClaim& claim, const std::string& input,
                                                        const std::vector<const JobOutput*>& conversions,
                                                        bool want_scene,
                                                        const std::shared_ptr<std::atomic<bool>>& cancel,
                                                        FileRead& read, const std::string& content_sha256);
    void run_render(const JobClaim& claim, const JobOutput& out, const std::shared_ptr<const PreparedScene>& scene,
                    const FileRead& read, const std::shared_ptr<std::atomic<bool>>& cancel,
                    const std::string& content_sha256);
    // Fails the output with `e` (its message without the service's paths).
    void output_failed(const JobClaim& claim, const JobOutput& out, const std::exception& e);
    // Moves the written files of `out` (under their partial names, in
    // output_artifacts order) into place within the quota and records the
    // output's success with `result`; artifacts made here (`content_sha256` of
    // their input given) are kept for reuse.
    void store_artifact(const JobClaim& claim, const JobOutput& out, const std::vector<std::string>& partials,
                        const std::string& result_json, const std::shared_ptr<std::atomic<bool>>& cancel,
                        const std::string& content_sha256 = {});
    // Moves one written file into place under `name` (downloadable from then
    // on), the lease and the quota checked first (`placed_bytes`: the output's
    // files placed before it); returns its size.
    int64_t place_artifact(const JobClaim& claim, const std::string& name, const std::string& partial,
                           int64_t placed_bytes, const std::shared_ptr<std::atomic<bool>>& cancel);
    // Records the success of `out`, whose files are in place (`sizes`, in
    // output_artifacts order, listed in its result when there are several),
    // and keeps them for reuse when `content_sha256` is given.
    void output_stored(const JobClaim& claim, const JobOutput& out, const std::vector<int64_t>& sizes,
                       const std::string& result_json, const std::string& content_sha256);
    // The temporary name of the artifact `artifact` while it is written.
    std::string partial_path(const JobClaim& claim, const std::string& artifact) const;
    // Those of every file of `out`, in output_artifacts order.
    std::vector<std::string> partial_paths(const JobClaim& claim, const JobOutput& out) const;
    std::string input_path(const std::string& id, int file) const;
    // Whether the job's spec asked `force` (no artifact reuse).
    bool forced(const std::string& id) const;
    void end_claim(const JobClaim& claim);
    void remove_files(const std::string& id) const;
    std::string job_dir(const std::string& id) const;

    ServerContext& ctx_;
    std::string jobs_dir_;
    std::shared_ptr<JobStore> store_;  // shared: a canceled render's thread may report progress late
    std::string instance_;
    std::mutex submit_m_;

    std::mutex m_;
    std::condition_variable cv_;
    bool stopping_ = false;
    uint64_t submissions_ = 0;  // jobs submitted here: an idle runner wakes when it changes
    struct Active {
        JobClaim claim;
        std::shared_ptr<std::atomic<bool>> cancel;
    };
    std::map<uint64_t, Active> active_;  // claims at work, by a number of their own
    uint64_t next_active_ = 0;
    std::vector<std::thread> runners_;
    std::thread sweeper_, heartbeat_;
    std::unique_ptr<WebhookSender> webhooks_;
    ArtifactReuse reuse_;  // DATA_DIR/reuse  // callbacks of finished jobs (of any instance, with a shared store)
};

}  // namespace nurbsrt::server
