// The service's resources by route template, and the methods each answers:
// one table for logs and metrics (the route label), for 405 Method Not Allowed
// and its Allow header, for OPTIONS and for CORS preflights.
#pragma once

#include <string>

namespace nurbsrt::server {

// The route template of `path` ("/v1/jobs/{id}", ...), or "other" for a path
// that names no resource (never the raw path, which is the client's and unbounded).
std::string route_of(const std::string& path);

// The Allow header of a route (RFC 9110 §10.2.1): every method it answers,
// "GET, HEAD, OPTIONS", ...; "" for "other".
const char* allowed_methods(const std::string& route);

// True when `route` answers `method` (HEAD wherever GET is, RFC 9110 §9.3.2;
// OPTIONS on every known route, RFC 9110 §9.3.7).
bool allows_method(const std::string& route, const std::string& method);

}  // namespace nurbsrt::server
