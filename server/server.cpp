#include "server/server.h"

#include <httplib.h>
#include <nlohmann/json.hpp>

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cctype>
#include <algorithm>
#include <chrono>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <optional>
#include <thread>

#include "core/error.h"
#include "renderer/image_module.h"
#include "server/http/api_keys.h"
#include "server/render/context.h"
#include "server/jobs/artifact_quota.h"
#include "server/common/cors.h"
#include "server/store/data_dir_lock.h"
#include "server/http/http_server.h"
#include "server/routes/handler_util.h"
#include "server/jobs/job_runner.h"
#include "server/jobs/webhooks.h"
#include "server/http/problem.h"
#include "server/common/request_log.h"
#include "server/routes/route_table.h"
#include "server/http/upload.h"

namespace nurbsrt::server {
namespace {

// A stop signal that comes before the server runs waits in steps this long
// (the listening loop starts within milliseconds of the port file).
constexpr auto kStartPoll = std::chrono::milliseconds(5);

ProblemCode code_for_status(int status) {
    switch (status) {
        case 404:
            return ServiceCode::not_found;
        case 405:
            return ServiceCode::method_not_allowed;
        case 408:
            return ServiceCode::request_timeout;
        case 413:
        case 431:
            return ErrorCode::limit_exceeded;
        case 415:
            return ErrorCode::unsupported_format;
        case 503:
            return ServiceCode::overloaded;
        default:
            return status < 500 ? ErrorCode::invalid_argument : ErrorCode::internal;
    }
}

ConnectionLimits connection_limits(const ServerConfig& config) {
    ConnectionLimits limits = config.connection;
    limits.max_body_bytes = config.max_upload_bytes;
    limits.retry_after_s = config.retry_after_s;
    return limits;
}

std::string format_seconds(double s) {
    char text[32];
    std::snprintf(text, sizeof text, "%g s", s);
    return text;
}

bool has_body(const httplib::Request& req) {
    return req.has_header("Transfer-Encoding") ||
           (req.has_header("Content-Length") && req.get_header_value("Content-Length") != "0");
}

// An answer a request gets from its headers alone, before its body is read.
struct EarlyAnswer {
    int status;
    ProblemCode code;
    std::string detail;
    std::string allow = {};  // the Allow header of a 405
};

// No such resource (404), or a method the resource does not answer (405 with
// Allow, RFC 9110 §15.5.6), answered before the body is read: cpp-httplib 0.11
// reads the body of a PUT or PATCH without Content-Length until the client
// closes, so an unrouted one would otherwise wait for the body timeout.
std::optional<EarlyAnswer> check_route(const httplib::Request& req) {
    const std::string route = route_of(req.path);
    if (route == "other") return EarlyAnswer{404, ServiceCode::not_found, "no such resource"};
    if (!allows_method(route, req.method))
        return EarlyAnswer{
            405, ServiceCode::method_not_allowed,
            "method " + req.method + " is not allowed on " + route + " (allowed: " + allowed_methods(route) + ")",
            allowed_methods(route)};
    return std::nullopt;
}

std::optional<EarlyAnswer> check_before_body(const httplib::Request& req, const ServerConfig& config,
                                             const ApiKeys& keys) {
    if (keys.enabled() && !ApiKeys::is_public_path(req.path) && !keys.accepts(req.get_header_value("Authorization")) &&
        !keys.accepts_key(req.get_header_value("X-Api-Key")))
        return EarlyAnswer{401, ServiceCode::unauthorized,
                           req.has_header("Authorization") || req.has_header("X-Api-Key")
                               ? "the API key is not valid"
                               : "this service requires an API key: send 'Authorization: Bearer <key>' or "
                                 "'X-Api-Key: <key>'"};
    if (std::optional<EarlyAnswer> a = check_route(req)) return a;
    // Compressed request bodies are refused, not inflated: cpp-httplib 0.11
    // inflates them without any bound (a 2 MB gzip body can expand to GiBs).
    const std::string encoding = req.get_header_value("Content-Encoding");
    if (!encoding.empty() && encoding != "identity")
        return EarlyAnswer{415, ErrorCode::unsupported_format,
                           "compressed request bodies (Content-Encoding) are not accepted: send the file "
                           "uncompressed"};
    // A declared length over the limit is answered now, not after reading (or
    // waiting for) the whole body.
    if (req.has_header("Content-Length")) {
        const std::string text = req.get_header_value("Content-Length");
        char* end = nullptr;
        errno = 0;
        const unsigned long long n = std::strtoull(text.c_str(), &end, 10);
        const bool valid = !text.empty() && *end == '\0' && errno == 0 && text.find('-') == std::string::npos;
        if (!valid) return EarlyAnswer{400, ErrorCode::invalid_argument, "the Content-Length header is not a number"};
        if (n > config.max_upload_bytes)
            return EarlyAnswer{413, ErrorCode::limit_exceeded,
                               "the upload exceeds the limit of " + std::to_string(config.max_upload_bytes) + " bytes"};
    }
    // A request with neither Content-Length nor Transfer-Encoding has no body
    // (RFC 9112 §6.3); cpp-httplib 0.11 would wait for one until the client closes.
    if (req.method == "POST" && !req.has_header("Content-Length") && !req.has_header("Transfer-Encoding"))
        return EarlyAnswer{400, ErrorCode::invalid_argument, no_body_detail(route_of(req.path))};
    return std::nullopt;
}

void write_port_file(const std::string& path, int port) {
    const std::string tmp = path + ".tmp";
    {
        std::ofstream out(tmp, std::ios::trunc);
        out << port << "\n";
        if (!out) throw Error(ErrorCode::io, "cannot write port file " + path);
    }
    std::filesystem::rename(tmp, path);
}

// OPTIONS on a known resource: 204 with Allow (RFC 9110 §9.3.7), and for a
// CORS preflight from an allowed origin the Access-Control-Allow-* headers.
// Answered before the API key is checked: browsers send a preflight without
// credentials (Fetch standard, CORS-preflight request).
bool answer_options(const httplib::Request& req, httplib::Response& res, const CorsPolicy& cors) {
    if (req.method != "OPTIONS") return false;
    const std::string route = route_of(req.path);
    if (route == "other") return false;
    res.status = 204;
    res.set_header("Allow", allowed_methods(route));
    if (req.has_header("Access-Control-Request-Method"))
        for (const auto& [name, value] : cors.preflight_headers(req.get_header_value("Origin"), allowed_methods(route)))
            res.set_header(name, value);
    if (has_body(req)) {
        GuardedServer::close_after_response();
        res.set_header("Connection", "close");
    }
    return true;
}

void install_early_answers(GuardedServer& svr, const ServerConfig& config, const ApiKeys& keys,
                           const CorsPolicy& cors) {
    // An answer before the body is read (route, auth, encoding, declared size)
    // also closes the connection: the unread body must not be parsed as a request.
    // Captured by address: the objects live in run_server, beyond the server.
    auto answer_early = [cfg = &config, k = &keys, c = &cors](const httplib::Request& req, httplib::Response& res,
                                                              bool expecting) {
        if (!res.has_header("X-Request-Id")) {
            const std::string id = request_id_from_header(req.get_header_value("X-Request-Id"));
            res.set_header("X-Request-Id", id);
            note_request_start(id);
        }
        // On every answer, refusals included: a page reads a 401 or 413 only with them.
        if (!res.has_header("Vary"))
            for (const auto& [name, value] : c->response_headers(req.get_header_value("Origin")))
                res.set_header(name, value);
        if (answer_options(req, res, *c)) return true;
        const std::optional<EarlyAnswer> a = check_before_body(req, *cfg, *k);
        if (!a) return false;
        if (a->code == ServiceCode::unauthorized) res.set_header("WWW-Authenticate", "Bearer realm=\"nurbsrt\"");
        if (!a->allow.empty()) res.set_header("Allow", a->allow);
        send_problem_with_status(res, a->status, a->code, a->detail);
        if (has_body(req)) {
            GuardedServer::close_after_response();
            res.set_header("Connection", "close");
        }
        // cpp-httplib writes the answer to an Expect: 100-continue without
        // adding the body's length itself (its routed answers get one).
        if (expecting) res.set_header("Content-Length", std::to_string(res.body.size()));
        return true;
    };
    // The request id and CORS headers are set once: by the 100-continue
    // handler when the client expects one, else here.
    svr.set_pre_routing_handler([answer_early](const httplib::Request& req, httplib::Response& res) {
        return answer_early(req, res, false) ? httplib::Server::HandlerResponse::Handled
                                             : httplib::Server::HandlerResponse::Unhandled;
    });
    // curl and browsers send large uploads with "Expect: 100-continue": answer
    // those that will be refused before the client sends the body at all.
    svr.set_expect_100_continue_handler([answer_early](const httplib::Request& req, httplib::Response& res) {
        return answer_early(req, res, true) ? res.status : 100;
    });
}

void install_error_answers(GuardedServer& svr, const ServerConfig& config) {
    // Statuses set by cpp-httplib itself (404 no route, 413 payload, 400 bad
    // request line, a body read that failed) get a problem body too; handlers'
    // own problems are kept. The body's status is always the response's.
    svr.set_error_handler(
        httplib::Server::HandlerWithResponse([cfg = &config](const httplib::Request& req, httplib::Response& res) {
            const ServerConfig& config = *cfg;
            if (!res.body.empty()) return httplib::Server::HandlerResponse::Unhandled;
            if (!res.has_header("X-Request-Id")) res.set_header("X-Request-Id", new_request_id());
            // cpp-httplib caps form-urlencoded bodies at 8 KiB and answers 413 itself;
            // a CAD file sent that way has the wrong content type, not the wrong size.
            if (res.status == 413 &&
                req.get_header_value("Content-Type").rfind("application/x-www-form-urlencoded", 0) == 0) {
                send_problem(res, ErrorCode::unsupported_format,
                             "form-urlencoded bodies are not accepted: send the file raw "
                             "(application/octet-stream) or as multipart/form-data");
                return httplib::Server::HandlerResponse::Handled;
            }
            const ReadFailure failure = GuardedServer::current_read_failure();
            if (failure == ReadFailure::bad_framing) {
                // Where this request ends is unknown or disputed: answer and close.
                const FramingVerdict framing = GuardedServer::current_framing();
                send_problem_with_status(res, framing.status, framing.code, framing.detail);
                res.set_header("Connection", "close");
                return httplib::Server::HandlerResponse::Handled;
            }
            if (failure == ReadFailure::header_timeout) {
                send_problem(
                    res, ServiceCode::request_timeout,
                    "the request headers did not arrive within " + format_seconds(config.connection.header_timeout_s));
                return httplib::Server::HandlerResponse::Handled;
            }
            if (failure == ReadFailure::body_timeout) {
                send_problem(res, ServiceCode::request_timeout,
                             "the request body did not arrive in time (at least " +
                                 std::to_string(static_cast<long long>(config.connection.min_body_rate / 1024)) +
                                 " KiB/s on average after " + format_seconds(config.connection.header_timeout_s) + ")");
                return httplib::Server::HandlerResponse::Handled;
            }
            // (A method a known resource does not answer got its 405 before routing.)
            const int status = failure == ReadFailure::body_too_large     ? 413
                               : failure == ReadFailure::header_too_large ? 431
                                                                          : res.status;
            const std::string detail =
                status == 413 ? "the upload exceeds the limit of " + std::to_string(config.max_upload_bytes) + " bytes"
                : status == 404 ? "no such resource"
                : status == 414 ? "the request target is too long"
                : status == 431 ? "the request headers exceed " + std::to_string(kMaxRequestHeaderBytes) + " bytes"
                                : "the request could not be handled";
            send_problem_with_status(res, status, code_for_status(status), detail);
            return httplib::Server::HandlerResponse::Handled;
        }));
    svr.set_exception_handler([](const httplib::Request&, httplib::Response& res, std::exception_ptr ep) {
        std::string what = "unexpected exception";
        try {
            if (ep) std::rethrow_exception(ep);
        } catch (const std::exception& e) {
            what = e.what();
        } catch (...) {}
        send_problem(res, ErrorCode::internal, what);
    });
}

void install_request_log(GuardedServer& svr, ServerContext& ctx) {
    svr.set_logger([c = &ctx](const httplib::Request& req, const httplib::Response& res) {
        const RequestNote note = take_request_note();
        RequestLogEntry e;
        e.request_id = res.get_header_value("X-Request-Id");
        e.method = req.method;
        e.route = route_of(req.path);
        e.remote = req.remote_addr;
        e.status = res.status;
        e.duration_ms = note.elapsed_s * 1000.0;
        e.bytes_in = req.body.size();
        for (const auto& [name, part] : req.files) e.bytes_in += part.content.size();
        e.bytes_out = res.body.size();
        e.code = note.code;
        log_request(e);
        c->metrics.observe_request(e.route, res.status, note.elapsed_s);
    });
}

// host name + 8 random hex digits: unique per process, readable in logs and leases.
std::string default_instance_id() {
    char host[256] = {0};
    if (gethostname(host, sizeof host - 1) != 0 || !*host) std::snprintf(host, sizeof host, "nurbsrt");
    std::string id;
    for (const char* p = host; *p && id.size() < 40; ++p)
        id += std::isalnum(static_cast<unsigned char>(*p)) || *p == '-' ? *p : '-';
    return id + "-" + new_request_id().substr(0, 8);
}

}  // namespace

int run_server(const ServerConfig& given) {
    given.validate();
    ServerConfig config = given;
    if (config.instance_id.empty()) config.instance_id = default_instance_id();
    if (!config.webhook_secret_file.empty())
        config.webhook_secret = read_webhook_secret_file(config.webhook_secret_file);
    if (!config.webhook_secret.empty()) check_webhook_secret(config.webhook_secret);
    // SIGINT/SIGTERM are taken by a waiting thread (blocked everywhere else,
    // before any thread starts); a peer closing its socket must not kill us.
    sigset_t stop_signals;
    sigemptyset(&stop_signals);
    sigaddset(&stop_signals, SIGINT);
    sigaddset(&stop_signals, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);
    signal(SIGPIPE, SIG_IGN);
    // Every render encodes an image: a service without its writer module must not
    // start (it would answer ready and fail every render), and it loads the
    // writer now, not in the first request.
    locate_image_module();
    const ImageWriterPreload image_writer;
    // The first renders' preliminary maps find their OpenGL contexts ready: one
    // per core (renders beyond that share the cores anyway), made while the
    // service opens its stores and starts listening.
    const int warm_maps = std::clamp(static_cast<int>(std::thread::hardware_concurrency()), 1, config.max_renders);
    std::jthread map_warm_up([warm_maps] { warm_up_preliminary_maps(warm_maps, kDefaultWidth, kDefaultHeight); });

    ApiKeys keys;
    if (!config.api_keys_file.empty()) keys.add_file(config.api_keys_file);
    if (config.api_keys) keys.add_list(*config.api_keys);

    // Before anything in the data directory is touched (scratch clean-up, job recovery).
    std::optional<DataDirLock> data_dir_lock;
    if (config.job_store.empty()) data_dir_lock.emplace(config.data_dir);
    if (config.max_artifact_bytes == 0) config.max_artifact_bytes = default_artifact_quota(config.data_dir);
    ServerContext ctx(config);
    // Opened (and recovered) before listening: a bad job database stops the start.
    JobService jobs(ctx);
    ctx.jobs = &jobs;
    GuardedServer svr(connection_limits(config));

    const CorsPolicy cors(config.cors_origins);
    install_early_answers(svr, config, keys, cors);
    install_error_answers(svr, config);
    install_request_log(svr, ctx);

    register_routes(svr, ctx);

    int port = config.port;
    if (port == 0) {
        port = svr.bind_to_any_port(config.host);
        if (port <= 0) throw Error(ErrorCode::io, "cannot listen on " + config.host + ": " + std::strerror(errno));
    } else if (!svr.bind_to_port(config.host, port)) {
        const int err = errno;
        throw Error(ErrorCode::io, "cannot listen on " + config.host + ":" + std::to_string(port) + ": " +
                                       (err == EADDRINUSE ? std::string("the port is in use by another process")
                                                          : std::string(std::strerror(err))));
    }
    svr.raise_listen_backlog();
    if (!config.port_file.empty()) write_port_file(config.port_file, port);

    const nlohmann::json fields = {{"host", config.host},
                                   {"port", port},
                                   {"data_dir", config.data_dir},
                                   {"workers", config.workers},
                                   {"max_queue", config.max_queue},
                                   {"max_upload_bytes", config.max_upload_bytes},
                                   {"max_pixels", config.max_pixels},
                                   {"max_faces", config.max_faces},
                                   {"render_timeout_s", config.render_timeout_s},
                                   {"import_timeout_s", config.import_timeout_s},
                                   {"cache_bytes", config.cache_bytes},
                                   {"api_keys", keys.size()},  // how many, never which
                                   {"cors_origins", config.cors_origins},
                                   {"header_timeout_s", config.connection.header_timeout_s},
                                   {"min_body_rate_bytes", config.connection.min_body_rate},
                                   {"max_connections", config.connection.max_connections},
                                   {"max_connections_per_client", config.connection.max_connections_per_client},
                                   {"job_runners", config.job_runners},
                                   {"max_queued_jobs", config.max_queued_jobs},
                                   {"job_retention_s", config.job_retention_s},
                                   {"max_stored_bytes", config.max_stored_bytes},
                                   {"max_artifact_bytes", config.max_artifact_bytes},
                                   {"instance", config.instance_id},
                                   {"webhooks_signed", !config.webhook_secret.empty()},
                                   {"webhook_allow_private", config.webhook_allow_private},
                                   {"job_store", ctx.jobs->store().describe()}};
    log_event("listening", fields.dump());
    jobs.start();

    std::atomic<bool> done{false};
    std::thread signal_waiter([&] {
        const timespec tick{0, 200 * 1000 * 1000};
        while (!done) {
            const int sig = sigtimedwait(&stop_signals, nullptr, &tick);
            if (sig == SIGINT || sig == SIGTERM) {
                log_event("stopping", nlohmann::json{{"signal", sig == SIGINT ? "SIGINT" : "SIGTERM"}}.dump());
                // cpp-httplib's stop() does nothing before listen_after_bind has
                // marked the server running: a signal that comes right after the
                // start waits for that (or the stop went unheard: the service
                // hung, 4 times in 20 with SIGTERM as the port file appeared).
                while (!done && !svr.is_running()) std::this_thread::sleep_for(kStartPoll);
                ctx.stopping = true;  // event streams end (the stop waits for their threads)
                svr.stop();
                return;
            }
        }
    });
    const bool ok = svr.listen_after_bind();
    done = true;
    signal_waiter.join();
    jobs.stop();
    // A canceled render (a job's, stopped just now, or one past its time limit)
    // ends on its own thread at its next block of rows, holding its worker
    // ticket until then: wait for those threads before the gate, the cache and
    // the rest of the context go away under them.
    for (int i = 0; i < 300 && (ctx.gate.active() > 0 || ctx.render_gate.active() > 0); ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
    log_event("stopped");
    return ok ? 0 : 1;
}

}  // namespace nurbsrt::server
