#include "server/common/metrics.h"

#include <cstdio>

namespace nurbsrt::server {
namespace {

const std::vector<double>& latency_bounds() {
    static const std::vector<double> b = {0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1, 2.5, 5, 10, 30, 60, 120};
    return b;
}

std::string num(double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.9g", v);
    return buf;
}

}  // namespace

void Metrics::observe(Histogram& h, const std::vector<double>& bounds, double v) {
    if (h.buckets.empty()) h.buckets.assign(bounds.size(), 0);
    for (size_t i = 0; i < bounds.size(); ++i)
        if (v <= bounds[i]) {
            ++h.buckets[i];
            break;
        }
    ++h.count;
    h.sum += v;
}

void Metrics::observe_request(const std::string& route, int status, double seconds) {
    std::lock_guard<std::mutex> lock(m_);
    ++requests_[{route, status}];
    observe(latency_[route], latency_bounds(), seconds);
}

void Metrics::observe_stage(const std::string& stage, double seconds) {
    std::lock_guard<std::mutex> lock(m_);
    observe(stages_[stage], latency_bounds(), seconds);
}

void Metrics::count_import_failure(const std::string& code) {
    std::lock_guard<std::mutex> lock(m_);
    ++import_failures_[code];
}

void Metrics::count_cache(bool hit) {
    std::lock_guard<std::mutex> lock(m_);
    ++(hit ? cache_hits_ : cache_misses_);
}

void Metrics::count_job_finished(const std::string& result) {
    std::lock_guard<std::mutex> lock(m_);
    ++jobs_finished_[result];
}

void Metrics::count_webhook_attempt(const std::string& outcome) {
    std::lock_guard<std::mutex> lock(m_);
    ++webhook_attempts_[outcome];
}

void Metrics::write_histogram(std::string& out, const std::string& name, const std::string& labels, const Histogram& h,
                              const std::vector<double>& bounds) {
    uint64_t cumulative = 0;
    const std::string sep = labels.empty() ? "" : ",";
    for (size_t i = 0; i < bounds.size(); ++i) {
        cumulative += h.buckets.empty() ? 0 : h.buckets[i];
        out += name + "_bucket{" + labels + sep + "le=\"" + num(bounds[i]) + "\"} " + std::to_string(cumulative) + "\n";
    }
    out += name + "_bucket{" + labels + sep + "le=\"+Inf\"} " + std::to_string(h.count) + "\n";
    out += name + "_sum{" + labels + "} " + num(h.sum) + "\n";
    out += name + "_count{" + labels + "} " + std::to_string(h.count) + "\n";
}

std::string Metrics::exposition(const Gauges& g) const {
    std::lock_guard<std::mutex> lock(m_);
    std::string out;
    out += "# HELP nurbsrt_http_requests_total HTTP requests by route and status.\n";
    out += "# TYPE nurbsrt_http_requests_total counter\n";
    for (const auto& [k, v] : requests_)
        out += "nurbsrt_http_requests_total{route=\"" + k.first + "\",status=\"" + std::to_string(k.second) + "\"} " +
               std::to_string(v) + "\n";
    out += "# HELP nurbsrt_http_request_duration_seconds HTTP request latency by route.\n";
    out += "# TYPE nurbsrt_http_request_duration_seconds histogram\n";
    for (const auto& [route, h] : latency_)
        write_histogram(out, "nurbsrt_http_request_duration_seconds", "route=\"" + route + "\"", h, latency_bounds());
    out += "# HELP nurbsrt_render_stage_seconds Wall-clock time of each render stage.\n";
    out += "# TYPE nurbsrt_render_stage_seconds histogram\n";
    for (const auto& [stage, h] : stages_)
        write_histogram(out, "nurbsrt_render_stage_seconds", "stage=\"" + stage + "\"", h, latency_bounds());
    out += "# HELP nurbsrt_import_failures_total Failed imports and conversions by error code.\n";
    out += "# TYPE nurbsrt_import_failures_total counter\n";
    for (const auto& [code, v] : import_failures_)
        out += "nurbsrt_import_failures_total{code=\"" + code + "\"} " + std::to_string(v) + "\n";
    out += "# HELP nurbsrt_scene_cache_requests_total Scene cache lookups by result.\n";
    out += "# TYPE nurbsrt_scene_cache_requests_total counter\n";
    out += "nurbsrt_scene_cache_requests_total{result=\"hit\"} " + std::to_string(cache_hits_) + "\n";
    out += "nurbsrt_scene_cache_requests_total{result=\"miss\"} " + std::to_string(cache_misses_) + "\n";
    out +=
        "# HELP nurbsrt_jobs_finished_total Batch jobs finished since start, by result "
        "(canceled: deleted while running).\n";
    out += "# TYPE nurbsrt_jobs_finished_total counter\n";
    for (const char* result : {"succeeded", "failed", "canceled"}) {
        const auto it = jobs_finished_.find(result);
        out += std::string("nurbsrt_jobs_finished_total{result=\"") + result + "\"} " +
               std::to_string(it == jobs_finished_.end() ? 0 : it->second) + "\n";
    }
    out +=
        "# HELP nurbsrt_webhook_attempts_total Job callback attempts made by this instance, by outcome "
        "(retry: not delivered, tried again later; failed: given up).\n";
    out += "# TYPE nurbsrt_webhook_attempts_total counter\n";
    for (const char* outcome : {"delivered", "retry", "failed"}) {
        const auto it = webhook_attempts_.find(outcome);
        out += std::string("nurbsrt_webhook_attempts_total{outcome=\"") + outcome + "\"} " +
               std::to_string(it == webhook_attempts_.end() ? 0 : it->second) + "\n";
    }
    out += "# HELP nurbsrt_jobs Batch jobs in the store by state (queued: the job queue's depth).\n";
    out += "# TYPE nurbsrt_jobs gauge\n";
    for (const auto& [state, n] : g.jobs_by_state)
        out += "nurbsrt_jobs{state=\"" + state + "\"} " + std::to_string(n) + "\n";
    // An info metric (Prometheus naming practice): scrapes of several instances
    // behind one balancer tell which instance answered; the job gauges above
    // come from the store, so with a shared store they are the whole queue.
    out += "# HELP nurbsrt_instance_info This instance and its job store backend.\n";
    out += "# TYPE nurbsrt_instance_info gauge\n";
    out += "nurbsrt_instance_info{instance=\"" + g.instance + "\",job_store=\"" + g.job_store + "\"} 1\n";
    auto gauge = [&](const char* name, const char* help, double v) {
        out +=
            std::string("# HELP ") + name + " " + help + "\n# TYPE " + name + " gauge\n" + name + " " + num(v) + "\n";
    };
    gauge("nurbsrt_work_active", "Imports and conversions running.", g.active);
    gauge("nurbsrt_work_queued", "Imports and conversions waiting for a worker.", g.queued);
    gauge("nurbsrt_work_max_active", "Configured concurrent work limit.", g.max_active);
    gauge("nurbsrt_work_max_queued", "Configured queue length limit.", g.max_queued);
    gauge("nurbsrt_renders_active", "Renders running.", g.renders_active);
    gauge("nurbsrt_renders_queued", "Renders waiting for memory within the budget.", g.renders_queued);
    gauge("nurbsrt_render_memory_reserved_bytes", "Estimated memory of the renders running.",
          static_cast<double>(g.render_memory_used));
    gauge("nurbsrt_render_memory_capacity_bytes", "Memory budget left for renders (budget less cache and base).",
          static_cast<double>(g.render_memory_capacity));
    gauge("nurbsrt_scene_cache_bytes", "Estimated memory held by cached scenes.", static_cast<double>(g.cache_bytes));
    gauge("nurbsrt_scene_cache_entries", "Cached scenes.", static_cast<double>(g.cache_entries));
    gauge("nurbsrt_scene_cache_capacity_bytes", "Scene cache bound.", static_cast<double>(g.cache_capacity));
    gauge("nurbsrt_event_streams", "Job event streams open.", g.event_streams);
    gauge("nurbsrt_event_streams_max", "Job event streams allowed at once (--max-event-streams).", g.max_event_streams);
    return out;
}

}  // namespace nurbsrt::server
