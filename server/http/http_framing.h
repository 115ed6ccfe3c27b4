// RFC 9112 message framing of a request, checked on its head (request line and
// header lines up to the blank line) before cpp-httplib acts on it. cpp-httplib
// 0.11 is lenient where leniency lets one request hide another (request
// smuggling): it takes the first of two Content-Length headers, parses "+10"
// as 10, skips header lines without a colon, reads no body of a GET (so the body
// is parsed as the next request), and reads the body of a request with an
// unknown Transfer-Encoding until the client closes. Here such a request is
// refused with 400 (or 501 for a transfer coding other than chunked) and its
// connection closed, as RFC 9112 §6.3 says a server must when it cannot tell
// where the message ends.
#pragma once

#include <string>
#include <string_view>

#include "server/common/service_error.h"

namespace nurbsrt::server {

// How the request's body is delimited, once its head is acceptable.
enum class BodyFraming {
    none,            // neither Content-Length nor Transfer-Encoding: no body (RFC 9112 §6.3 rule 7)
    content_length,  // exactly Content-Length bytes
    chunked,         // Transfer-Encoding: chunked
};

struct FramingVerdict {
    int status = 0;  // 0: acceptable; else 400 or 501, and the connection is closed after the answer
    ServiceCode code = ServiceCode::malformed_request;
    std::string detail;
    BodyFraming body = BodyFraming::none;
    bool ok() const { return status == 0; }
};

// `head`: the request line and header lines, each ending in CRLF, and the
// blank line that ends them.
FramingVerdict check_request_head(std::string_view head);

// `s` without the optional white space around a field value (RFC 9110 §5.6.3:
// spaces and tabs).
std::string_view trim_ows(std::string_view s);

}  // namespace nurbsrt::server
