// The route handlers, one file per group; route_table.cpp maps paths and
// methods to them. Each takes the service context, the request (its path's
// parameters in req.matches) and the response to fill; errors are thrown
// (core/error.h, server/common/service_error.h) and answered as problem+json.
#pragma once

#include <string>

namespace httplib {
struct Request;
struct Response;
}  // namespace httplib

namespace nurbsrt::server {

struct ServerContext;

// routes_render.cpp: POST /v1/renders
void handle_render(ServerContext& ctx, const httplib::Request& req, httplib::Response& res);
// routes_conversions.cpp: POST /v1/conversions
void handle_conversion(ServerContext& ctx, const httplib::Request& req, httplib::Response& res);
// routes_jobs.cpp: POST and GET /v1/jobs, GET and DELETE /v1/jobs/{id}, GET /v1/jobs/{id}/artifacts/{name}
void handle_job_submit(ServerContext& ctx, const httplib::Request& req, httplib::Response& res);
void handle_job_list(ServerContext& ctx, const httplib::Request& req, httplib::Response& res);
void handle_job_get(ServerContext& ctx, const httplib::Request& req, httplib::Response& res);
void handle_job_delete(ServerContext& ctx, const httplib::Request& req, httplib::Response& res);
void handle_job_artifact(ServerContext& ctx, const httplib::Request& req, httplib::Response& res);
// The job id of a path; ServiceError(not_found) when it cannot be one.
std::string checked_id(const std::string& id);
// routes_job_events.cpp: GET /v1/jobs/{id}/events (Server-Sent Events)
void handle_job_events(ServerContext& ctx, const httplib::Request& req, httplib::Response& res);
// routes_files.cpp: POST and GET /v1/files, GET, PATCH and DELETE /v1/files/{id}, GET /v1/files/{id}/content
void handle_file_upload(ServerContext& ctx, const httplib::Request& req, httplib::Response& res);
void handle_file_list(ServerContext& ctx, const httplib::Request& req, httplib::Response& res);
void handle_file_get(ServerContext& ctx, const httplib::Request& req, httplib::Response& res);
void handle_file_patch(ServerContext& ctx, const httplib::Request& req, httplib::Response& res);
void handle_file_delete(ServerContext& ctx, const httplib::Request& req, httplib::Response& res);
void handle_file_content(ServerContext& ctx, const httplib::Request& req, httplib::Response& res);
// routes_service.cpp: GET /healthz (the process answers), /readyz (it can take
// work now), /metrics (Prometheus text), /v1/openapi.json (the API document)
void handle_healthz(ServerContext& ctx, const httplib::Request& req, httplib::Response& res);
void handle_readyz(ServerContext& ctx, const httplib::Request& req, httplib::Response& res);
void handle_metrics(ServerContext& ctx, const httplib::Request& req, httplib::Response& res);
void handle_openapi(ServerContext& ctx, const httplib::Request& req, httplib::Response& res);
// routes_page.cpp: GET / and /web/{name}, the web page
void handle_page(ServerContext& ctx, const httplib::Request& req, httplib::Response& res);
void handle_web_file(ServerContext& ctx, const httplib::Request& req, httplib::Response& res);

}  // namespace nurbsrt::server
