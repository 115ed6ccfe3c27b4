// Standard base64 (RFC 4648, with padding) for images and files in JSON responses.
#pragma once

#include <string>

namespace nurbsrt::server {

std::string base64_encode(const std::string& bytes);

}  // namespace nurbsrt::server
