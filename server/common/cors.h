// Cross-origin resource sharing (Fetch standard, "CORS protocol"): which web
// origins may call the API from a browser, and the headers that tell the
// browser so. Off unless origins are configured (`serve --cors-origin`): a
// service without it answers no CORS header, and browsers keep other origins'
// pages from reading its answers.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace nurbsrt::server {

using HeaderList = std::vector<std::pair<std::string, std::string>>;

// How long a browser may reuse a preflight's answer. 600 s: Chromium caps the
// value at 7200 s and Firefox at 86400 s, but a shorter cache lets a changed
// origin list take effect within minutes while sparing a page one preflight
// per request.
inline constexpr int kCorsPreflightMaxAgeS = 600;

// Request headers a page may send: the two ways of giving an API key, the
// body's type (multipart and octet-stream are not CORS-safelisted types), the
// client's request id, and the conditional GET of artifacts.
inline constexpr const char* kCorsAllowedHeaders =
    "Authorization, X-Api-Key, Content-Type, Accept, X-Request-Id, If-None-Match";

// Response headers a page may read besides the CORS-safelisted ones
// (Cache-Control, Content-Type, Content-Length, ...).
inline constexpr const char* kCorsExposedHeaders =
    "X-Request-Id, Retry-After, Location, ETag, Content-Disposition, Server-Timing, Allow, X-Nurbsrt-Warnings";

// Checks and normalizes one configured origin: "scheme://host[:port]" with
// scheme http or https, as browsers serialize an origin (RFC 6454 §6.1):
// no path, no trailing slash, no wildcard. Throws Error(invalid_argument).
std::string normalized_origin(const std::string& origin);

class CorsPolicy {
public:
    CorsPolicy() = default;
    explicit CorsPolicy(const std::vector<std::string>& origins);  // each checked by normalized_origin

    bool enabled() const { return !origins_.empty(); }
    // True for an Origin header value that is one of the configured origins
    // (ASCII case-insensitively, as scheme and host are).
    bool allows(const std::string& origin) const;

    // Headers of any answer to a request with this Origin header: the echoed
    // origin for an allowed one, and Vary: Origin whenever CORS is on (the
    // answer differs by origin, so a shared cache must key on it).
    HeaderList response_headers(const std::string& origin) const;
    // Headers of the answer to a preflight (OPTIONS with
    // Access-Control-Request-Method) from an allowed origin, for a resource
    // answering `allow_methods`; none for another origin.
    HeaderList preflight_headers(const std::string& origin, const std::string& allow_methods) const;

private:
    std::vector<std::string> origins_;  // normalized
};

}  // namespace nurbsrt::server
