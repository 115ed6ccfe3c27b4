#include "server/http/problem.h"

#include <nlohmann/json.hpp>

namespace nurbsrt::server {
namespace {

int library_status(ErrorCode code) {
    switch (code) {
        case ErrorCode::invalid_argument:
        case ErrorCode::invalid_json:
            return 400;
        case ErrorCode::canceled:
            return 409;  // the resource's work was canceled
        // Pixels, faces, render memory, files or outputs of a job: the request is
        // well formed but asks for more than this service is configured to do,
        // RFC 9110 §15.5.21 422 Unprocessable Content. An upload over the size
        // limit is answered 413 Content Too Large (§15.5.14) with that status given explicitly.
        case ErrorCode::limit_exceeded:
            return 422;
        case ErrorCode::unsupported_format:
            return 415;
        case ErrorCode::unreadable_file:  // the CAD content is the problem
        case ErrorCode::no_faces:
        case ErrorCode::import_crashed:
        case ErrorCode::occt_failure:
            return 422;
        case ErrorCode::import_timeout:
            return 504;
        case ErrorCode::io:
        case ErrorCode::corrupt_scene:
        case ErrorCode::internal:
            return 500;
    }
    return 500;
}

int service_status(ServiceCode code) {
    switch (code) {
        case ServiceCode::unauthorized:
            return 401;
        case ServiceCode::not_found:
            return 404;
        case ServiceCode::method_not_allowed:
            return 405;
        case ServiceCode::request_timeout:
            return 408;
        case ServiceCode::overloaded:
            return 503;
        case ServiceCode::malformed_request:
            return 400;
        case ServiceCode::not_acceptable:
            return 406;
        case ServiceCode::not_implemented:
            return 501;
        case ServiceCode::strict_refused:
            return 422;
        case ServiceCode::render_timeout:
            return 504;
        case ServiceCode::interrupted:
            return 500;  // job errors only; never a request's
    }
    return 500;
}

const char* library_title(ErrorCode code) {
    switch (code) {
        case ErrorCode::invalid_argument:
            return "Invalid request";
        case ErrorCode::invalid_json:
            return "Invalid JSON";
        case ErrorCode::canceled:
            return "Canceled";
        case ErrorCode::limit_exceeded:
            return "Limit exceeded";
        case ErrorCode::unsupported_format:
            return "Unsupported format";
        case ErrorCode::unreadable_file:
            return "Unreadable CAD file";
        case ErrorCode::no_faces:
            return "No faces to render";
        case ErrorCode::import_crashed:
            return "Import crashed";
        case ErrorCode::occt_failure:
            return "CAD kernel failure";
        case ErrorCode::import_timeout:
            return "Import timed out";
        case ErrorCode::io:
            return "I/O error";
        case ErrorCode::corrupt_scene:
            return "Corrupt cached scene";
        case ErrorCode::internal:
            return "Internal error";
    }
    return "Internal error";
}

const char* service_title(ServiceCode code) {
    switch (code) {
        case ServiceCode::unauthorized:
            return "Unauthorized";
        case ServiceCode::not_found:
            return "Not found";
        case ServiceCode::method_not_allowed:
            return "Method not allowed";
        case ServiceCode::request_timeout:
            return "Request timeout";
        case ServiceCode::overloaded:
            return "Service overloaded";
        case ServiceCode::render_timeout:
            return "Render timed out";
        case ServiceCode::interrupted:
            return "Interrupted by a service restart";
        case ServiceCode::malformed_request:
            return "Malformed request";
        case ServiceCode::not_acceptable:
            return "Not acceptable";
        case ServiceCode::not_implemented:
            return "Not implemented";
        case ServiceCode::strict_refused:
            return "Refused by strict";
    }
    return "Internal error";
}

struct StatusOf {
    int operator()(ErrorCode c) const { return library_status(c); }
    int operator()(ServiceCode c) const { return service_status(c); }
};

struct TitleOf {
    const char* operator()(ErrorCode c) const { return library_title(c); }
    const char* operator()(ServiceCode c) const { return service_title(c); }
};

// The title of a status given instead of the code's own: the status's reason
// phrase (RFC 9110 §15), which says more than the code's title there.
const char* status_title(int status, ProblemCode code) {
    switch (status) {
        case 413:
            return "Content too large";
        case 414:
            return "URI too long";
        case 431:
            return "Request header fields too large";
        case 507:
            return "Insufficient storage";
        default:
            return problem_title(code);
    }
}

}  // namespace

int http_status(ProblemCode code) { return code.visit(StatusOf{}); }

const char* problem_title(ProblemCode code) { return code.visit(TitleOf{}); }

Problem make_problem(ProblemCode code, const std::string& detail, const std::string& request_id, int status) {
    if (status == 0) status = http_status(code);
    const nlohmann::json j = {
        {"type", std::string("urn:nurbsrt:error:") + code.name()},
        {"title", status == http_status(code) ? problem_title(code) : status_title(status, code)},
        {"status", status},
        {"detail", detail},
        {"code", code.name()},
        {"request_id", request_id},
    };
    // Invalid UTF-8 (from a file's content in an error message) is replaced, never thrown on.
    return {status, j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace)};
}

}  // namespace nurbsrt::server
