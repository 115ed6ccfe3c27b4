// The "upload -> rendered image bytes + statistics" step shared by POST
// /v1/renders and batch jobs: limit checks, the scene (cache or isolated
// import), the render bounded in time and cancelable, and the encoding.
#pragma once

#include <atomic>
#include <chrono>
#include <optional>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "core/stage_clock.h"
#include "renderer/camera.h"
#include "renderer/frame_cost.h"
#include "renderer/render.h"
#include "server/render/context.h"
#include "options/render_request.h"

namespace nurbsrt::server {

// One AOV of a frame as raw bytes: width x height x components values of
// `type` (float32, uint32 or uint8), little-endian, row 0 = top.
struct AovBuffer {
    Aov aov;
    const char* type;
    int components;
    std::string bytes;
};

struct RenderedImage {
    std::string bytes;            // the encoded image (r.format); empty for layout separate
    std::vector<AovBuffer> aovs;  // those of r.aovs, in kAllAovs order
    // What the Statistics object of the answer and of a job's result says,
    // serialised once, at the edge (statistics_json).
    RenderStats stats;
    std::optional<Camera> camera;  // the first view's on a contact sheet
    // A contact sheet's views (RenderRequest::views): name, camera, frame statistics.
    struct View {
        std::string name;
        Camera camera;
        RenderStats stats;
        // Layout separate (RenderRequest::layout): the view's own image and AOVs.
        std::string bytes;
        std::vector<AovBuffer> aovs;
    };
    std::vector<View> views;
    MapPrecision map_precision = MapPrecision::float32;
    FrameCost cost;
    RenderPriority priority = RenderPriority::normal;
    std::vector<std::string> warnings;  // the import's
    bool cache_hit = false;
    // The stages from RenderControl::start to the statistics; a caller that
    // builds an answer from this marks its own stage ("response") on it and so
    // keeps the stages summing to the total.
    StageClock timings;
};

// Layout separate: a ZIP of the views' images, "<view>.<extension>" each (the
// API's answer without JSON; a job stores each view as an artifact instead).
std::string views_zip(const RenderedImage& image, const OutputFormat& format);

// The Statistics object of `image` (the renderer's statistics with the camera,
// the estimate, the cache, the warnings), with timings_ms as `image.timings`
// holds them now.
nlohmann::json statistics_json(const RenderedImage& image);

struct RenderControl {
    // Set by the caller to stop the render (a deleted job); the render then ends
    // with Error(canceled) at its next block of rows.
    std::shared_ptr<const std::atomic<bool>> cancel;
    // Polled by the waiting caller's thread (about every 50 ms): true stops the
    // render the same way (a client that disconnected).
    std::function<bool()> should_stop;
    // Fraction done in (0, 1], from the rendering threads.
    std::function<void(double)> progress;
    // When the request started (the `total` timing and its first stage, `upload`,
    // run from here); default: the call.
    std::optional<std::chrono::steady_clock::time_point> start;
    // Accepted batch work: waits for admission as long as it takes (see AdmissionWait).
    bool patient = false;
    // The SHA-256 (hex) of the CAD bytes when the caller knows it (a stored
    // file's id): the scene cache's key is made from it, without hashing the
    // bytes again. Empty: hashed here.
    std::string content_sha256;
    // The scene when the caller holds it already (a job's file, imported once
    // for all its outputs): no cache lookup and no import; counted as a hit.
    std::shared_ptr<const PreparedScene> scene;
    // The frame's threads (RenderOptions::threads); 0: the service's --render-threads.
    int threads = 0;
    // Layout separate: called with each view as soon as its image is encoded,
    // before the next view renders (a job stores it as its artifact then).
    // What it throws ends the render.
    std::function<void(const RenderedImage::View&)> view_done;
};

// The imported and prepared scene of `cad_bytes` (STEP/IGES, checked by
// content): from the scene cache, by waiting for a simultaneous request's
// import of the same bytes, or imported in a child process (holding an import
// slot, importer/isolated.h) and prepared here, once for every later render of
// the same bytes. Throws the import's Error (unreadable_file, import_crashed,
// ...). `cache_hit`: no import was paid. `stages` gets this call's stages
// marked end to end: cache (the key's hash of the bytes, the lookup, the insert,
// or the wait for another request's import), and on a miss queue (the wait for
// the slot), prescan, isolation, read, nurbs_convert, mesh, transfer, prepare.
// Also what POST /v1/files imports, so a stored file's first render is a hit.
std::shared_ptr<const PreparedScene> imported_scene(ServerContext& ctx, const std::string& cad_bytes,
                                                    const RenderControl& control, bool& cache_hit, StageClock& stages);

// Renders `cad_bytes` (STEP/IGES, already checked by content) with `r`.
// Admission happens here, in two steps: an import slot (ctx.gate) when the
// scene is not cached, then the render's estimated memory and work
// (estimate_frame_cost) against the per-render caps and the render gate's
// budget; the render runs at a priority from its estimated work. Each ticket
// is held until its work really stops. Throws nurbsrt::Error (import errors,
// limit_exceeded for too many faces or too costly a frame, overloaded,
// render_timeout, canceled). The stage times (timings_ms: marked end to end on
// one clock from control.start, so they sum to the total; the time spent
// waiting for admission is `queue`) also go to the metrics.
RenderedImage render_upload(ServerContext& ctx, const std::string& cad_bytes, const RenderRequest& r,
                            const RenderControl& control = {});

}  // namespace nurbsrt::server
