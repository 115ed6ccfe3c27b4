// Prometheus metrics of the service (text exposition format 0.0.4):
// requests by route and status, request latency and render stage histograms,
// import failures by error code, scene cache hits and misses, batch jobs by
// state and finished jobs by result. Thread-safe.
#pragma once

#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

namespace nurbsrt::server {

class Metrics {
public:
    void observe_request(const std::string& route, int status, double seconds);
    void observe_stage(const std::string& stage, double seconds);
    void count_import_failure(const std::string& code);
    void count_cache(bool hit);
    void count_job_finished(const std::string& result);      // succeeded | failed | canceled
    void count_webhook_attempt(const std::string& outcome);  // delivered | retry | failed

    // Gauges are sampled by the caller when the text is produced.
    struct Gauges {
        int active = 0, queued = 0, max_active = 0, max_queued = 0;  // imports and conversions
        int renders_active = 0, renders_queued = 0;
        size_t render_memory_used = 0, render_memory_capacity = 0;
        size_t cache_bytes = 0, cache_entries = 0, cache_capacity = 0;
        int event_streams = 0, max_event_streams = 0;  // GET /v1/jobs/{id}/events open, and their cap
        std::map<std::string, int64_t> jobs_by_state;  // from the job store (shared: every instance's jobs)
        std::string instance, job_store;               // this process's id; the store's backend
    };
    std::string exposition(const Gauges& g) const;

private:
    struct Histogram {
        std::vector<uint64_t> buckets;  // cumulative counts are computed on output
        uint64_t count = 0;
        double sum = 0;
    };
    static void observe(Histogram& h, const std::vector<double>& bounds, double v);
    static void write_histogram(std::string& out, const std::string& name, const std::string& labels,
                                const Histogram& h, const std::vector<double>& bounds);

    mutable std::mutex m_;
    std::map<std::pair<std::string, int>, uint64_t> requests_;
    std::map<std::string, Histogram> latency_, stages_;
    std::map<std::string, uint64_t> import_failures_;
    uint64_t cache_hits_ = 0, cache_misses_ = 0;
    std::map<std::string, uint64_t> jobs_finished_;
    std::map<std::string, uint64_t> webhook_attempts_;
};

}  // namespace nurbsrt::server
