// Errors as application/problem+json (RFC 9457): type, title, status, detail,
// plus `code` (the ErrorCode or ServiceCode name) and `request_id`. The mapping
// from those codes to HTTP statuses lives here and nowhere else.
#pragma once

#include <string>

#include "server/common/service_error.h"

namespace nurbsrt::server {

inline constexpr const char* kProblemContentType = "application/problem+json";

int http_status(ProblemCode code);
const char* problem_title(ProblemCode code);

struct Problem {
    int status = 500;
    std::string body;  // the problem+json document
};

// `detail` is a human-readable explanation for this occurrence. `status`: the
// HTTP status when it is not the code's own (431 or 413 for limit_exceeded,
// ...); the body's `status` always equals the response's.
Problem make_problem(ProblemCode code, const std::string& detail, const std::string& request_id, int status = 0);

}  // namespace nurbsrt::server
