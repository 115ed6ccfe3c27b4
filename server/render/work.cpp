#include "server/render/work.h"

#include <string>
#include <thread>

#include "core/error.h"
#include "server/common/service_error.h"

namespace nurbsrt::server {

std::shared_ptr<AdmissionGate::Ticket> admit(ServerContext& ctx, AdmissionGate& gate, size_t bytes,
                                             const AdmissionWait& wait) {
    // A full queue turns a request away; patient work tries again shortly.
    constexpr auto kRetryWhenFull = std::chrono::milliseconds(200);
    const auto max_wait = wait.patient
                              ? std::chrono::milliseconds(std::chrono::hours(24))
                              : std::chrono::milliseconds(static_cast<long long>(ctx.config.queue_timeout_s * 1000));
    for (;;) {
        AdmissionGate::Refusal why;
        auto ticket = gate.enter(max_wait, why, wait.give_up, bytes, wait.order);
        if (ticket) return ticket;
        switch (why) {
            case AdmissionGate::Refusal::too_large:
                throw Error(ErrorCode::limit_exceeded, "the work needs an estimated " + std::to_string(bytes >> 20) +
                                                           " MiB; the service's memory for it is " +
                                                           std::to_string(gate.capacity_bytes() >> 20) + " MiB in all");
            case AdmissionGate::Refusal::gave_up:
                throw Error(ErrorCode::canceled, "the work was canceled while waiting");
            case AdmissionGate::Refusal::queue_full:
                if (wait.patient) {
                    if (wait.give_up && wait.give_up())
                        throw Error(ErrorCode::canceled, "the work was canceled while waiting");
                    std::this_thread::sleep_for(kRetryWhenFull);
                    continue;
                }
                throw ServiceError(ServiceCode::overloaded, "all workers are busy and the queue is full; retry later");
            case AdmissionGate::Refusal::queue_timeout:
                if (wait.patient) continue;
                throw ServiceError(ServiceCode::overloaded, "no worker became free in time; retry later");
            case AdmissionGate::Refusal::none:
                break;
        }
        throw Error(ErrorCode::internal, "admission refused without a reason");
    }
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
