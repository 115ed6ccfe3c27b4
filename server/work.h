// Steps shared by renders and conversions: admission through the gate, and
// the isolation limits of a child process, from the configuration.
#pragma once

#include <memory>

#include "importer/isolated.h"
#include "server/context.h"

namespace nurbsrt::server {

// A ticket of the gate; throws Error(overloaded) when the queue is full or the
// wait ran out.
std::shared_ptr<AdmissionGate::Ticket> admit(ServerContext& ctx);

IsolationLimits isolation_limits(const ServerContext& ctx);

}  // namespace nurbsrt::server
