// Request ids and the structured request log: one JSON object per line on
// stderr for every request (and for service events such as start and stop).
#pragma once

#include <string>

namespace nurbsrt::server {

// A fresh random request id (32 hex digits).
std::string new_request_id();
// The client's X-Request-Id when it is a safe token (1..64 of [A-Za-z0-9._-]),
// else a fresh id: nothing unchecked from a request reaches the log.
std::string request_id_from_header(const std::string& header_value);

struct RequestLogEntry {
    std::string request_id, method, route, remote;
    int status = 0;
    double duration_ms = 0;
    size_t bytes_in = 0, bytes_out = 0;
    std::string code;  // ErrorCode name for problem responses, else empty
};

void log_request(const RequestLogEntry& e);
// A service event: {"ts":..., "event": event, ...fields} where fields_json is a
// JSON object's text (or empty).
void log_event(const std::string& event, const std::string& fields_json = "");

}  // namespace nurbsrt::server
