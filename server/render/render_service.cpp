#include "server/render/render_service.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <bit>
#include <cstdio>
#include <exception>
#include <future>
#include <thread>

#include "importer/importer.h"
#include "importer/isolated.h"
#include "core/error.h"
#include "renderer/frame_cost.h"
#include "renderer/render.h"
#include "renderer/stats_json.h"
#include "server/http/zip_archive.h"
#include "server/render/stage_timings.h"
#include "server/render/work.h"
#include "server/common/service_error.h"
#include "server/common/sha256.h"

namespace nurbsrt::server {
namespace {

using clock_type = std::chrono::steady_clock;

AdmissionWait admission_wait(const RenderControl& control) {
    AdmissionWait w;
    w.patient = control.patient;
    w.give_up = [cancel = control.cancel, stop = control.should_stop] {
        return (cancel && cancel->load()) || (stop && stop());
    };
    return w;
}

// Frames estimated below this many core-seconds are interactive (a thumbnail,
// a dragged view, up to ~1600x1200 of a typical part): they go ahead of others.
// Above kHeavyCoreSeconds (several seconds of a core: 3000x2000 of a typical
// part, high-degree faces at 1600x1200) a frame yields to everything else.
constexpr double kInteractiveCoreSeconds = 1.0;
constexpr double kHeavyCoreSeconds = 2.5;

RenderPriority priority_for(const FrameCost& cost) {
    if (cost.core_seconds < kInteractiveCoreSeconds) return RenderPriority::high;
    if (cost.core_seconds > kHeavyCoreSeconds) return RenderPriority::low;
    return RenderPriority::normal;
}

const char* priority_name(RenderPriority p) {
    switch (p) {
        case RenderPriority::low:
            return "low";
        case RenderPriority::high:
            return "high";
        case RenderPriority::normal:
            break;
    }
    return "normal";
}

// Refuses a frame whose estimate exceeds the per-render caps.
void check_frame_cost(const ServerConfig& c, const FrameCost& cost) {
    const auto mib = [](size_t b) { return std::to_string((b + (1 << 20) - 1) >> 20); };
    if (cost.memory_bytes > c.max_render_bytes)
        throw Error(ErrorCode::limit_exceeded, "the render needs an estimated " + mib(cost.memory_bytes) +
                                                   " MiB; the limit is " + mib(c.max_render_bytes) +
                                                   " MiB per render (a smaller image needs less)");
    if (cost.core_seconds > c.max_render_cost_s) {
        char msg[200];
        std::snprintf(msg, sizeof msg,
                      "the render needs an estimated %.0f core-seconds; the limit is %g per render "
                      "(a smaller image needs less)",
                      cost.core_seconds, c.max_render_cost_s);
        throw Error(ErrorCode::limit_exceeded, msg);
    }
}

// Runs the render on its own thread and waits at most the configured time. A
// render that runs over, or whose caller cancels it, is canceled
// (RenderOptions::cancel); it keeps its worker slot (the ticket) until its
// thread has really stopped, at the next block of rows, so the slot is never
// handed out twice.
RenderResult render_bounded(ServerContext& ctx, std::shared_ptr<const PreparedScene> scene, const Camera& camera,
                            RenderOptions options, std::shared_ptr<AdmissionGate::Ticket> ticket,
                            const std::shared_ptr<const std::atomic<bool>>& external_cancel,
                            const std::function<bool()>& should_stop) {
    auto cancel = std::make_shared<std::atomic<bool>>(false);
    options.cancel = cancel;
    // The thread lets go of its share of the ticket before the result is ready:
    // once the caller has the frame, only the caller's share holds the memory
    // (a share kept until the thread exits outlived the answer, and the
    // reservation showed in /metrics after it, under load).
    auto promise = std::make_shared<std::promise<RenderResult>>();
    std::future<RenderResult> result = promise->get_future();
    std::thread([promise, scene, camera, options, ticket]() mutable {
        try {
            RenderResult r = render(*scene, camera, options);
            ticket.reset();
            promise->set_value(std::move(r));
        } catch (...) {
            ticket.reset();
            promise->set_exception(std::current_exception());
        }
    }).detach();
    const auto deadline = clock_type::now() + std::chrono::duration_cast<clock_type::duration>(
                                                  std::chrono::duration<double>(ctx.config.render_timeout_s));
    // Short waits so that an external cancel is seen promptly, never past the
    // deadline (a 50 ms step would let a short limit pass unnoticed).
    while (result.wait_until(std::min(clock_type::now() + std::chrono::milliseconds(50), deadline)) !=
           std::future_status::ready) {
        if ((external_cancel && external_cancel->load()) || (should_stop && should_stop())) {
            cancel->store(true);
            throw Error(ErrorCode::canceled, "the render was canceled");
        }
        if (clock_type::now() >= deadline) {
            cancel->store(true);
            char msg[128];
            std::snprintf(msg, sizeof msg, "the render did not finish within %g s", ctx.config.render_timeout_s);
            throw ServiceError(ServiceCode::render_timeout, msg);
        }
    }
    return result.get();
}

template <class T>
std::string raw_bytes(const std::vector<T>& values) {
    return {reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T)};
}

// The AOVs asked for, as the raw arrays the JSON answer carries.
std::vector<AovBuffer> aov_buffers(const RenderImage& image, unsigned bits) {
    // The arrays are sent as they are in memory, and browsers' typed arrays read
    // the platform's order, which is little-endian on every platform they run on.
    static_assert(std::endian::native == std::endian::little, "AOV arrays are sent little-endian");
    std::vector<AovBuffer> out;
    for (Aov a : kAllAovs) {
        if (!(bits & aov_bit(a))) continue;
        switch (a) {
            case Aov::z:
                out.push_back({a, "float32", 1, raw_bytes(image.z)});
                break;
            case Aov::face:
                out.push_back({a, "uint32", 1, raw_bytes(image.face)});
                break;
            case Aov::normal:
                out.push_back({a, "float32", 3, raw_bytes(image.normal)});
                break;
            case Aov::uv: {
                std::vector<float> uv(image.u.size() * 2);
                for (size_t i = 0; i < image.u.size(); ++i) uv[2 * i] = image.u[i], uv[2 * i + 1] = image.v[i];
                out.push_back({a, "float32", 2, raw_bytes(uv)});
                break;
            }
            case Aov::iterations:
                out.push_back({a, "uint8", 1, raw_bytes(image.iterations)});
                break;
        }
    }
    return out;
}

}  // namespace

std::shared_ptr<const PreparedScene> imported_scene(ServerContext& ctx, const std::string& bytes,
                                                    const RenderControl& control, bool& cache_hit, StageClock& stages) {
    if (control.scene) {
        stages.mark("cache");
        cache_hit = true;
        return control.scene;
    }
    const ImportOptions options;
    SceneCache::Source source = SceneCache::Source::loaded;
    // A hash of every byte, unless the caller knows it: a stage of its own.
    const std::string key =
        scene_cache_key(control.content_sha256.empty() ? sha256_hex(bytes) : control.content_sha256, options);
    stages.mark("cache");
    auto scene = ctx.cache.get_or_load(
        key,
        [&] {
            stages.mark("cache");  // the lookup that missed
            const auto slot = admit(ctx, ctx.gate, 0, admission_wait(control));
            stages.mark("queue");
            const TempFile upload = ctx.scratch.write("upload", ".cad", bytes);
            stages.mark("isolation");  // handing the bytes to the child
            std::shared_ptr<const Scene> scene;
            IsolationTimings isolated;
            try {
                scene = std::make_shared<const Scene>(
                    import_isolated(upload.path(), options, isolation_limits(ctx), &isolated));
            } catch (const Error& e) {
                ctx.metrics.count_import_failure(error_code_name(e.code()));
                throw;
            }
            stages.add("prescan", isolated.prescan_ms);
            add_import_stages(scene->timings, stages);
            stages.add("transfer", isolated.transfer_ms);
            stages.add("isolation", isolated.isolation_ms);
            stages.mark("isolation");
            auto prepared = std::make_shared<const PreparedScene>(prepare(std::move(scene), ctx.config.render_threads));
            stages.mark("prepare");
            return prepared;
        },
        source);
    // The lookup that hit, or the insert after an import, or the wait for a
    // simultaneous request's import of the same bytes (which pays no import).
    stages.mark("cache");
    cache_hit = source != SceneCache::Source::loaded;
    ctx.metrics.count_cache(cache_hit);
    return scene;
}

RenderedImage render_upload(ServerContext& ctx, const std::string& bytes, const RenderRequest& r,
                            const RenderControl& control) {
    RenderedImage out;
    out.timings = StageClock(control.start.value_or(clock_type::now()));
    StageClock& stages = out.timings;
    // Before this call since control.start: the caller's reading of the request
    // (its parts, options and checks) or of a job's input file.
    stages.mark("upload");
    std::shared_ptr<const PreparedScene> prepared = imported_scene(ctx, bytes, control, out.cache_hit, stages);
    const Scene& scene = prepared->scene();
    if (scene.faces.size() > ctx.config.max_faces)
        throw Error(ErrorCode::limit_exceeded, "the model has " + std::to_string(scene.faces.size()) +
                                                   " faces; the limit is " + std::to_string(ctx.config.max_faces));
    // Hidden, ghosted, recoloured and exploded parts and sections are options of
    // the frame: the cached prepared scene serves them all as it is.
    RenderOptions options = render_options_for(r, scene);
    std::vector<Camera> cameras;
    for (const CameraSpec& spec : camera_specs_for(r, scene, options.hidden_faces, options.face_offsets))
        cameras.emplace_back(spec);
    options.threads = control.threads > 0 ? control.threads : ctx.config.render_threads;
    options.progress = control.progress;
    // A contact sheet's frames are estimated as one frame of all their pixels
    // (their buffers are alive together until the sheet is composed).
    const int frames = static_cast<int>(cameras.size());
    const FrameCost cost = estimate_frame_cost(*prepared, r.width, r.height * frames,
                                               {options.antialias, options.shadows || options.ground});
    check_frame_cost(ctx.config, cost);
    // Accepted batch work never goes ahead of interactive requests: a job's
    // thumbnails are as cheap as a client's, but nobody is waiting on each one.
    const RenderPriority priority =
        control.patient ? std::min(priority_for(cost), RenderPriority::normal) : priority_for(cost);
    options.priority = priority;
    AdmissionWait wait = admission_wait(control);
    if (priority == RenderPriority::high) wait.order = AdmissionGate::Order::may_overtake;
    stages.mark("frame_setup");
    std::shared_ptr<AdmissionGate::Ticket> ticket = admit(ctx, ctx.render_gate, cost.memory_bytes, wait);
    stages.mark("queue");

    std::vector<RenderResult> results;
    for (size_t v = 0; v < cameras.size(); ++v) {
        results.push_back(
            render_bounded(ctx, prepared, cameras[v], options, ticket, control.cancel, control.should_stop));
        add_frame_stages(results.back().stats, stages);
        stages.mark("frame_setup");  // the rest: the options, starting the render's thread and joining it
        if (r.views.empty()) continue;
        out.views.push_back({r.views[v].name, cameras[v], results[v].stats, {}, {}});
        if (r.layout != ViewLayout::separate) continue;
        // An image per view, encoded as soon as it is rendered.
        RenderedImage::View& view = out.views.back();
        view.bytes = encode_image(results[v].image, r.format.name);
        view.aovs = aov_buffers(results[v].image, r.aovs);
        stages.mark("encode");
        if (control.view_done) control.view_done(view);
    }
    if (r.layout != ViewLayout::separate) {
        RenderImage sheet;
        if (!r.views.empty()) sheet = compose_sheet(results, view_names(r), options);
        const RenderImage& image = r.views.empty() ? results[0].image : sheet;
        out.bytes = encode_image(image, r.format.name);
        out.aovs = aov_buffers(image, r.aovs);
    }
    ticket.reset();
    stages.mark("encode");

    out.stats = results[0].stats;
    out.camera = cameras[0];
    out.map_precision = r.map_precision;
    out.cost = cost;
    out.priority = priority;
    out.warnings = scene.warnings;
    stages.mark("statistics");
    for (const StageClock::Stage& s : stages.stages()) ctx.metrics.observe_stage(s.name, s.ms / 1000.0);
    ctx.metrics.observe_stage("total", stages.total_ms() / 1000.0);
    return out;
}

std::string views_zip(const RenderedImage& image, const OutputFormat& format) {
    std::vector<ZipEntry> entries;
    for (const RenderedImage::View& v : image.views) entries.push_back({v.name + format.extension, v.bytes});
    return zip_archive(entries);
}

nlohmann::json statistics_json(const RenderedImage& image) {
    nlohmann::json stats = render_stats_json(image.stats, nlohmann::json::object());
    stats["estimate"] = {{"memory_mb", double(image.cost.memory_bytes) / (1 << 20)},
                         {"core_seconds", image.cost.core_seconds},
                         {"priority", priority_name(image.priority)}};
    if (image.camera) stats["camera"] = camera_json(*image.camera);
    if (!image.views.empty()) {  // a contact sheet: the first view above, every view here
        stats["views"] = nlohmann::json::array();
        for (const RenderedImage::View& v : image.views)
            stats["views"].push_back(view_stats_json(v.name, v.camera, v.stats));
    }
    stats["map_precision"] = map_precision_option(image.map_precision);
    stats["warnings"] = image.warnings;
    stats["cache"] = image.cache_hit ? "hit" : "miss";
    stats["timings_ms"] = stage_timings_json(image.timings, kRenderStages);
    return stats;
}

}  // namespace nurbsrt::server
