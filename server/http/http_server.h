// The service's HTTP server: cpp-httplib's request parsing and routing, with the
// connection handling that a service in front of untrusted clients needs and
// cpp-httplib 0.11 lacks (server/*.cpp only: this header pulls in httplib.h).
//
// cpp-httplib gives each connection a pool thread for its whole life and only a
// per-read timeout, so a client sending one byte a second (slowloris), a slow
// body, or a lying Content-Length held a thread indefinitely, and a few dozen
// such connections blocked every route. Here, as Apache's mod_reqtimeout does:
//  - the request line and headers must arrive within `header_timeout_s` of the
//    request's first byte, and at most kMaxRequestHeaderBytes of them;
//  - the body must then keep an average rate of `min_body_rate` bytes/s after a
//    grace of `header_timeout_s`, and may not exceed the upload limit (chunked
//    bodies too, which cpp-httplib 0.11 does not bound);
//  - connections are capped in total and per client address (503 beyond), and
//    each runs on a thread of an elastic pool sized above the cap, so a slow
//    client delays only itself and a probe always finds a thread;
//  - beyond the caps, a few reserved slots still answer a health probe
//    (GET or HEAD of /healthz or /readyz, one request, then closed), so that an
//    orchestrator never restarts a healthy instance because clients (or one
//    balancer's address) hold every connection;
//  - the listen backlog is SOMAXCONN (cpp-httplib listens with 5: bursts were
//    reset), and TCP_NODELAY is set (a keep-alive answer written in two parts
//    otherwise waits ~40 ms for the client's delayed ACK, Nagle's algorithm);
//  - a connection closed before its body was read is closed lingering (write
//    side first, then the unread input drained briefly), so the client reads
//    the early answer (413, 415, 401) instead of a reset.
#pragma once

#include <httplib.h>

#include <chrono>
#include <cstddef>
#include <functional>
#include <memory>
#include <string>

#include "server/common/config.h"
#include "server/http/http_framing.h"

namespace nurbsrt::server {

// Request line + headers: cpp-httplib caps one line at 8 KiB but not their
// number; 64 KiB is 8 such lines and far above what browsers and curl send.
inline constexpr size_t kMaxRequestHeaderBytes = 64 * 1024;

// Why reading the current request stopped early (for the error handler's answer).
// bad_framing: its head breaks RFC 9112's framing rules (server/http/http_framing.h).
enum class ReadFailure { none, header_timeout, body_timeout, header_too_large, body_too_large, bad_framing };

class GuardedServer : public httplib::Server {
public:
    explicit GuardedServer(const ConnectionLimits& limits);
    ~GuardedServer() override;

    // After bind_to_port/bind_to_any_port: the listen backlog becomes SOMAXCONN.
    void raise_listen_backlog();

    // On a handler's thread: how reading the current request failed (none while
    // it is fine), and a request to close the connection after this answer
    // (an early answer before the body was read).
    static ReadFailure current_read_failure();
    // On a handler's thread: the framing check of the current request's head
    // (its status, code and detail when current_read_failure() is bad_framing).
    static FramingVerdict current_framing();
    static void close_after_response();
    // On a handler's thread: a check, cheap enough to poll, that is true once
    // the client of the current request has closed or reset its connection (so
    // its render or conversion can stop). Valid while the handler runs.
    static std::function<bool()> client_gone_check();
    // On a handler's thread: when the last bytes of the current request were
    // handed to cpp-httplib's parser, i.e. when the request was received (the
    // parsing of the last of its body, the routing and the handler come after);
    // now, off a connection's thread. Where a request's stage timings start:
    // receiving the body is the client's pace, not the service's work.
    static std::chrono::steady_clock::time_point request_received_at();

private:
    bool process_and_close_socket(socket_t sock) override;
    bool serve_connection(socket_t sock, const std::string& remote_ip, int remote_port, int max_requests);
    // A connection beyond the caps: served when it is a health probe and a
    // reserved slot is free, else refused with 503.
    void probe_or_refuse(socket_t sock, const std::string& client, int port);

    struct Tracker;
    ConnectionLimits limits_;
    std::unique_ptr<Tracker> tracker_;
};

}  // namespace nurbsrt::server
