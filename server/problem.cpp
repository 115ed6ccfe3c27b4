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
        case ErrorCode::limit_exceeded: return 413;          // upload, pixels, faces, memory
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

Problem make_problem(ErrorCode code, const std::string& detail, const std::string& request_id, int status) {
    if (status == 0) status = http_status(code);
    const nlohmann::json j = {
        {"type", std::string("urn:nurbsrt:error:") + error_code_name(code)},
        {"title", problem_title(code)},
        {"status", status},
        {"detail", detail},
        {"code", error_code_name(code)},
        {"request_id", request_id},
    };
    // Invalid UTF-8 (from a file's content in an error message) is replaced, never thrown on.
    return {status, j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace)};
}

}  // namespace nurbsrt::server
