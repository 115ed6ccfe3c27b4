// Registration of the HTTP routes, one file per group (server/*.cpp only).
#pragma once

namespace httplib {
class Server;
}

namespace nurbsrt::server {

struct ServerContext;

void add_render_routes(httplib::Server& svr, ServerContext& ctx);      // POST /v1/renders
void add_conversion_routes(httplib::Server& svr, ServerContext& ctx);  // POST /v1/conversions
void add_job_routes(httplib::Server& svr, ServerContext& ctx);         // /v1/jobs...
void add_file_routes(httplib::Server& svr, ServerContext& ctx);        // /v1/files...
void add_service_routes(httplib::Server& svr, ServerContext& ctx);     // /healthz /readyz /metrics /v1/openapi.json
void add_page_routes(httplib::Server& svr, ServerContext& ctx);        // GET / and /web/{name}: the web page

}  // namespace nurbsrt::server
