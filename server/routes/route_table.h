// The service's routes in one table: each resource's template, the pattern its
// paths match and the handler of each method it answers. The listener registers
// the handlers from it, and the logs and metrics (the route label), 405 Method
// Not Allowed with its Allow header, OPTIONS and CORS preflights read it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace httplib {
class Server;
struct Request;
struct Response;
}  // namespace httplib

namespace nurbsrt::server {

struct ServerContext;

// A handler (server/routes/routes.h); its Error or ServiceError becomes the
// problem+json answer of the error's code (handler_util.h, guarded).
using RouteHandler = void (*)(ServerContext& ctx, const httplib::Request& req, httplib::Response& res);

// The methods a route's handlers take; HEAD is answered wherever GET is (RFC 9110
// §9.3.2) and OPTIONS on every route (§9.3.7), by the listener.
enum class HttpMethod : uint8_t { get, post, patch, del };

struct RouteMethod {
    HttpMethod method;
    RouteHandler handler;
};

struct Route {
    const char* name;     // the template: "/v1/jobs/{id}" (never the raw path: it is the client's, unbounded)
    const char* pattern;  // the regular expression paths match; its groups are req.matches[1...]
    std::vector<RouteMethod> methods;
};

// Every route, in the order paths are matched.
const std::vector<Route>& route_table();

// Registers every handler of the table with `svr`.
void register_routes(httplib::Server& svr, ServerContext& ctx);

// The route template of `path`, or "other" for a path that names no resource.
std::string route_of(const std::string& path);

// The Allow header of a route (RFC 9110 §10.2.1): every method it answers,
// "GET, HEAD, OPTIONS", ...; "" for "other".
const char* allowed_methods(const std::string& route);

// True when `route` answers `method` (HEAD wherever GET is, OPTIONS everywhere).
bool allows_method(const std::string& route, const std::string& method);

}  // namespace nurbsrt::server
