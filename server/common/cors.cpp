#include "server/common/cors.h"

#include <cctype>
#include <regex>

#include "core/error.h"
#include "core/ascii.h"

namespace nurbsrt::server {
namespace {}  // namespace

std::string normalized_origin(const std::string& origin) {
    // A host name, an IPv4 address or a bracketed IPv6 address; a port of up to 5 digits.
    static const std::regex form(
        R"(^https?://(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9]([A-Za-z0-9.-]*[A-Za-z0-9])?)(:[0-9]{1,5})?$)", std::regex::icase);
    if (!std::regex_match(origin, form))
        throw Error(ErrorCode::invalid_argument,
                    "CORS origin '" + origin.substr(0, 100) +
                        "' is not an origin: give scheme://host[:port] with http or https, no path, no "
                        "trailing slash, no wildcard (e.g. https://app.example.com)");
    return ascii_lower(origin);
}

CorsPolicy::CorsPolicy(const std::vector<std::string>& origins) {
    for (const std::string& o : origins) origins_.push_back(normalized_origin(o));
}

bool CorsPolicy::allows(const std::string& origin) const {
    if (origin.empty()) return false;
    const std::string o = ascii_lower(origin);
    for (const std::string& a : origins_)
        if (a == o) return true;
    return false;
}

HeaderList CorsPolicy::response_headers(const std::string& origin) const {
    HeaderList h;
    if (!enabled()) return h;
    h.emplace_back("Vary", "Origin");
    if (!allows(origin)) return h;
    // The origin as the browser sent it: the Fetch standard's CORS check
    // compares Access-Control-Allow-Origin byte for byte with the request's origin.
    h.emplace_back("Access-Control-Allow-Origin", origin);
    h.emplace_back("Access-Control-Expose-Headers", kCorsExposedHeaders);
    return h;
}

HeaderList CorsPolicy::preflight_headers(const std::string& origin, const std::string& allow_methods) const {
    HeaderList h;
    if (!allows(origin)) return h;
    h.emplace_back("Access-Control-Allow-Methods", allow_methods);
    h.emplace_back("Access-Control-Allow-Headers", kCorsAllowedHeaders);
    h.emplace_back("Access-Control-Max-Age", std::to_string(kCorsPreflightMaxAgeS));
    return h;
}

}  // namespace nurbsrt::server
