#include "server/work.h"

#include "renderer/error.h"

namespace nurbsrt::server {

std::shared_ptr<AdmissionGate::Ticket> admit(ServerContext& ctx) {
    AdmissionGate::Refusal why;
    const auto wait = std::chrono::milliseconds(static_cast<long long>(ctx.config.queue_timeout_s * 1000));
    auto ticket = ctx.gate.enter(wait, why);
    if (!ticket) {
        throw Error(ErrorCode::overloaded, why == AdmissionGate::Refusal::queue_full
                                               ? "all workers are busy and the queue is full; retry later"
                                               : "no worker became free in time; retry later");
    }
    return ticket;
}

IsolationLimits isolation_limits(const ServerContext& ctx) {
    IsolationLimits l;
    l.time_limit_s = ctx.config.import_timeout_s;
    l.memory_limit_bytes = ctx.config.import_memory_bytes;
    l.scratch_dir = ctx.scratch.path();
    l.prescan.max_entities = ctx.config.import_max_entities;
    l.prescan.max_list_items = ctx.config.import_max_list_items;
    l.prescan.max_nesting = ctx.config.import_max_nesting;
    return l;
}

}  // namespace nurbsrt::server
