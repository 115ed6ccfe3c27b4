#include "server/routes/route_table.h"

#include <algorithm>
#include <regex>
#include <string_view>

namespace nurbsrt::server {

std::string route_of(const std::string& path) {
    static const char* known[] = {"/v1/renders", "/v1/conversions", "/v1/jobs",         "/v1/files", "/healthz",
                                  "/readyz",     "/metrics",        "/v1/openapi.json", "/"};
    for (const char* k : known)
        if (path == k) return k;
    // Job and stored-file resources by template (the id and name are the client's, unbounded).
    static const std::regex job("^/v1/jobs/[^/]+$"), artifact("^/v1/jobs/[^/]+/artifacts/[^/]+$");
    if (std::regex_match(path, job)) return "/v1/jobs/{id}";
    if (std::regex_match(path, artifact)) return "/v1/jobs/{id}/artifacts/{name}";
    static const std::regex file("^/v1/files/[^/]+$"), content("^/v1/files/[^/]+/content$");
    if (std::regex_match(path, file)) return "/v1/files/{id}";
    if (std::regex_match(path, content)) return "/v1/files/{id}/content";
    static const std::regex web_file("^/web/[A-Za-z0-9_.-]+$");
    if (std::regex_match(path, web_file)) return "/web/{name}";
    return "other";
}

const char* allowed_methods(const std::string& route) {
    if (route == "/v1/renders" || route == "/v1/conversions") return "POST, OPTIONS";
    if (route == "/v1/jobs" || route == "/v1/files") return "GET, HEAD, POST, OPTIONS";
    if (route == "/v1/files/{id}") return "GET, HEAD, PATCH, DELETE, OPTIONS";
    if (route == "/v1/jobs/{id}") return "GET, HEAD, DELETE, OPTIONS";
    if (route == "other") return "";
    return "GET, HEAD, OPTIONS";  // probes, metrics, the API document, artifacts, the web page
}

bool allows_method(const std::string& route, const std::string& method) {
    if (method.empty()) return false;
    const std::string_view allow = allowed_methods(route);
    for (size_t start = 0; start < allow.size();) {
        const size_t comma = std::min(allow.find(',', start), allow.size());
        if (allow.substr(start, comma - start) == method) return true;
        start = comma + 2;  // ", "
    }
    return false;
}

}  // namespace nurbsrt::server
