// Webhooks: a batch job may name a `callback_url`; when the job ends
// (succeeded or failed) the service POSTs the job document there, signed with
// HMAC-SHA256 over the exact body bytes under the service's secret:
//
//   X-Nurbsrt-Signature: sha256=<hex>    X-Nurbsrt-Event: job.finished
//   X-Nurbsrt-Delivery: <job id>         X-Nurbsrt-Attempt: <1, 2, ...>
//
// A 2xx answer delivers it; anything else (another status, no answer within
// the timeout, a refused connection) is retried with exponential back-off
// until the attempts are spent. The state lives in the job store, so a
// restart (or, with PostgreSQL, another instance) carries on where a sender
// stopped; delivery is at least once (the receiver tells repeats apart by the
// delivery id). Redirects are not followed, and non-public addresses
// (loopback, private, link-local, ...) are refused unless allowed, at
// submission for literal addresses and at delivery for what a name resolves
// to, connecting to the very address that was checked.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "server/jobs/callback_url.h"
#include "server/common/config.h"
#include "server/store/job_store.h"

namespace nurbsrt::server {

class Metrics;

// The secret from a file (surrounding whitespace trimmed). Throws
// Error(invalid_argument) when unreadable; check_webhook_secret for its form.
std::string read_webhook_secret_file(const std::string& path);
// At least 16 characters (a guessable secret signs nothing), no control characters.
void check_webhook_secret(const std::string& secret);

// The delay before attempt `attempt + 1` after attempt `attempt` (1-based)
// failed: base * 2^(attempt-1), at most an hour, plus `jitter` (0..1) times 25 %.
int64_t webhook_backoff_ms(int attempt, double base_s, double jitter);

// Sender threads: each takes the next due callback from the store, attempts
// it and records the outcome. notify() wakes them (a job just ended here);
// otherwise they poll, which is also how other instances' jobs reach them.
class WebhookSender {
public:
    WebhookSender(JobStore& store, const ServerConfig& config, Metrics& metrics);
    ~WebhookSender();  // stop()
    WebhookSender(const WebhookSender&) = delete;
    WebhookSender& operator=(const WebhookSender&) = delete;

    void start();
    // Stops after the attempts in flight (bounded by the timeout).
    void stop();
    void notify();

private:
    void loop();
    void attempt(const JobRecord& job);

    JobStore& store_;
    const ServerConfig& config_;
    Metrics& metrics_;
    std::mutex m_;
    std::condition_variable cv_;
    bool stopping_ = false;
    uint64_t wakeups_ = 0;
    int64_t next_due_ms_ = INT64_MAX;  // the earliest retry this process scheduled: wake for it, not a poll later
    std::vector<std::thread> threads_;
};

}  // namespace nurbsrt::server
