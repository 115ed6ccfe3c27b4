// Steps shared by renders and conversions: admission through a gate, and the
// isolation limits of a child process, from the configuration.
#pragma once

#include <functional>
#include <memory>

#include "importer/isolated.h"
#include "server/render/context.h"

namespace nurbsrt::server {

// How a caller waits for admission. A request waits at most the configured
// queue timeout; accepted batch work (`patient`) waits as long as it takes, in
// its place in the order. Either leaves the queue once `give_up` returns true
// (a client that disconnected, a deleted job), with Error(canceled).
struct AdmissionWait {
    bool patient = false;
    std::function<bool()> give_up;
    AdmissionGate::Order order = AdmissionGate::Order::fifo;
};

// A ticket of `gate` for work of `bytes` estimated memory. Throws
// Error(overloaded) when the queue is full or the wait ran out (a request),
// Error(limit_exceeded) when `bytes` exceed the gate's whole capacity, and
// Error(canceled) when the caller gave up.
std::shared_ptr<AdmissionGate::Ticket> admit(ServerContext& ctx, AdmissionGate& gate, size_t bytes = 0,
                                             const AdmissionWait& wait = {});
// An import/conversion slot for a request.
inline std::shared_ptr<AdmissionGate::Ticket> admit(ServerContext& ctx) { return admit(ctx, ctx.gate); }

IsolationLimits isolation_limits(const ServerContext& ctx);

}  // namespace nurbsrt::server
