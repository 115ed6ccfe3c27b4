// Service endpoints: GET /healthz (the process answers), /readyz (it can take
// work now), /metrics (Prometheus text), /v1/openapi.json (the API document).
#include <httplib.h>
#include <nlohmann/json.hpp>

#include "server/render/context.h"
#include "server/jobs/job_runner.h"
#include "server/routes/routes.h"

namespace nurbsrt::server {

void handle_healthz(ServerContext&, const httplib::Request&, httplib::Response& res) {
    res.set_content(R"({"status":"ok"})", "application/json");
}

void handle_readyz(ServerContext& ctx, const httplib::Request&, httplib::Response& res) {
    const int active = ctx.gate.active(), queued = ctx.gate.queued();
    const bool ready = queued < ctx.gate.max_queued() || active < ctx.gate.max_active();
    const nlohmann::json body = {{"status", ready ? "ready" : "overloaded"},
                                 {"active", active},
                                 {"queued", queued},
                                 {"max_active", ctx.gate.max_active()},
                                 {"max_queued", ctx.gate.max_queued()},
                                 {"renders",
                                  {{"active", ctx.render_gate.active()},
                                   {"queued", ctx.render_gate.queued()},
                                   {"max_active", ctx.render_gate.max_active()},
                                   {"memory_used_mb", double(ctx.render_gate.used_bytes()) / (1 << 20)},
                                   {"memory_capacity_mb", double(ctx.render_gate.capacity_bytes()) / (1 << 20)}}}};
    res.status = ready ? 200 : 503;
    if (!ready) res.set_header("Retry-After", std::to_string(ctx.config.retry_after_s));
    res.set_content(body.dump(), "application/json");
}

void handle_metrics(ServerContext& ctx, const httplib::Request&, httplib::Response& res) {
    Metrics::Gauges g;
    g.active = ctx.gate.active();
    g.queued = ctx.gate.queued();
    g.max_active = ctx.gate.max_active();
    g.max_queued = ctx.gate.max_queued();
    g.renders_active = ctx.render_gate.active();
    g.renders_queued = ctx.render_gate.queued();
    g.render_memory_used = ctx.render_gate.used_bytes();
    g.render_memory_capacity = ctx.render_gate.capacity_bytes();
    g.cache_bytes = ctx.cache.bytes();
    g.cache_entries = ctx.cache.entries();
    g.cache_capacity = ctx.cache.capacity();
    g.event_streams = ctx.event_streams.load();
    g.max_event_streams = ctx.config.event_stream_cap();
    if (ctx.jobs)
        for (const auto& [state, n] : ctx.jobs->store().count_by_state()) g.jobs_by_state[job_state_name(state)] = n;
    g.instance = ctx.config.instance_id;
    g.job_store = ctx.config.job_store.empty() ? "sqlite" : "postgresql";
    res.set_content(ctx.metrics.exposition(g), "text/plain; version=0.0.4; charset=utf-8");
}

void handle_openapi(ServerContext&, const httplib::Request&, httplib::Response& res) {
    const std::string_view doc = openapi_document();
    res.set_content(doc.data(), doc.size(), "application/json");
}

}  // namespace nurbsrt::server
