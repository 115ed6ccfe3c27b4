// POST /v1/renders: one synchronous render of an uploaded STEP/IGES file, or
// of a stored one (server/store/file_store.h) named by `file_id`.
// Order of work: parse and check every limit, then admission, then
// render_upload (server/render/render_service.h): scene, bounded render, encoding.
#include <httplib.h>
#include <nlohmann/json.hpp>

#include <chrono>

#include "importer/importer.h"
#include "core/error.h"
#include "server/common/base64.h"
#include "server/http/zip_archive.h"
#include "server/render/context.h"
#include "server/http/etag.h"
#include "server/http/http_server.h"
#include "server/routes/handler_util.h"
#include "options/render_request.h"
#include "server/render/render_limits.h"
#include "server/render/render_service.h"
#include "server/routes/routes.h"
#include "server/render/stage_timings.h"
#include "server/render/work.h"

namespace nurbsrt::server {
namespace {

// {"z": {"type": "float32", "components": 1, "data": base64}, ...}
nlohmann::json aovs_json(const std::vector<AovBuffer>& aovs) {
    nlohmann::json out = nlohmann::json::object();
    for (const AovBuffer& a : aovs)
        out[aov_name(a.aov)] = {{"type", a.type}, {"components", a.components}, {"data", base64_encode(a.bytes)}};
    return out;
}

// The answer's media type (RFC 9110 §12.5.1): the image in the format the
// options name, or, when they name none, in the one Accept prefers (PNG for
// */*); a ZIP of the views' images for layout separate; or JSON. True for JSON;
// else `r.format` is the image's.
bool choose_answer(const httplib::Request& req, RenderRequest& r) {
    // The API's image formats, PNG first: the default.
    static const std::vector<OutputFormat> kImageFormats = {
        output_format(ImageFormat::png), output_format(ImageFormat::jpeg), output_format(ImageFormat::tiff),
        output_format(ImageFormat::exr)};
    std::vector<std::string> offers;
    if (r.layout == ViewLayout::separate)  // the views' images (r.format) in a ZIP
        offers.push_back(kZipMediaType);
    else if (r.format_given)
        offers.push_back(r.format.content_type);
    else
        for (const OutputFormat& f : kImageFormats) offers.push_back(f.content_type);
    offers.push_back(kJsonMediaType);
    const std::string answer = negotiate_answer(req, offers);
    if (answer == kJsonMediaType) return true;
    for (const OutputFormat& f : kImageFormats)
        if (f.content_type == answer) r.format = f;
    return false;
}

}  // namespace

void handle_render(ServerContext& ctx, const httplib::Request& req, httplib::Response& res) {
    // The stages (timings_ms, Server-Timing) run from the request's arrival.
    const auto t0 = GuardedServer::request_received_at();
    Upload upload = read_upload(req);
    RenderRequest r = parse_render_options(upload.options_json);
    check_render_limits(ctx.config, r);
    const bool json_answer = choose_answer(req, r);
    if (r.aovs && !json_answer)
        throw Error(ErrorCode::invalid_argument,
                    "option 'aovs' needs a JSON answer: send 'Accept: application/json' (or use format exr)");
    StoredContent stored;
    if (!upload.file_id.empty()) {
        load_stored_file(ctx, upload, stored);
        // The image of a stored file is known by its content and options
        // before any work: a client holding it gets 304 without a render.
        // JSON answers carry timings and a request id, so they get no tag.
        if (!json_answer) {
            const std::string etag = render_etag(stored.file.id, upload.options_json + "\n" + r.format.content_type);
            res.set_header("ETag", etag);
            res.set_header("Vary", "Accept");
            if (req.has_header("If-None-Match") && if_none_match_matches(req.get_header_value("If-None-Match"), etag)) {
                res.status = 304;
                return;
            }
        }
    }
    const std::string& bytes = *upload.bytes;
    if (bytes.empty()) throw Error(ErrorCode::invalid_argument, empty_upload_detail(upload));
    if (detect_format_bytes(bytes.data(), bytes.size()) == CadFormat::unknown)
        throw Error(ErrorCode::unsupported_format, "the upload is neither STEP, IGES nor BREP (recognised by content)");

    RenderControl control;
    control.start = t0;
    control.content_sha256 = stored.file.id;  // a stored file's id is its bytes' SHA-256 (empty for an upload)
    control.should_stop = GuardedServer::client_gone_check();  // a gone client's render stops
    RenderedImage rendered = render_upload(ctx, bytes, r, control);
    StageClock& stages = rendered.timings;
    const auto set_timing_header = [&] {
        res.set_header("Server-Timing",
                       server_timing(stages, kRenderStages, {{"cache", rendered.cache_hit ? "hit" : "miss"}}));
    };
    set_warnings_header(res, rendered.warnings);
    const bool separate = r.layout == ViewLayout::separate;
    if (!json_answer) {
        if (separate)
            res.set_content(views_zip(rendered, r.format), kZipMediaType);
        else
            res.set_content(rendered.bytes, r.format.content_type.c_str());
        stages.mark("response");
        set_timing_header();
        return;
    }
    nlohmann::json body = {{"request_id", request_id(res)},
                           {"format", r.format.name},
                           {"content_type", r.format.content_type},
                           {"width", r.width},
                           {"height", r.height},
                           {"warnings", rendered.warnings}};
    if (separate) {  // an image per view, in the order of `views`
        body["images"] = nlohmann::json::array();
        for (const RenderedImage::View& v : rendered.views) {
            nlohmann::json one = {{"view", v.name}, {"image_base64", base64_encode(v.bytes)}};
            if (!v.aovs.empty()) one["aovs"] = aovs_json(v.aovs);
            body["images"].push_back(std::move(one));
        }
    } else {
        body["image_base64"] = base64_encode(rendered.bytes);
        if (!rendered.aovs.empty()) body["aovs"] = aovs_json(rendered.aovs);
    }
    // The last stage, this answer, ends before its serialization: the text
    // cannot hold the time it takes to write itself.
    stages.mark("response");
    body["statistics"] = statistics_json(rendered);
    set_timing_header();
    res.set_content(body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), kBulkJsonContentType);
}

}  // namespace nurbsrt::server
