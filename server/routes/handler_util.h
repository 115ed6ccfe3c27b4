// Helpers shared by the route handlers (server/routes/ only: this header pulls
// in httplib.h): request ids, problem responses, content negotiation, and
// reading an upload (server/http/upload.h).
#pragma once

#include <httplib.h>
#include <nlohmann/json_fwd.hpp>

#include <initializer_list>
#include <map>
#include <string>
#include <vector>

#include "core/error.h"
#include "server/common/service_error.h"
#include "server/store/file_store.h"
#include "server/http/upload.h"

namespace nurbsrt::server {

struct ServerContext;

// The request id of the request being handled (set before routing).
std::string request_id(const httplib::Response& res);

// Per-request bookkeeping of the handling thread for the request log
// (cpp-httplib runs a request's pre-routing, handler and logger on one thread).
void note_request_start(const std::string& request_id);
void note_problem_code(const std::string& code);
struct RequestNote {
    bool valid = false;
    double elapsed_s = 0;
    std::string code;
};
RequestNote take_request_note();

// Fills `res` with the problem+json body and status for `code` (plus
// Retry-After for overloaded).
void send_problem(httplib::Response& res, ProblemCode code, const std::string& detail, int retry_after_s = 0);
// The same with an HTTP status other than the code's own (413, 414, 431, ...),
// which the body's `status` repeats.
void send_problem_with_status(httplib::Response& res, int status, ProblemCode code, const std::string& detail);

// `message` without the service's own directories (the data dir, the scratch
// dir): an error from a child process or the file system may name the private
// path of an upload, which is none of the client's business.
std::string without_service_paths(const std::string& message, const ServerContext& ctx);

// The paging parameters of a list route (GET /v1/jobs, /v1/files): `limit`
// (1..100, default 20) and `order` (newest, the default, or oldest); `cursor`
// and the names in `extra` are allowed and left to the route, any other
// parameter is refused. Throws Error(invalid_argument) naming the parameter.
struct PageQuery {
    int limit = 20;
    bool newest = true;
};
PageQuery parse_page_query(const httplib::Request& req, std::initializer_list<const char*> extra);

// A route handler f(ctx, req, res) whose Error or ServiceError becomes the
// problem+json answer of its code (the service's own paths cut out of the message). Ctx is
// ServerContext (a template parameter so that this header needs only its
// declaration).
template <typename Ctx, typename F>
httplib::Server::Handler guarded(Ctx& ctx, F f) {
    return [&ctx, f](const httplib::Request& req, httplib::Response& res) {
        auto answer = [&](ProblemCode code, const char* what) {
            send_problem(res, code, without_service_paths(what, ctx), ctx.config.retry_after_s);
        };
        try {
            f(ctx, req, res);
        } catch (const Error& e) {
            answer(e.code(), e.what());
        } catch (const ServiceError& e) {
            answer(e.code(), e.what());
        }
    };
}

// The content type of JSON answers that carry megabytes of base64 (images,
// AOVs, converted files). cpp-httplib 0.11 compresses every body of the exact
// type "application/json" for a client that accepts it, with Brotli at that
// library's default quality 11: about 1 MB/s, 15 s for an 800x600 frame with
// its AOVs (seen with Chromium, which always offers br), for little gain on
// base64 of compressed images and float arrays. With a parameter the type is
// the same but cpp-httplib's exact match fails, so the body goes uncompressed.
inline constexpr const char* kBulkJsonContentType = "application/json; charset=utf-8";

// True when the client asked for JSON (Accept contains application/json).
// The media type of the answer among `offers`, most preferred first, as the
// request's Accept header admits them (RFC 9110 §12.5.1); a request that admits
// none is refused 406 (code not_acceptable) with the list it could have had.
std::string negotiate_answer(const httplib::Request& req, const std::vector<std::string>& offers);
inline constexpr const char* kJsonMediaType = "application/json";
// X-Nurbsrt-Warnings: the count and the first warnings as a JSON array in
// ASCII, cut under a few KiB (the full list is in the JSON answer); none
// without warnings. On every render and conversion answer, image or JSON.
void set_warnings_header(httplib::Response& res, const std::vector<std::string>& warnings);
// A JSON answer (invalid UTF-8 in client text replaced, never an exception).
void send_json(httplib::Response& res, const nlohmann::json& body, int status = 200);

// For a request naming a stored file (upload.file_id, server/store/file_store.h):
// loads its record and bytes into `stored` and points upload.bytes and
// upload.filename at them. Throws Error(not_found) naming the id.
void load_stored_file(ServerContext& ctx, Upload& upload, StoredContent& stored);

}  // namespace nurbsrt::server
