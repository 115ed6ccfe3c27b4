#include "server/http/http_framing.h"

#include <algorithm>
#include <cctype>
#include <vector>

#include "core/ascii.h"

namespace nurbsrt::server {
namespace {

// RFC 9110 §5.6.2 tchar: the characters of a field name (and of a method).
bool is_tchar(char c) {
    if (std::isalnum(static_cast<unsigned char>(c))) return true;
    return std::string_view("!#$%&'*+-.^_`|~").find(c) != std::string_view::npos;
}

// A bounded excerpt of client text for a message (printable ASCII only).
std::string excerpt(std::string_view s) {
    constexpr size_t kMaxExcerpt = 64;
    std::string out;
    for (char c : s.substr(0, kMaxExcerpt)) out += (c >= 0x20 && c < 0x7f) ? c : '?';
    return out;
}

FramingVerdict refuse(std::string detail, int status = 400, ServiceCode code = ServiceCode::malformed_request) {
    FramingVerdict v;
    v.status = status;
    v.code = code;
    v.detail = std::move(detail);
    return v;
}

// The head's lines without their CRLF, the blank last one left out; false
// where a CR or LF stands alone (RFC 9112 §2.2: a bare CR must be refused; a
// bare LF is refused too, since cpp-httplib would skip that line unread).
bool split_lines(std::string_view head, std::vector<std::string_view>& lines) {
    size_t start = 0;
    while (start < head.size()) {
        const size_t lf = head.find('\n', start);
        if (lf == std::string_view::npos || lf == start || head[lf - 1] != '\r') return false;
        const std::string_view line = head.substr(start, lf - 1 - start);
        if (line.find('\r') != std::string_view::npos) return false;
        if (line.empty()) return start + 2 == head.size();  // the blank line ends the head
        lines.push_back(line);
        start = lf + 1;
    }
    return false;
}

// What the framing headers say, gathered over the header lines.
struct Framing {
    std::vector<std::string_view> content_lengths;
    std::string transfer_encoding;  // the field lines' values joined with ", "
    int hosts = 0;
};

// One header line "name: value" (RFC 9112 §5): name a token right before the
// colon, no line folding, no NUL in the value.
std::string check_field_line(std::string_view line, Framing& f) {
    if (line.front() == ' ' || line.front() == '\t')
        return "a header line starts with whitespace (obsolete line folding, RFC 9112 §5.2)";
    const size_t colon = line.find(':');
    if (colon == std::string_view::npos) return "the header line '" + excerpt(line) + "' has no colon";
    const std::string_view name = line.substr(0, colon);
    if (name.empty() || !std::all_of(name.begin(), name.end(), is_tchar))
        return "the header name '" + excerpt(name) + "' is not a token (no whitespace before the colon, RFC 9112 §5.1)";
    const std::string_view value = trim_ows(line.substr(colon + 1));
    if (value.find('\0') != std::string_view::npos) return "the header '" + excerpt(name) + "' holds a NUL byte";
    const std::string key = ascii_lower(name);
    if (key == "content-length") f.content_lengths.push_back(value);
    if (key == "transfer-encoding")
        f.transfer_encoding += (f.transfer_encoding.empty() ? "" : ", ") + ascii_lower(value);
    if (key == "host") ++f.hosts;
    return {};
}

// Methods whose body cpp-httplib 0.11 never reads: a body sent with one would
// be parsed as the next request.
bool body_is_unread(std::string_view method) {
    return method == "GET" || method == "HEAD" || method == "TRACE" || method == "CONNECT";
}

}  // namespace

FramingVerdict check_request_head(std::string_view head) {
    std::vector<std::string_view> lines;
    if (!split_lines(head, lines) || lines.empty())
        return refuse("a line of the request head does not end with CRLF (RFC 9112 §2.2)");
    // The request line: method SP target SP version (cpp-httplib checks its parts).
    const std::string_view request_line = lines.front();
    const std::string_view method = request_line.substr(0, request_line.find(' '));
    const bool http10 = request_line.size() >= 8 && request_line.substr(request_line.size() - 8) == "HTTP/1.0";

    Framing f;
    for (size_t i = 1; i < lines.size(); ++i)
        if (std::string problem = check_field_line(lines[i], f); !problem.empty()) return refuse(std::move(problem));

    // RFC 9112 §3.2: exactly one Host in HTTP/1.1, at most one in HTTP/1.0.
    if (f.hosts > 1) return refuse("more than one Host header (RFC 9112 §3.2)");
    if (f.hosts == 0 && !http10)
        return refuse("a request without a Host header (HTTP/1.1 requires one, RFC 9112 §3.2)");

    FramingVerdict v;
    if (!f.transfer_encoding.empty()) {
        if (http10) return refuse("Transfer-Encoding in an HTTP/1.0 request (RFC 9112 §6.1)");
        // Only chunked, alone: any other coding (or chunked not last, or twice)
        // leaves the body's end unknown to us (RFC 9112 §6.1: 501).
        if (f.transfer_encoding != "chunked")
            return refuse("the transfer coding '" + excerpt(f.transfer_encoding) +
                              "' is not supported: send the body with Content-Length or 'Transfer-Encoding: chunked'",
                          501, ServiceCode::not_implemented);
        if (!f.content_lengths.empty())
            return refuse("both Transfer-Encoding and Content-Length: the body's length is ambiguous (RFC 9112 §6.1)");
        v.body = BodyFraming::chunked;
    } else if (!f.content_lengths.empty()) {
        if (f.content_lengths.size() > 1) return refuse("more than one Content-Length header (RFC 9112 §6.3)");
        const std::string_view n = f.content_lengths.front();
        constexpr size_t kMaxLengthDigits = 18;  // below 2^63: no overflow, and far above any upload limit
        if (n.empty() || n.size() > kMaxLengthDigits ||
            !std::all_of(n.begin(), n.end(), [](char c) { return c >= '0' && c <= '9'; }))
            return refuse("the Content-Length '" + excerpt(n) + "' is not a decimal number of bytes (RFC 9110 §8.6)");
        if (n.find_first_not_of('0') != std::string_view::npos) v.body = BodyFraming::content_length;
    }
    if (v.body != BodyFraming::none && body_is_unread(method))
        return refuse("a " + std::string(method) + " request carries no body: send it without one");
    return v;
}

std::string_view trim_ows(std::string_view s) {
    while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
    return s;
}

}  // namespace nurbsrt::server
