#include "server/problem.h"

#include <nlohmann/json.hpp>

namespace nurbsrt::server {

int http_status(ErrorCode code) {
    switch (code) {
        case ErrorCode::invalid_argument: return 400;
        case ErrorCode::unauthorized: return 401;
        case ErrorCode::not_found: return 404;
        case ErrorCode::request_timeout: return 408;
        case ErrorCode::canceled: return 409;                // the resource's work was canceled
        // Pixels, faces, render memory, files or outputs of a job: the request is
        // well formed but asks for more than this service is configured to do,
        // RFC 9110 §15.5.21 422 Unprocessable Content. An upload over the size
        // limit is answered 413 Content Too Large (§15.5.14) with that status given explicitly.
        case ErrorCode::limit_exceeded: return 422;
        case ErrorCode::unsupported_format: return 415;
        case ErrorCode::unreadable_file:                     // the CAD content is the problem
        case ErrorCode::no_faces:
        case ErrorCode::import_crashed:
        case ErrorCode::occt_failure: return 422;
        case ErrorCode::overloaded: return 503;
        case ErrorCode::import_timeout:
        case ErrorCode::render_timeout: return 504;
        case ErrorCode::interrupted:                         // job errors only; never a request's
        case ErrorCode::io:
        case ErrorCode::corrupt_scene:
        case ErrorCode::internal: return 500;
    }
    return 500;
}

const char* problem_title(ErrorCode code) {
    switch (code) {
        case ErrorCode::invalid_argument: return "Invalid request";
        case ErrorCode::unauthorized: return "Unauthorized";
        case ErrorCode::not_found: return "Not found";
        case ErrorCode::request_timeout: return "Request timeout";
        case ErrorCode::canceled: return "Canceled";
        case ErrorCode::limit_exceeded: return "Limit exceeded";
        case ErrorCode::unsupported_format: return "Unsupported format";
        case ErrorCode::unreadable_file: return "Unreadable CAD file";
        case ErrorCode::no_faces: return "No faces to render";
        case ErrorCode::import_crashed: return "Import crashed";
        case ErrorCode::occt_failure: return "CAD kernel failure";
        case ErrorCode::overloaded: return "Service overloaded";
        case ErrorCode::import_timeout: return "Import timed out";
        case ErrorCode::render_timeout: return "Render timed out";
        case ErrorCode::io: return "I/O error";
        case ErrorCode::corrupt_scene: return "Corrupt cached scene";
        case ErrorCode::interrupted: return "Interrupted by a service restart";
        case ErrorCode::internal: return "Internal error";
    }
    return "Internal error";
}

namespace {

// The title of a status given instead of the code's own: the status's reason
// phrase (RFC 9110 §15), which says more than the code's title there.
const char* status_title(int status, ErrorCode code) {
    switch (status) {
        case 405: return "Method not allowed";
        case 413: return "Content too large";
        case 414: return "URI too long";
        case 431: return "Request header fields too large";
        case 507: return "Insufficient storage";
        default: return problem_title(code);
    }
}

}  // namespace

Problem make_problem(ErrorCode code, const std::string& detail, const std::string& request_id, int status) {
    if (status == 0) status = http_status(code);
    const nlohmann::json j = {
        {"type", std::string("urn:nurbsrt:error:") + error_code_name(code)},
        {"title", status == http_status(code) ? problem_title(code) : status_title(status, code)},
        {"status", status},
        {"detail", detail},
        {"code", error_code_name(code)},
        {"request_id", request_id},
    };
    // Invalid UTF-8 (from a file's content in an error message) is replaced, never thrown on.
    return {status, j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace)};
}

}  // namespace nurbsrt::server
