// `nurbsrt serve`: the HTTP service (API in api_schema/openapi.json).
#pragma once

#include "server/common/config.h"

namespace nurbsrt::server {

// Listens until SIGINT or SIGTERM; returns the exit status. Throws
// nurbsrt::Error for a bad configuration or an address that cannot be bound.
int run_server(const ServerConfig& config);

}  // namespace nurbsrt::server
