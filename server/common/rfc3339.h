// Timestamps of the API's documents (jobs, stored files): RFC 3339 in UTC.
#pragma once

#include <cstdint>
#include <string>

namespace nurbsrt::server {

// RFC 3339 UTC with milliseconds ("2026-12-02T00:04:46.123Z") of Unix ms.
std::string rfc3339_utc(int64_t ms);

}  // namespace nurbsrt::server
