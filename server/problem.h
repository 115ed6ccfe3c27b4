// Errors as application/problem+json (RFC 9457): type, title, status, detail,
// plus `code` (the ErrorCode name) and `request_id`. The mapping from
// ErrorCode to HTTP status lives here and nowhere else.
#pragma once

#include <string>

#include "renderer/error.h"

namespace nurbsrt::server {

inline constexpr const char* kProblemContentType = "application/problem+json";

int http_status(ErrorCode code);
const char* problem_title(ErrorCode code);

struct Problem {
    int status = 500;
    std::string body;  // the problem+json document
};

// `detail` is a human-readable explanation for this occurrence. `status`: the
// HTTP status when it is not the code's own (431 for limit_exceeded, 405 for
// not_found, ...); the body's `status` always equals the response's.
Problem make_problem(ErrorCode code, const std::string& detail, const std::string& request_id, int status = 0);

}  // namespace nurbsrt::server
