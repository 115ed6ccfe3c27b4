// POST /v1/renders: one synchronous render of an uploaded STEP/IGES file.
// Order of work: parse and check every limit, then admission, then the scene
// (cache or isolated import), then the render (bounded in time), then encoding.
#include <httplib.h>
#include <nlohmann/json.hpp>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <future>
#include <thread>

#include "importer/importer.h"
#include "importer/isolated.h"
#include "renderer/error.h"
#include "renderer/render.h"
#include "renderer/stats_json.h"
#include "server/base64.h"
#include "server/context.h"
#include "server/http_util.h"
#include "server/render_options.h"
#include "server/routes.h"
#include "server/work.h"

namespace nurbsrt::server {
namespace {

using clock_type = std::chrono::steady_clock;
double ms_since(clock_type::time_point t0) {
    return std::chrono::duration<double, std::milli>(clock_type::now() - t0).count();
}

void check_limits(const ServerContext& ctx, const RenderRequest& r) {
    const ServerConfig& c = ctx.config;
    if (r.width > c.max_dimension || r.height > c.max_dimension)
        throw Error(ErrorCode::limit_exceeded, "image " + std::to_string(r.width) + "x" + std::to_string(r.height) +
                                                   " exceeds the limit of " + std::to_string(c.max_dimension) +
                                                   " pixels per side");
    if (static_cast<long long>(r.width) * r.height > c.max_pixels)
        throw Error(ErrorCode::limit_exceeded, "image of " +
                                                   std::to_string(static_cast<long long>(r.width) * r.height) +
                                                   " pixels exceeds the limit of " + std::to_string(c.max_pixels));
}

// The imported scene for these bytes: from the cache, or imported in a child process.
std::shared_ptr<const Scene> scene_for(ServerContext& ctx, const std::string& bytes, bool& cache_hit) {
    const ImportOptions options;
    SceneCache::Source source = SceneCache::Source::loaded;
    auto scene = ctx.cache.get_or_load(
        scene_cache_key(bytes, options),
        [&] {
            const TempFile upload = ctx.scratch.write("upload", ".cad", bytes);
            try {
                return std::make_shared<const Scene>(import_isolated(upload.path(), options, isolation_limits(ctx)));
            } catch (const Error& e) {
                ctx.metrics.count_import_failure(error_code_name(e.code()));
                throw;
            }
        },
        source);
    // A request that waited for another's import of the same bytes paid no import.
    cache_hit = source != SceneCache::Source::loaded;
    ctx.metrics.count_cache(cache_hit);
    return scene;
}

// Runs the render on its own thread and waits at most the configured time. A
// render that runs over is canceled (RenderOptions::cancel); it keeps its worker
// slot (the ticket) until its thread has really stopped, at the next block of
// rows, so the slot is never handed out twice.
RenderResult render_bounded(ServerContext& ctx, std::shared_ptr<const Scene> scene, const Camera& camera,
                            RenderOptions options, std::shared_ptr<AdmissionGate::Ticket> ticket) {
    auto cancel = std::make_shared<std::atomic<bool>>(false);
    options.cancel = cancel;
    auto task = std::make_shared<std::packaged_task<RenderResult()>>(
        [scene, camera, options, ticket] { return render(*scene, camera, options); });
    std::future<RenderResult> result = task->get_future();
    std::thread([task] { (*task)(); }).detach();
    const auto limit = std::chrono::duration<double>(ctx.config.render_timeout_s);
    if (result.wait_for(limit) != std::future_status::ready) {
        cancel->store(true);
        char msg[128];
        std::snprintf(msg, sizeof msg, "the render did not finish within %.0f s", ctx.config.render_timeout_s);
        throw Error(ErrorCode::render_timeout, msg);
    }
    return result.get();
}

void handle_render(ServerContext& ctx, const httplib::Request& req, httplib::Response& res) {
    const auto t0 = clock_type::now();
    const Upload upload = read_upload(req);
    const RenderRequest r = parse_render_options(upload.options_json);
    check_limits(ctx, r);
    const std::string& bytes = *upload.bytes;
    if (bytes.empty()) throw Error(ErrorCode::invalid_argument, "empty upload: send a STEP or IGES file");
    if (detect_format_bytes(bytes.data(), bytes.size()) == CadFormat::unknown)
        throw Error(ErrorCode::unsupported_format, "the upload is neither STEP nor IGES (recognised by content)");

    auto ticket = admit(ctx);
    bool cache_hit = false;
    std::shared_ptr<const Scene> scene = scene_for(ctx, bytes, cache_hit);
    if (scene->faces.size() > ctx.config.max_faces)
        throw Error(ErrorCode::limit_exceeded, "the model has " + std::to_string(scene->faces.size()) +
                                                   " faces; the limit is " + std::to_string(ctx.config.max_faces));
    const Camera camera(camera_spec_for(r, *scene));
    RenderOptions options;
    options.method = r.method == "martin" ? NewtonMethod::martin : NewtonMethod::proposed;
    options.map_precision = r.map_precision == "rgb8" ? MapPrecision::rgb8 : MapPrecision::float32;
    options.threads = ctx.config.render_threads;
    if (r.background)
        options.background = {static_cast<float>(r.background->x), static_cast<float>(r.background->y),
                              static_cast<float>(r.background->z)};
    const RenderResult result = render_bounded(ctx, scene, camera, options, ticket);

    const auto te = clock_type::now();
    std::string image;
    {
        const TempFile out = ctx.scratch.create("render", r.format.extension.c_str());
        write_image(result.image, out.path());
        image = read_file_bytes(out.path());
    }
    const double encode_ms = ms_since(te);
    ticket.reset();

    const ImportTimings import_ms = cache_hit ? ImportTimings{} : scene->timings;
    nlohmann::json stats = render_stats_json(result.stats, import_ms, encode_ms, ms_since(t0));
    const CameraSpec& cs = camera.spec();
    stats["camera"] = {{"eye", {cs.eye.x, cs.eye.y, cs.eye.z}},
                       {"target", {cs.target.x, cs.target.y, cs.target.z}},
                       {"up", {cs.up.x, cs.up.y, cs.up.z}},
                       {"projection", camera.perspective() ? "perspective" : "orthographic"},
                       {"fov_deg", cs.fov_deg},
                       {"ortho_height", cs.ortho_height}};
    stats["map_precision"] = r.map_precision;
    stats["warnings"] = scene->warnings;
    stats["cache"] = cache_hit ? "hit" : "miss";

    std::string timing;
    for (const char* stage : {"read", "nurbs_convert", "mesh", "preliminary_map", "newton", "shade", "encode", "total"}) {
        const double ms = stats["timings_ms"].value(stage, 0.0);
        char buf[96];
        std::snprintf(buf, sizeof buf, "%s%s;dur=%.3f", timing.empty() ? "" : ", ", stage, ms);
        timing += buf;
        ctx.metrics.observe_stage(stage, ms / 1000.0);
    }
    timing += std::string(", cache;desc=") + (cache_hit ? "hit" : "miss");
    res.set_header("Server-Timing", timing);

    if (wants_json(req)) {
        const nlohmann::json body = {{"request_id", request_id(res)},
                                     {"format", r.format.name},
                                     {"content_type", r.format.content_type},
                                     {"width", r.width},
                                     {"height", r.height},
                                     {"image_base64", base64_encode(image)},
                                     {"statistics", stats}};
        res.set_content(body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), "application/json");
    } else {
        res.set_content(image, r.format.content_type.c_str());
    }
}

}  // namespace

void add_render_routes(httplib::Server& svr, ServerContext& ctx) {
    svr.Post("/v1/renders", [&ctx](const httplib::Request& req, httplib::Response& res) {
        try {
            handle_render(ctx, req, res);
        } catch (const Error& e) {
            send_problem(res, e.code(), e.what(), ctx.config.retry_after_s);
        }
    });
}

}  // namespace nurbsrt::server
