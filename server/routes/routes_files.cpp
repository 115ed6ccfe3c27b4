// Stored files: POST /v1/files (upload once, then render, convert or use in
// jobs by id), GET /v1/files (paged), GET, PATCH (pin) and DELETE
// /v1/files/{id}, and GET /v1/files/{id}/content. The store itself is
// server/store/file_store.h; a file is imported when it is stored (the same
// isolated, guarded import as a render, server/render/render_service.h), so a file
// that cannot be imported is refused with the problem its render would get,
// never stored, and the first render of a stored file finds its scene cached.
#include <httplib.h>
#include <nlohmann/json.hpp>

#include <map>
#include <tuple>

#include "importer/importer.h"
#include "core/error.h"
#include "core/io/assembly_tree_json.h"
#include "core/json_limits.h"
#include "server/render/context.h"
#include "server/http/etag.h"
#include "server/store/file_store.h"
#include "server/http/http_server.h"
#include "server/http/negotiation.h"
#include "server/routes/handler_util.h"
#include "server/common/rfc3339.h"
#include "server/store/job_store.h"
#include "server/render/render_service.h"
#include "server/routes/routes.h"
#include "server/common/service_error.h"

namespace nurbsrt::server {
namespace {

using nlohmann::json;

// Distinct colours listed in a summary at most: a model painted face by face
// in a gradient would otherwise make the summary as long as its face list.
constexpr size_t kMaxSummaryColors = 64;

std::string file_url(const std::string& id) { return "/v1/files/" + id; }

// What the import found: faces, bodies, units, bounding box (mm), the
// colours with how many faces each has (a face's own colour, else its
// body's; linear RGB in [0,1] as imported), the import's warnings, and the
// assembly tree (the part ids and names renders' `parts` take).
json import_summary(const Scene& scene) {
    std::map<std::tuple<float, float, float>, int> colors;
    for (const Face& f : scene.faces) {
        const Body* body = f.body < scene.bodies.size() ? &scene.bodies[f.body] : nullptr;
        const Color* c = f.has_color ? &f.color : body && body->has_color ? &body->color : nullptr;
        if (c) ++colors[{c->r, c->g, c->b}];
    }
    json color_list = json::array();
    for (const auto& [rgb, faces] : colors) {
        if (color_list.size() == kMaxSummaryColors) break;
        color_list.push_back({{"rgb", {std::get<0>(rgb), std::get<1>(rgb), std::get<2>(rgb)}}, {"faces", faces}});
    }
    json bbox = nullptr;
    if (!scene.bbox.empty())
        bbox = {{"min", {scene.bbox.lo.x, scene.bbox.lo.y, scene.bbox.lo.z}},
                {"max", {scene.bbox.hi.x, scene.bbox.hi.y, scene.bbox.hi.z}}};
    return {{"faces", scene.faces.size()},
            {"bodies", scene.bodies.size()},
            {"units", scene.units},
            {"bbox", bbox},
            {"colors", color_list},
            {"warnings", scene.warnings},
            {"parts", assembly_tree_json(scene)}};
}

json file_json(const ServerContext& ctx, const StoredFile& f) {
    json summary = json::parse(f.summary_json, nullptr, false);
    if (summary.is_discarded()) summary = json::object();
    const auto retention_ms = static_cast<int64_t>(ctx.config.job_retention_s * 1000);
    return {{"id", f.id},
            {"url", file_url(f.id)},
            {"content_url", file_url(f.id) + "/content"},
            {"format", f.format},
            {"filename", f.filename},
            {"bytes", f.bytes},
            {"sha256", f.id},
            {"created_at", rfc3339_utc(f.created_ms)},
            {"pinned", f.pinned},
            {"expires_at", f.pinned ? json(nullptr) : json(rfc3339_utc(f.created_ms + retention_ms))},
            {"summary", summary}};
}

ServiceError no_such_file(const std::string& id) {
    return ServiceError(ServiceCode::not_found, "no stored file '" + id.substr(0, 80) + "'");
}

bool parse_bool(const json& v, const char* name) {
    if (v.is_boolean()) return v.get<bool>();  // query and form values are typed at the edge (query_values.h)
    throw Error(ErrorCode::invalid_argument, std::string("'") + name + "' must be true or false");
}

// The filename of Content-Disposition (RFC 6266 §4.1: filename="..." or a token).
std::string disposition_filename(const std::string& header) {
    const size_t at = header.find("filename=");
    if (at == std::string::npos) return "";
    std::string v = header.substr(at + 9);
    if (!v.empty() && v.front() == '"') {
        const size_t end = v.find('"', 1);
        return v.substr(1, end == std::string::npos ? std::string::npos : end - 1);
    }
    return v.substr(0, v.find(';'));
}

struct UploadRequest {
    std::string filename;
    bool pinned = false;
};

// The upload's parameters: `filename` (raw bodies; else Content-Disposition)
// and `pinned`, as query parameters or form fields.
UploadRequest upload_parameters(const httplib::Request& req, const Upload& upload) {
    if (!upload.file_id.empty())
        throw Error(ErrorCode::invalid_argument,
                    "POST /v1/files stores the file itself: send it raw or as the 'file' part of multipart/form-data");
    UploadRequest out;
    const json options = json::parse(upload.options_json);
    for (const auto& [k, v] : options.items()) {
        if (k == "pinned") {
            out.pinned = parse_bool(v, "pinned");
        } else if (k == "filename" && v.is_string()) {
            out.filename = v.get<std::string>();
        } else {
            throw Error(ErrorCode::invalid_argument,
                        "unknown parameter '" + k.substr(0, 64) + "' (a stored file takes 'filename' and 'pinned')");
        }
    }
    if (upload.multipart && !upload.filename.empty()) out.filename = upload.filename;
    if (out.filename.empty()) out.filename = disposition_filename(req.get_header_value("Content-Disposition"));
    // A label for the client only, never a path: bounded like a job's file names.
    constexpr size_t kMaxFilename = 255;
    out.filename = out.filename.substr(0, kMaxFilename);
    return out;
}

void send_over_quota(const ServerContext& ctx, httplib::Response& res, size_t size) {
    // 507 Insufficient Storage (RFC 4918 §11.5): the request is fine and within
    // the upload limit (413 would tell the client to send less, which does not
    // help); the service cannot store it until stored files are deleted.
    send_problem_with_status(res, 507, ErrorCode::limit_exceeded,
                             "storing this file (" + std::to_string(size) + " bytes) would exceed the quota of " +
                                 std::to_string(ctx.files.max_bytes()) + " bytes of stored files (" +
                                 std::to_string(ctx.files.used_bytes()) +
                                 " in use): delete stored files (DELETE /v1/files/{id}) first");
}

}  // namespace

void handle_file_upload(ServerContext& ctx, const httplib::Request& req, httplib::Response& res) {
    const Upload upload = read_upload(req, {"pinned", "filename"});
    const UploadRequest params = upload_parameters(req, upload);
    const std::string& bytes = *upload.bytes;
    if (bytes.empty()) throw Error(ErrorCode::invalid_argument, empty_upload_detail(upload));
    const CadFormat format = detect_format_bytes(bytes.data(), bytes.size());
    if (format == CadFormat::unknown)
        throw Error(ErrorCode::unsupported_format, "the upload is neither STEP, IGES nor BREP (recognised by content)");

    StoredFile file;
    file.id = sha256_hex(bytes);
    file.format = format_name(format);
    file.filename = params.filename;
    file.bytes = static_cast<int64_t>(bytes.size());
    file.pinned = params.pinned;
    // The same bytes again: the stored record, without a second import.
    if (std::optional<StoredFile> existing = ctx.files.get(file.id)) {
        if (params.pinned && !existing->pinned) existing = ctx.files.set_pinned(file.id, true);
        if (existing) {
            res.set_header("Location", file_url(existing->id));
            send_json(res, file_json(ctx, *existing), 200);
            return;
        }
    }
    // Before the import: an upload that cannot be kept costs no import.
    if (ctx.files.used_bytes() + file.bytes > ctx.files.max_bytes()) return send_over_quota(ctx, res, bytes.size());

    RenderControl control;
    control.should_stop = GuardedServer::client_gone_check();  // a gone client's import stops waiting
    control.content_sha256 = file.id;
    bool cache_hit = false;
    StageClock stages;  // not reported: a stored file's answer carries no timings
    const auto prepared = imported_scene(ctx, bytes, control, cache_hit, stages);
    file.summary_json = import_summary(prepared->scene()).dump(-1, ' ', false, json::error_handler_t::replace);
    file.created_ms = unix_now_ms();
    switch (ctx.files.put(file, bytes)) {
        case FileStore::PutOutcome::over_quota:
            return send_over_quota(ctx, res, bytes.size());
        case FileStore::PutOutcome::created:
            res.set_header("Location", file_url(file.id));
            return send_json(res, file_json(ctx, file), 201);
        case FileStore::PutOutcome::existing:  // stored meanwhile by a simultaneous upload
            res.set_header("Location", file_url(file.id));
            return send_json(res, file_json(ctx, file), 200);
    }
}

void handle_file_list(ServerContext& ctx, const httplib::Request& req, httplib::Response& res) {
    const PageQuery q = parse_page_query(req, {});
    std::optional<std::string> cursor;
    if (req.has_param("cursor")) cursor = req.get_param_value("cursor");
    const FilePage page = ctx.files.list(q.newest, q.limit, cursor);
    json list = json::array();
    for (const StoredFile& f : page.files) list.push_back(file_json(ctx, f));
    send_json(res, {{"files", list},
                    {"next_cursor", page.next_cursor ? json(*page.next_cursor) : json(nullptr)},
                    {"stored_bytes", ctx.files.used_bytes()},
                    {"max_stored_bytes", ctx.files.max_bytes()}});
}

void handle_file_get(ServerContext& ctx, const httplib::Request& req, httplib::Response& res) {
    const std::string id = req.matches[1];
    const std::optional<StoredFile> f = ctx.files.get(id);
    if (!f) throw no_such_file(id);
    send_json(res, file_json(ctx, *f));
}

void handle_file_content(ServerContext& ctx, const httplib::Request& req, httplib::Response& res) {
    const std::string id = req.matches[1];
    if (!ctx.files.get(id)) throw no_such_file(id);
    // The id is the SHA-256 of the bytes, which never change: a strong
    // validator (RFC 9110 §8.8.3), and the content may be kept while stored.
    const std::string etag = "\"" + id + "\"";
    res.set_header("ETag", etag);
    res.set_header("Cache-Control", "private, immutable");
    if (req.has_header("If-None-Match") && if_none_match_matches(req.get_header_value("If-None-Match"), etag)) {
        const StoredContent c = ctx.files.open(id);
        res.status = 304;  // RFC 9110 §15.4.5; Content-Length that of the 200 (§8.6)
        res.set_header("Content-Length", std::to_string(c.bytes->size()));
        return;
    }
    const StoredContent c = ctx.files.open(id);
    const bool step = c.file.format == "STEP";
    // The name it was stored under, byte for byte (a client's label, never a path).
    res.set_header(
        "Content-Disposition",
        attachment_disposition(c.file.filename.empty() ? (step ? "model.stp" : "model.igs") : c.file.filename));
    res.set_content(*c.bytes, step ? "model/step" : "model/iges");
}

void handle_file_patch(ServerContext& ctx, const httplib::Request& req, httplib::Response& res) {
    const std::string id = req.matches[1];
    const std::string type = req.get_header_value("Content-Type");
    const std::string base = type.substr(0, type.find(';'));
    // application/merge-patch+json: the body is a JSON Merge Patch (RFC 7396).
    if (base != "application/json" && base != "application/merge-patch+json")
        throw Error(ErrorCode::unsupported_format, "send the change as JSON: {\"pinned\": true}");
    const json body = parse_json_or_throw(req.body, kRequestJsonLimits, "the body");
    if (!body.is_object() || !body.contains("pinned") || !body["pinned"].is_boolean())
        throw Error(ErrorCode::invalid_argument, "the body must be {\"pinned\": true} or {\"pinned\": false}");
    for (const auto& [k, v] : body.items())
        if (k != "pinned")
            throw Error(ErrorCode::invalid_argument,
                        "field '" + k.substr(0, 64) + "' cannot be changed (only 'pinned')");
    const std::optional<StoredFile> f = ctx.files.set_pinned(id, body["pinned"].get<bool>());
    if (!f) throw no_such_file(id);
    send_json(res, file_json(ctx, *f));
}

void handle_file_delete(ServerContext& ctx, const httplib::Request& req, httplib::Response& res) {
    const std::string id = req.matches[1];
    if (!ctx.files.remove(id)) throw no_such_file(id);
    res.status = 204;
}

}  // namespace nurbsrt::server
