// The service's size limits on a render request (ServerConfig: max_dimension,
// max_pixels), checked before any work.
#pragma once

#include "options/render_request.h"
#include "server/common/config.h"

namespace nurbsrt::server {

// Throws Error(limit_exceeded) when the image is over the configured size limits.
void check_render_limits(const ServerConfig& config, const RenderRequest& r);

}  // namespace nurbsrt::server
