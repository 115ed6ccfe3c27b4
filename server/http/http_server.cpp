#include "server/http/http_server.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <cstring>
#include <deque>
#include <functional>
#include <map>
#include <mutex>
#include <thread>
#include <vector>

#include "server/http/problem.h"
#include "server/common/request_log.h"

namespace nurbsrt::server {
namespace {

using Clock = std::chrono::steady_clock;

// Chunked transfer framing (chunk-size lines) on top of the upload limit.
constexpr size_t kBodyFramingAllowance = 64 * 1024;
// Threads kept above the connection cap, so that refusing a connection (a
// quick canned 503) never waits behind the connections it refuses.
constexpr int kSpareThreads = 32;
// Waits are cut into steps this long so a stopping server is noticed.
constexpr std::chrono::milliseconds kPollStep{100};
// Writes: the answer must drain to the client at all within this time.
constexpr std::chrono::milliseconds kWriteTimeout = std::chrono::seconds(30);
// Lingering close: unread input is drained this long at most (and stops after
// kLingerIdle without data), so the client reads the answer, not a reset.
constexpr std::chrono::milliseconds kLinger{2000}, kLingerIdle{500};
// Read buffer of a connection, as cpp-httplib's own SocketStream (its line
// reader asks for one byte at a time).
constexpr size_t kReadBufferBytes = 4096;
// Connections beyond the caps that may still be served as health probes at
// once: enough for an orchestrator's liveness and readiness probes and a
// balancer's checks, few enough that they cannot be used to pass the caps.
constexpr int kProbeSlots = 8;
// A probe's request line must arrive within this time (probes send it at
// once); a connection that is slower is refused like any other beyond the caps.
constexpr std::chrono::milliseconds kProbeLineWait{500};
// The request line of a probe fits in this many bytes.
constexpr size_t kProbeLineBytes = 64;
// Admission follows the accept order (below); a connection whose turn does not
// come within this time (its predecessor's thread never got to decide) is
// decided anyway, so one lost turn cannot stall every later connection.
constexpr auto kAdmissionTurnWait = std::chrono::seconds(2);

// The accept order of the connection the current thread serves: cpp-httplib
// accepts on one thread and hands each socket to the pool as one task.
thread_local uint64_t t_accept_ticket = 0;

// Threads grow with the open connections up to a cap and then stay (an idle
// thread costs its stack's address space, a few KiB of memory): a connection
// never waits for a thread that a slow client holds. Tasks beyond the cap wait.
class ElasticPool final : public httplib::TaskQueue {
public:
    explicit ElasticPool(size_t max_threads) : max_threads_(max_threads) {}
    ~ElasticPool() override { shutdown(); }

    void enqueue(std::function<void()> fn) override {
        std::lock_guard lock(mutex_);
        tasks_.push_back({next_ticket_++, std::move(fn)});
        if (idle_ < tasks_.size() && threads_.size() < max_threads_) threads_.emplace_back([this] { work(); });
        cond_.notify_one();
    }

    void shutdown() override {
        {
            std::lock_guard lock(mutex_);
            if (stopping_) return;
            stopping_ = true;
        }
        cond_.notify_all();
        for (std::thread& t : threads_) t.join();
    }

private:
    void work() {
        for (;;) {
            Task task;
            {
                std::unique_lock lock(mutex_);
                ++idle_;
                cond_.wait(lock, [&] { return stopping_ || !tasks_.empty(); });
                --idle_;
                if (tasks_.empty()) return;  // stopping and nothing left
                task = std::move(tasks_.front());
                tasks_.pop_front();
            }
            t_accept_ticket = task.ticket;
            task.fn();
        }
    }

    const size_t max_threads_;
    std::mutex mutex_;
    std::condition_variable cond_;
    struct Task {
        uint64_t ticket = 0;
        std::function<void()> fn;
    };
    std::deque<Task> tasks_;
    uint64_t next_ticket_ = 0;
    std::vector<std::thread> threads_;
    size_t idle_ = 0;
    bool stopping_ = false;
};

// One connection's socket, read buffer and state across its requests.
struct Connection {
    socket_t sock = -1;
    const std::atomic<socket_t>* listening = nullptr;  // INVALID_SOCKET once the server stops
    std::string remote_ip, local_ip;
    int remote_port = 0, local_port = 0;
    std::array<char, kReadBufferBytes> buffer{};
    size_t pos = 0, len = 0;
    ReadFailure failure = ReadFailure::none;
    FramingVerdict framing;  // of the current request's head, once read
    bool close_requested = false;
    Clock::time_point last_read{};  // when the parser last got bytes: a handler's request is in by then
    bool buffered() const { return pos < len; }
};

thread_local Connection* t_connection = nullptr;

std::string address_of(const sockaddr_storage& a, int& port) {
    char text[INET6_ADDRSTRLEN] = {};
    if (a.ss_family == AF_INET) {
        const auto* in = reinterpret_cast<const sockaddr_in*>(&a);
        inet_ntop(AF_INET, &in->sin_addr, text, sizeof text);
        port = ntohs(in->sin_port);
    } else if (a.ss_family == AF_INET6) {
        const auto* in6 = reinterpret_cast<const sockaddr_in6*>(&a);
        inet_ntop(AF_INET6, &in6->sin6_addr, text, sizeof text);
        port = ntohs(in6->sin6_port);
    }
    return text;
}

// Waits until `sock` is ready for `events` or `ms` passed; false on timeout or error.
bool wait_for(socket_t sock, short events, std::chrono::milliseconds timeout) {
    pollfd p{sock, events, 0};
    for (;;) {
        const int r = ::poll(&p, 1, static_cast<int>(timeout.count()));
        if (r < 0 && errno == EINTR) continue;
        return r > 0;
    }
}

bool send_all(socket_t sock, const char* data, size_t size) {
    while (size > 0) {
        if (!wait_for(sock, POLLOUT, kWriteTimeout)) return false;
        const ssize_t n = ::send(sock, data, size, MSG_NOSIGNAL);
        if (n < 0 && (errno == EINTR || errno == EAGAIN)) continue;
        if (n <= 0) return false;
        data += n;
        size -= static_cast<size_t>(n);
    }
    return true;
}

// A complete answer written without cpp-httplib, for a connection that is
// refused or whose request never got as far as routing.
void send_canned_problem(socket_t sock, int status, const char* reason, ProblemCode code, const std::string& detail,
                         int retry_after_s) {
    const std::string id = new_request_id();
    const Problem p = make_problem(code, detail, id, status);
    std::string head = "HTTP/1.1 " + std::to_string(status) + " " + reason + "\r\n";
    head += "Content-Type: " + std::string(kProblemContentType) + "\r\n";
    head += "Content-Length: " + std::to_string(p.body.size()) + "\r\n";
    head += "X-Request-Id: " + id + "\r\n";
    if (retry_after_s > 0) head += "Retry-After: " + std::to_string(retry_after_s) + "\r\n";
    head += "Connection: close\r\n\r\n";
    send_all(sock, (head + p.body).data(), head.size() + p.body.size());
}

// One request of a connection, as cpp-httplib reads and answers it: reads
// through the connection's buffer against the request's deadlines and size
// caps (see the header), and records why it stopped in Connection::failure.
class RequestStream final : public httplib::Stream {
public:
    RequestStream(Connection& c, const ConnectionLimits& limits) : c_(c), limits_(limits), start_(Clock::now()) {
        c_.framing = FramingVerdict{};
    }

    bool is_readable() const override { return c_.buffered() || wait_for(c_.sock, POLLIN, kPollStep); }
    bool is_writable() const override { return wait_for(c_.sock, POLLOUT, kWriteTimeout); }

    ssize_t read(char* ptr, size_t size) override {
        if (c_.failure != ReadFailure::none) return -1;
        // A request without Content-Length or Transfer-Encoding has no body
        // (RFC 9112 §6.3); cpp-httplib would read a PUT, PATCH or DELETE's
        // until the client closes. The buffered bytes are the next request's.
        if (!in_headers_ && c_.framing.body == BodyFraming::none) return 0;
        if (!c_.buffered()) {
            if (!wait_readable()) return -1;
            const ssize_t n = recv_retrying(c_.buffer.data(), c_.buffer.size());
            if (n <= 0) return n;
            c_.pos = 0;
            c_.len = static_cast<size_t>(n);
        }
        const size_t n = std::min(size, c_.len - c_.pos);
        std::memcpy(ptr, c_.buffer.data() + c_.pos, n);
        c_.pos += n;
        c_.last_read = Clock::now();
        account(ptr, n);
        return c_.failure == ReadFailure::none ? static_cast<ssize_t>(n) : -1;
    }

    ssize_t write(const char* ptr, size_t size) override {
        written_ += size;
        return send_all(c_.sock, ptr, size) ? static_cast<ssize_t>(size) : -1;
    }

    void get_remote_ip_and_port(std::string& ip, int& port) const override {
        ip = c_.remote_ip;
        port = c_.remote_port;
    }
    void get_local_ip_and_port(std::string& ip, int& port) const override {
        ip = c_.local_ip;
        port = c_.local_port;
    }
    socket_t socket() const override { return c_.sock; }

    bool in_headers() const { return in_headers_; }
    size_t header_bytes() const { return header_bytes_; }
    size_t written() const { return written_; }

private:
    ssize_t recv_retrying(char* to, size_t size) {
        for (;;) {
            const ssize_t n = ::recv(c_.sock, to, size, 0);
            if (n < 0 && (errno == EINTR || errno == EAGAIN)) continue;
            return n;
        }
    }

    // The request's deadline now: headers within header_timeout_s of the first
    // byte; the body at min_body_rate on average after the same grace.
    Clock::time_point deadline() const {
        const auto grace = std::chrono::duration<double>(limits_.header_timeout_s);
        if (in_headers_) return start_ + std::chrono::duration_cast<Clock::duration>(grace);
        const auto allowed = grace + std::chrono::duration<double>(body_bytes_ / limits_.min_body_rate);
        return body_start_ + std::chrono::duration_cast<Clock::duration>(allowed);
    }

    bool wait_readable() {
        for (;;) {
            if (*c_.listening == INVALID_SOCKET) return false;  // stopping: no request waits for its bytes
            const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline() - Clock::now());
            if (left.count() <= 0) {
                c_.failure = in_headers_ ? ReadFailure::header_timeout : ReadFailure::body_timeout;
                return false;
            }
            if (wait_for(c_.sock, POLLIN, std::min(left, kPollStep))) return true;
        }
    }

    // Counts bytes handed to the parser; finds the end of the headers (CRLF CRLF,
    // the only end cpp-httplib accepts) to switch to the body's deadline and cap,
    // and checks the head's framing there: cpp-httplib reads it a byte at a
    // time, so a refused head never reaches its parser's end.
    void account(const char* p, size_t n) {
        size_t i = 0;
        for (; in_headers_ && i < n; ++i) {
            tail_ = (tail_ << 8) | static_cast<unsigned char>(p[i]);
            ++header_bytes_;
            if (header_bytes_ <= kMaxRequestHeaderBytes) head_ += p[i];
            if (tail_ == 0x0D0A0D0Au) {
                in_headers_ = false;
                body_start_ = Clock::now();
                c_.framing = check_request_head(head_);
                if (!c_.framing.ok()) c_.failure = ReadFailure::bad_framing;
            }
        }
        body_bytes_ += n - i;
        if (in_headers_ && header_bytes_ > kMaxRequestHeaderBytes) c_.failure = ReadFailure::header_too_large;
        if (!in_headers_ && body_bytes_ > limits_.max_body_bytes + kBodyFramingAllowance)
            c_.failure = ReadFailure::body_too_large;
    }

    Connection& c_;
    const ConnectionLimits& limits_;
    const Clock::time_point start_;
    Clock::time_point body_start_{};
    bool in_headers_ = true;
    std::string head_;  // the request line and headers as received
    uint32_t tail_ = 0;
    size_t header_bytes_ = 0, written_ = 0;
    double body_bytes_ = 0;
};

// True when the connection's first bytes (peeked, not consumed) are the
// request line of a health probe, arriving within kProbeLineWait.
bool is_health_probe(socket_t sock) {
    const auto until = Clock::now() + kProbeLineWait;
    char line[kProbeLineBytes + 1] = {};
    for (;;) {
        const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(until - Clock::now());
        if (left.count() <= 0 || !wait_for(sock, POLLIN, left)) return false;
        const ssize_t n = ::recv(sock, line, kProbeLineBytes, MSG_PEEK);
        if (n <= 0) return false;
        const std::string_view head(line, static_cast<size_t>(n));
        if (head.find("\r\n") != std::string_view::npos || static_cast<size_t>(n) == kProbeLineBytes) {
            for (const char* probe : {"GET /healthz ", "GET /readyz ", "HEAD /healthz ", "HEAD /readyz "})
                if (head.rfind(probe, 0) == 0) return true;
            return false;
        }
        // Not all of the line yet: wait for more than what is buffered.
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
}

// Closes without a reset: the write side first, then unread input drained
// briefly (the client may still be sending a body we did not read).
void close_lingering(socket_t sock) {
    ::shutdown(sock, SHUT_WR);
    const auto until = Clock::now() + kLinger;
    char sink[16 * 1024];
    while (Clock::now() < until && wait_for(sock, POLLIN, kLingerIdle)) {
        const ssize_t n = ::recv(sock, sink, sizeof sink, 0);
        if (n <= 0 && !(n < 0 && errno == EINTR)) break;
    }
    ::close(sock);
}

}  // namespace

struct GuardedServer::Tracker {
    std::mutex mutex;
    int total = 0;
    std::atomic<int> probes{0};  // connections served in the reserved probe slots
    std::map<std::string, int> per_client;
    // Connections are admitted in accept order: a client's fifth connection
    // under a cap of four is the one refused, however the pool's threads are
    // scheduled (a thread that starts late would otherwise let a later
    // connection take its place).
    std::condition_variable turn;
    uint64_t next_turn = 0;
};

GuardedServer::GuardedServer(const ConnectionLimits& limits) : limits_(limits), tracker_(std::make_unique<Tracker>()) {
    const size_t threads = static_cast<size_t>(limits_.max_connections + kSpareThreads);
    new_task_queue = [threads] { return new ElasticPool(threads); };
    set_payload_max_length(limits_.max_body_bytes);
    // cpp-httplib binds with SO_REUSEPORT, so a second service on the same port
    // started silently and took half the connections. SO_REUSEADDR alone lets a
    // restart bind beside connections in TIME_WAIT, never beside a listener.
    set_socket_options([](socket_t sock) {
        const int yes = 1;
        ::setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
    });
    // cpp-httplib announces these in each answer's Keep-Alive header; the
    // connection loop below is what enforces them.
    set_keep_alive_max_count(static_cast<size_t>(limits_.max_requests_per_connection));
    set_keep_alive_timeout(static_cast<time_t>(std::ceil(limits_.keep_alive_timeout_s)));
}

GuardedServer::~GuardedServer() = default;

void GuardedServer::raise_listen_backlog() {
    // Linux applies a second listen() on a listening socket as a new backlog.
    const socket_t s = svr_sock_;
    if (s != INVALID_SOCKET) ::listen(s, SOMAXCONN);
}

ReadFailure GuardedServer::current_read_failure() { return t_connection ? t_connection->failure : ReadFailure::none; }

FramingVerdict GuardedServer::current_framing() { return t_connection ? t_connection->framing : FramingVerdict{}; }

void GuardedServer::close_after_response() {
    if (t_connection) t_connection->close_requested = true;
}

std::chrono::steady_clock::time_point GuardedServer::request_received_at() {
    return t_connection && t_connection->last_read != Clock::time_point{} ? t_connection->last_read : Clock::now();
}

std::function<bool()> GuardedServer::client_gone_check() {
    if (!t_connection) return {};
    const socket_t sock = t_connection->sock;
    // POLLRDHUP: the peer closed its side. HTTP/1.1 clients do not half-close
    // while they wait for an answer, so this means nobody will read it.
    return [sock] {
        pollfd p{sock, POLLRDHUP, 0};
        return ::poll(&p, 1, 0) > 0 && (p.revents & (POLLRDHUP | POLLHUP | POLLERR)) != 0;
    };
}

bool GuardedServer::process_and_close_socket(socket_t sock) {
    const int one = 1;
    ::setsockopt(sock, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    sockaddr_storage peer{};
    socklen_t peer_len = sizeof peer;
    int peer_port = 0;
    const std::string client =
        ::getpeername(sock, reinterpret_cast<sockaddr*>(&peer), &peer_len) == 0 ? address_of(peer, peer_port) : "";

    bool admitted = false;
    {
        std::unique_lock lock(tracker_->mutex);
        const uint64_t ticket = t_accept_ticket;
        tracker_->turn.wait_for(lock, kAdmissionTurnWait, [&] { return tracker_->next_turn >= ticket; });
        tracker_->next_turn = std::max(tracker_->next_turn, ticket + 1);
        tracker_->turn.notify_all();
        int& mine = tracker_->per_client[client];
        if (tracker_->total < limits_.max_connections && mine < limits_.max_connections_per_client) {
            ++tracker_->total;
            ++mine;
            admitted = true;
        } else if (mine == 0) {
            tracker_->per_client.erase(client);
        }
    }
    if (!admitted) {
        probe_or_refuse(sock, client, peer_port);
        return false;
    }
    const bool ok = serve_connection(sock, client, peer_port, limits_.max_requests_per_connection);
    {
        std::lock_guard lock(tracker_->mutex);
        --tracker_->total;
        if (--tracker_->per_client[client] <= 0) tracker_->per_client.erase(client);
    }
    return ok;
}

void GuardedServer::probe_or_refuse(socket_t sock, const std::string& client, int port) {
    if (tracker_->probes.fetch_add(1) < kProbeSlots && is_health_probe(sock)) {
        serve_connection(sock, client, port, 1);
        --tracker_->probes;
        return;
    }
    --tracker_->probes;
    log_event("connection_refused", "{\"remote\":\"" + client + "\",\"reason\":\"connection cap\"}");
    send_canned_problem(sock, 503, "Service Unavailable", ServiceCode::overloaded,
                        "too many open connections (from this address or in all); retry later", limits_.retry_after_s);
    close_lingering(sock);
}

bool GuardedServer::serve_connection(socket_t sock, const std::string& remote_ip, int remote_port, int max_requests) {
    Connection c;
    c.sock = sock;
    c.listening = &svr_sock_;
    c.remote_ip = remote_ip;
    c.remote_port = remote_port;
    sockaddr_storage a{};
    socklen_t len = sizeof a;
    if (::getsockname(sock, reinterpret_cast<sockaddr*>(&a), &len) == 0) c.local_ip = address_of(a, c.local_port);
    t_connection = &c;

    bool ok = false;
    const auto idle = std::chrono::milliseconds(static_cast<long long>(limits_.keep_alive_timeout_s * 1000));
    for (int served = 0; served < max_requests && svr_sock_ != INVALID_SOCKET; ++served) {
        // Wait for the next request's first byte (a stopping server ends the wait).
        bool readable = c.buffered();
        for (std::chrono::milliseconds waited{0}; !readable && waited < idle && svr_sock_ != INVALID_SOCKET;
             waited += kPollStep)
            readable = wait_for(sock, POLLIN, std::min(kPollStep, idle - waited));
        if (!readable) break;

        RequestStream stream(c, limits_);
        bool closed = false;
        const bool last = served + 1 == max_requests;
        ok = process_request(stream, last, closed, nullptr);
        // A request that failed before routing got no answer from cpp-httplib.
        if (stream.written() == 0 && stream.header_bytes() > 0 && c.failure != ReadFailure::none) {
            log_event("request_refused",
                      "{\"remote\":\"" + c.remote_ip + "\",\"reason\":\"" +
                          (c.failure == ReadFailure::header_timeout ? "header timeout" : "headers too large") + "\"}");
            if (c.failure == ReadFailure::header_timeout)
                send_canned_problem(sock, 408, "Request Timeout", ServiceCode::request_timeout,
                                    "the request headers did not arrive within the time limit", 0);
            else if (c.failure == ReadFailure::header_too_large)
                send_canned_problem(sock, 431, "Request Header Fields Too Large", ErrorCode::limit_exceeded,
                                    "the request headers exceed " + std::to_string(kMaxRequestHeaderBytes) + " bytes",
                                    0);
        }
        if (!ok || closed || c.close_requested || c.failure != ReadFailure::none) break;
    }
    t_connection = nullptr;
    // Input may be left unread (an early answer, a failed read): close lingering.
    if (c.close_requested || c.failure != ReadFailure::none || c.buffered()) {
        close_lingering(sock);
    } else {
        ::shutdown(sock, SHUT_RDWR);
        ::close(sock);
    }
    return ok;
}

}  // namespace nurbsrt::server
