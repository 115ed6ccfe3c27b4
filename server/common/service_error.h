// The service's own error conditions, apart from the library's ErrorCode
// (core/error.h): a route or resource that does not exist, a full queue, a
// missing API key, a request too slow to arrive, a render over the service's
// time limit, a job cut short by restarts. The renderer and importer never
// raise these; only server/ does, so they live here.
//
// A problem answer (server/http/problem.h) and a failed job output carry either
// kind of code: ProblemCode holds one of the two, with one name space
// ("not_found", "unreadable_file", ...) that the API documents as one enum.
#pragma once

#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include "core/error.h"

namespace nurbsrt::server {

enum class ServiceCode {
    not_found,           // no such route or resource
    method_not_allowed,  // a known resource asked with a method it does not answer (405 with Allow)
    overloaded,          // the work queue is full; retry later
    render_timeout,      // a render exceeded the service's time limit
    unauthorized,        // an API key is configured and the request has none or a wrong one
    request_timeout,     // the request's headers or body did not arrive in time (server/http/http_server.h)
    interrupted,         // a job's run was cut short by service restarts too often (server/jobs/job_runner.h)
    malformed_request,  // the request's HTTP framing or header syntax is invalid (RFC 9112; server/http/http_framing.h)
    not_acceptable,     // the Accept header admits none of the answer's media types (RFC 9110 §15.5.7: 406)
    not_implemented,    // a transfer coding other than chunked (RFC 9112 §6.1: 501)
    strict_refused,     // `strict` was asked and the conversion has warnings: 422, nothing written; the last code
                        // (tests iterate up to it)
};

// Stable machine-readable name ("not_found", ...), used in JSON errors and the job store.
const char* service_code_name(ServiceCode code);

// The code of a problem answer or a failed job output: a library ErrorCode
// (a bad file, a bad parameter, a canceled render) or a ServiceCode.
class ProblemCode {
public:
    ProblemCode(ErrorCode code) : code_(code) {}    // NOLINT: implicit on purpose, either kind is a problem code
    ProblemCode(ServiceCode code) : code_(code) {}  // NOLINT
    const char* name() const;
    bool operator==(const ProblemCode&) const = default;
    template <class F>
    auto visit(F&& f) const {
        return std::visit(static_cast<F&&>(f), code_);
    }

private:
    std::variant<ErrorCode, ServiceCode> code_;
};

// What server/ throws for its own conditions; handlers catch it beside nurbsrt::Error.
class ServiceError : public std::runtime_error {
public:
    ServiceError(ServiceCode code, const std::string& message) : std::runtime_error(message), code_(code) {}
    ServiceCode code() const { return code_; }

private:
    ServiceCode code_;
};

// The refusal of a conversion asked to be strict that has `warnings` (POST
// /v1/conversions and job outputs alike): strict_refused, every warning in the detail.
ServiceError strict_refusal(const std::vector<std::string>& warnings);

}  // namespace nurbsrt::server
