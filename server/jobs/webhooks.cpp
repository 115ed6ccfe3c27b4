#include "server/jobs/webhooks.h"

#include <httplib.h>
#include <netdb.h>
#include <nlohmann/json.hpp>
#include <sys/socket.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <random>
#include <sstream>

#include "core/error.h"
#include "server/jobs/job_document.h"
#include "server/common/metrics.h"
#include "server/common/request_log.h"
#include "server/common/sha256.h"

namespace nurbsrt::server {
namespace {

constexpr size_t kMinSecretLength = 16;
// How often idle senders look for due callbacks another instance's jobs (or a
// retry's due time) made: a second of latency on a webhook is unnoticed, and
// one indexed query a second per sender costs the store nothing.
constexpr auto kPollInterval = std::chrono::milliseconds(1000);
// Doubling stops here: a receiver that is down for hours is still tried hourly.
constexpr double kMaxBackoffS = 3600;
// Two senders: one slow receiver (up to the timeout) does not hold up the others.
constexpr int kSenderThreads = 2;
const char* const kCaBundle = "/etc/ssl/certs/ca-certificates.crt";

struct Outcome {
    bool delivered = false;
    bool permanent = false;  // no retry can help (the URL or what it resolves to is refused)
    int status = 0;
    std::string error;
};

// The address to connect to: the first that getaddrinfo gives, after every
// address the name has was checked (a name with one private address among
// public ones is refused: which one a client picks is not ours to know).
Outcome resolve(const CallbackUrl& u, bool allow_private, std::string& numeric) {
    addrinfo hints{};
    hints.ai_socktype = SOCK_STREAM;
    addrinfo* list = nullptr;
    const int rc = getaddrinfo(u.host.c_str(), std::to_string(u.port).c_str(), &hints, &list);
    if (rc != 0) return {false, false, 0, "cannot resolve " + u.host + ": " + gai_strerror(rc)};
    Outcome refused;
    for (addrinfo* a = list; a; a = a->ai_next) {
        char text[INET6_ADDRSTRLEN] = {};
        getnameinfo(a->ai_addr, a->ai_addrlen, text, sizeof text, nullptr, 0, NI_NUMERICHOST);
        if (numeric.empty()) numeric = text;
        if (!allow_private && !is_public_address(a->ai_addr))
            refused = {false, true, 0, u.host + " resolves to the non-public address " + std::string(text)};
    }
    freeaddrinfo(list);
    return refused;
}

Outcome post(const CallbackUrl& u, const std::string& body, const JobRecord& job, int attempt,
             const ServerConfig& config) {
    std::string address;
    if (Outcome r = resolve(u, config.webhook_allow_private, address); r.permanent || !r.error.empty()) return r;
    const bool v6 = u.host.find(':') != std::string::npos;
    httplib::Client cli(u.scheme + "://" + (v6 ? "[" + u.host + "]" : u.host) + ":" + std::to_string(u.port));
    // Connect to the address just checked, not to whatever a second lookup
    // answers (DNS rebinding); TLS still verifies the certificate for the name.
    cli.set_hostname_addr_map({{u.host, address}});
    const auto timeout = std::chrono::duration<double>(config.webhook_timeout_s);
    cli.set_connection_timeout(std::chrono::duration_cast<std::chrono::microseconds>(timeout));
    cli.set_read_timeout(std::chrono::duration_cast<std::chrono::microseconds>(timeout));
    cli.set_write_timeout(std::chrono::duration_cast<std::chrono::microseconds>(timeout));
    cli.set_follow_location(false);
    if (u.scheme == "https") {
        cli.enable_server_certificate_verification(true);
        if (std::ifstream(kCaBundle).good()) cli.set_ca_cert_path(kCaBundle);
    }
    const httplib::Headers headers = {
        {"User-Agent", "nurbsrt-webhook"},
        {"X-Nurbsrt-Event", "job.finished"},
        {"X-Nurbsrt-Delivery", job.id},
        {"X-Nurbsrt-Attempt", std::to_string(attempt)},
        {"X-Nurbsrt-Signature", "sha256=" + hmac_sha256_hex(config.webhook_secret, body)}};
    const auto res = cli.Post(u.target, headers, body, "application/json");
    if (!res) return {false, false, 0, "no answer: " + httplib::to_string(res.error())};
    if (res->status >= 200 && res->status < 300) return {true, false, res->status, ""};
    return {false, false, res->status, "answered HTTP " + std::to_string(res->status)};
}

}  // namespace

std::string read_webhook_secret_file(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw Error(ErrorCode::invalid_argument, "cannot read the webhook secret file " + path);
    std::stringstream ss;
    ss << in.rdbuf();
    std::string s = ss.str();
    const auto space = [](unsigned char c) { return std::isspace(c) != 0; };
    s.erase(s.begin(), std::find_if_not(s.begin(), s.end(), space));
    s.erase(std::find_if_not(s.rbegin(), s.rend(), space).base(), s.end());
    return s;
}

void check_webhook_secret(const std::string& secret) {
    if (secret.size() < kMinSecretLength)
        throw Error(ErrorCode::invalid_argument,
                    "the webhook secret must have at least " + std::to_string(kMinSecretLength) + " characters");
    for (unsigned char c : secret)
        if (c < 0x20 || c == 0x7f)
            throw Error(ErrorCode::invalid_argument, "the webhook secret must not contain control characters");
}

int64_t webhook_backoff_ms(int attempt, double base_s, double jitter) {
    const double delay = std::min(base_s * std::pow(2.0, std::max(attempt - 1, 0)), kMaxBackoffS);
    return static_cast<int64_t>(std::llround(delay * (1.0 + 0.25 * std::clamp(jitter, 0.0, 1.0)) * 1000.0));
}

WebhookSender::WebhookSender(JobStore& store, const ServerConfig& config, Metrics& metrics)
    : store_(store), config_(config), metrics_(metrics) {}

WebhookSender::~WebhookSender() { stop(); }

void WebhookSender::start() {
    for (int i = 0; i < kSenderThreads; ++i) threads_.emplace_back([this] { loop(); });
}

void WebhookSender::stop() {
    {
        std::lock_guard<std::mutex> lock(m_);
        stopping_ = true;
    }
    cv_.notify_all();
    for (std::thread& t : threads_) t.join();
    threads_.clear();
}

void WebhookSender::notify() {
    {
        std::lock_guard<std::mutex> lock(m_);
        ++wakeups_;
    }
    cv_.notify_all();
}

void WebhookSender::loop() {
    // An attempt in flight is held this long: past it, a sender that died
    // mid-attempt leaves the callback to another.
    const auto hold_ms = static_cast<int64_t>(config_.webhook_timeout_s * 3 * 1000) + 5000;
    for (;;) {
        uint64_t seen;
        {
            std::lock_guard<std::mutex> lock(m_);
            if (stopping_) return;
            seen = wakeups_;
        }
        std::optional<JobRecord> job;
        try {
            job = store_.claim_callback(unix_now_ms(), hold_ms);
        } catch (const std::exception& e) {
            log_event("webhook_store_error", nlohmann::json{{"error", e.what()}}.dump());
        }
        if (job) {
            attempt(*job);
            continue;
        }
        std::unique_lock<std::mutex> lock(m_);
        const int64_t now = unix_now_ms();
        if (next_due_ms_ <= now) next_due_ms_ = INT64_MAX;  // come due: the claim above took it (or another sender)
        const auto wait = std::min<int64_t>(std::chrono::milliseconds(kPollInterval).count(),
                                            std::max<int64_t>(next_due_ms_ - now, 1));
        cv_.wait_for(lock, std::chrono::milliseconds(wait), [&] { return stopping_ || wakeups_ != seen; });
    }
}

void WebhookSender::attempt(const JobRecord& job) {
    const int number = job.callback.attempts + 1;
    Outcome out;
    try {
        const CallbackUrl u = check_callback_url(job.callback_url, config_.webhook_allow_private);
        out = post(u, job_webhook_body(job), job, number, config_);
    } catch (const std::exception& e) {
        out = {false, true, 0, e.what()};
    }
    static thread_local std::mt19937_64 rng{std::random_device{}()};
    CallbackAttempt a;
    a.now_ms = unix_now_ms();
    a.status = out.status;
    a.error = out.error;
    if (out.delivered) {
        a.state = CallbackState::delivered;
    } else if (out.permanent || number >= config_.webhook_attempts) {
        a.state = CallbackState::failed;
    } else {
        a.state = CallbackState::pending;
        a.next_ms = a.now_ms + webhook_backoff_ms(number, config_.webhook_backoff_s,
                                                  std::uniform_real_distribution<double>(0, 1)(rng));
        std::lock_guard<std::mutex> lock(m_);
        next_due_ms_ = std::min(next_due_ms_, a.next_ms);
    }
    const char* outcome = out.delivered ? "delivered" : a.state == CallbackState::failed ? "failed" : "retry";
    metrics_.count_webhook_attempt(outcome);
    log_event(
        "webhook_attempt",
        nlohmann::json{
            {"job_id", job.id}, {"attempt", number}, {"outcome", outcome}, {"status", out.status}, {"error", out.error}}
            .dump());
    try {
        store_.callback_attempted(job.id, a);
    } catch (const std::exception& e) {
        log_event("webhook_store_error", nlohmann::json{{"job_id", job.id}, {"error", e.what()}}.dump());
    }
}

}  // namespace nurbsrt::server
