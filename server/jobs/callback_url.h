// The callback URL a job may name (server/jobs/webhooks.h sends to it): which URLs
// are accepted, and which addresses a callback may reach. Free of HTTP and
// JSON headers (the job spec parser uses it).
#pragma once

#include <string>

struct sockaddr;

namespace nurbsrt::server {

struct CallbackUrl {
    std::string scheme;  // http | https
    std::string host;    // a name, an IPv4 address, or an IPv6 address without brackets
    int port = 0;
    std::string target;  // path and query, at least "/"
};

// Parses and checks a callback URL: http or https, a host, an optional port,
// no user information (credentials would be stored and shown with the job),
// no fragment, at most 2048 characters; a literal non-public address (or
// "localhost") only when allowed. Throws Error(invalid_argument) naming
// callback_url and the problem.
CallbackUrl check_callback_url(const std::string& url, bool allow_private);

// False for addresses a callback must not reach unless allowed: unspecified,
// loopback, private (RFC 1918, RFC 4193), shared (RFC 6598), link-local,
// multicast, benchmarking, reserved and documentation ranges, and IPv4-mapped
// or NAT64 forms of those.
bool is_public_address(const sockaddr* address);

}  // namespace nurbsrt::server
