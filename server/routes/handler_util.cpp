#include "server/routes/handler_util.h"

#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <ctime>

#include "server/render/context.h"
#include "server/http/problem.h"
#include "server/common/redact.h"
#include "server/http/negotiation.h"

namespace nurbsrt::server {
namespace {

struct ThreadNote {
    bool valid = false;
    std::chrono::steady_clock::time_point start;
    std::string request_id, code;
};
thread_local ThreadNote t_note;

// Headers bigger than a few KiB are refused by some proxies (nginx's default
// buffer is 4-8 KiB); the full list is in the JSON answer.
constexpr size_t kMaxWarningsHeader = 4096;

// "N; [..JSON array..]" in ASCII (a header is no place for UTF-8), cut to
// whole entries under kMaxWarningsHeader.
std::string warnings_header(const std::vector<std::string>& warnings) {
    nlohmann::json list = nlohmann::json::array();
    const std::string head = std::to_string(warnings.size()) + "; ";
    for (const std::string& w : warnings) {
        list.push_back(w);
        if (head.size() + list.dump(-1, ' ', true, nlohmann::json::error_handler_t::replace).size() + 8 >
            kMaxWarningsHeader) {
            list.erase(list.size() - 1);
            list.push_back("...");
            break;
        }
    }
    return head + list.dump(-1, ' ', true, nlohmann::json::error_handler_t::replace);
}

}  // namespace

std::string request_id(const httplib::Response& res) { return res.get_header_value("X-Request-Id"); }

void note_request_start(const std::string& id) { t_note = ThreadNote{true, std::chrono::steady_clock::now(), id, ""}; }

void note_problem_code(const std::string& code) { t_note.code = code; }

RequestNote take_request_note() {
    RequestNote n;
    if (t_note.valid) {
        n.valid = true;
        n.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_note.start).count();
        n.code = t_note.code;
    }
    t_note = ThreadNote{};
    return n;
}

void send_problem(httplib::Response& res, ProblemCode code, const std::string& detail, int retry_after_s) {
    const Problem p = make_problem(code, detail, request_id(res));
    res.status = p.status;
    if (code == ServiceCode::overloaded && retry_after_s > 0)
        res.set_header("Retry-After", std::to_string(retry_after_s));
    res.set_content(p.body, kProblemContentType);
    note_problem_code(code.name());
}

void send_problem_with_status(httplib::Response& res, int status, ProblemCode code, const std::string& detail) {
    const Problem p = make_problem(code, detail, request_id(res), status);
    res.status = p.status;
    res.set_content(p.body, kProblemContentType);
    note_problem_code(code.name());
}

void set_warnings_header(httplib::Response& res, const std::vector<std::string>& warnings) {
    if (!warnings.empty()) res.set_header("X-Nurbsrt-Warnings", warnings_header(warnings));
}

void send_json(httplib::Response& res, const nlohmann::json& body, int status) {
    res.status = status;
    res.set_content(body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), kJsonMediaType);
}

std::string negotiate_answer(const httplib::Request& req, const std::vector<std::string>& offers) {
    if (auto chosen = negotiate_media_type(req.get_header_value("Accept"), offers)) return *chosen;
    std::string list;
    for (const std::string& o : offers) list += (list.empty() ? "" : ", ") + o;
    throw ServiceError(ServiceCode::not_acceptable,
                       "the Accept header admits none of the media types of this answer: " + list);
}

PageQuery parse_page_query(const httplib::Request& req, std::initializer_list<const char*> extra) {
    for (const auto& [k, v] : req.params) {
        bool known = k == "limit" || k == "order" || k == "cursor";
        for (const char* e : extra) known = known || k == e;
        if (!known) throw Error(ErrorCode::invalid_argument, "unknown query parameter '" + k.substr(0, 64) + "'");
    }
    PageQuery q;
    if (req.has_param("limit")) {
        const std::string v = req.get_param_value("limit");
        char* end = nullptr;
        const long n = std::strtol(v.c_str(), &end, 10);
        if (v.empty() || *end || n < 1 || n > 100)
            throw Error(ErrorCode::invalid_argument, "'limit' must be an integer in 1..100");
        q.limit = static_cast<int>(n);
    }
    const std::string order = req.has_param("order") ? req.get_param_value("order") : "newest";
    if (order != "newest" && order != "oldest")
        throw Error(ErrorCode::invalid_argument, "'order' must be newest or oldest");
    q.newest = order == "newest";
    return q;
}

std::string without_service_paths(const std::string& message, const ServerContext& ctx) {
    std::string data = ctx.config.data_dir;
    while (data.size() > 1 && data.back() == '/') data.pop_back();
    // Scratch files first: the scratch dir usually lies inside the data dir.
    auto dir_prefix = [](const std::string& d) { return d.empty() ? d : d + "/"; };  // "" erases nothing
    return without_prefixes(with_scratch_files_named(message, ctx.scratch.path()), {dir_prefix(data)});
}

void load_stored_file(ServerContext& ctx, Upload& upload, StoredContent& stored) {
    stored = ctx.files.open(upload.file_id);
    upload.bytes = stored.bytes.get();
    upload.filename = stored.file.filename;
}

}  // namespace nurbsrt::server
