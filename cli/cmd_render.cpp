// nurbsrt render MODEL... -o image: direct ray tracing of the models' trimmed
// NURBS faces, with optional AOV EXR and statistics JSON (the renderer's RenderImage and RenderStats).
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <string>
#include <thread>

#include <unistd.h>

#include "cli/commands.h"
#include "cli/warnings.h"
#include "cli/scene_file.h"
#include "cli/validators.h"
#include "core/error.h"
#include "renderer/image_module.h"
#include "renderer/render.h"
#include "renderer/stats_json.h"
#include "options/render_request.h"
#include "server/render/stage_timings.h"

namespace nurbsrt::cli {
namespace {

using clock_type = std::chrono::steady_clock;

double ms_since(clock_type::time_point t0) {
    return std::chrono::duration<double, std::milli>(clock_type::now() - t0).count();
}

// The stages of --stats timings_ms, in the order they run (with --isolated also
// prescan, isolation and transfer, the child process's share of the import).
constexpr const char* kCliRenderStages[] = {"read",      "nurbs_convert",   "mesh",       "assemble",   "frame_setup",
                                            "prepare",   "preliminary_map", "newton",     "shadow_map", "shade",
                                            "antialias", "edges",           "statistics", "encode"};

struct Args {
    std::vector<std::string> models;
    std::string output, aov, stats;
    int width = 0, height = 0;  // 0: not given (complete_size)
    std::string view = "iso";
    std::string eye, target, up;
    double fov = 0, ortho_height = 0;
    double fit_margin = kDefaultFitMargin;
    std::string projection;  // empty: resolved_projection's default
    std::string method = "proposed";
    std::string map_precision = "float";
    int threads = 0;
    double tolerance = kDefaultRelativeTolerance;
    std::string background;
    std::optional<int> antialias;  // unset: default_antialias(output format)
    bool edges = false;
    std::string edge_color;
    double edge_width = 1.0;
    bool shadows = false;
    bool ground = false;
    std::optional<double> ground_height;
    std::vector<std::string> sections;  // "px,py,pz,nx,ny,nz" each
    std::string section_mode = "union";
    bool no_caps = false, hatch = false;
    std::vector<std::string> hide, only, ghost, part_colors, part_moves;  // "PATTERN=r,g,b", "PATTERN=dx,dy,dz"
    std::string views;                                                    // "front,top,..." of a contact sheet
    double explode = 0;
    std::string explode_level = "top";
    std::string layout = "sheet";  // of --views: one sheet, or a file per view
    std::string out_dir;           // several files rendered one by one into it (instead of -o)
    std::string format = "png";    // of the images written into out_dir
    LoadOptions load;
    bool quiet = false;
    bool strict = false;
};

// The request model of the flags (options/render_request.h): the texts CLI11
// has checked are parsed here, once; the camera and the renderer's options are
// then built from it exactly as the service builds them.
RenderRequest request_of(const Args& a) {
    RenderRequest r;
    complete_size(a.width ? std::optional<int>(a.width) : std::nullopt,
                  a.height ? std::optional<int>(a.height) : std::nullopt, r.width, r.height);
    r.view = a.view;
    if (!a.eye.empty()) r.eye = parse_point(a.eye, "--eye");
    if (!a.target.empty()) r.target = parse_point(a.target, "--target");
    if (!a.up.empty()) r.up = parse_point(a.up, "--up");
    if (!a.projection.empty())
        r.projection = a.projection == "orthographic" ? Projection::orthographic : Projection::perspective;
    if (a.fov > 0) r.fov_deg = a.fov;  // a field of view means perspective unless --projection says otherwise
    if (a.ortho_height > 0) r.ortho_height = a.ortho_height;
    r.fit_margin = a.fit_margin;
    r.method = *parse_newton_method(a.method);
    r.map_precision = *parse_map_precision(a.map_precision);
    r.tolerance = a.tolerance;
    r.format = output_format(
        image_format_of_extension(a.out_dir.empty() ? std::filesystem::path(a.output).extension().string() : a.format));
    if (!a.background.empty()) r.background = parse_background(a.background, "--background");
    r.look.antialias = a.antialias;
    r.look.edges = a.edges;
    if (!a.edge_color.empty()) r.look.edge_color = parse_rgb(a.edge_color, "--edge-color");
    r.look.edge_width = a.edge_width;
    r.look.shadows = a.shadows;
    r.look.ground = a.ground || a.ground_height.has_value();
    r.look.ground_height = a.ground_height;
    if (a.sections.size() > kMaxSectionPlanes)  // a usage error (exit 2), as the API's 400
        throw CLI::ValidationError("--section", "at most " + std::to_string(kMaxSectionPlanes) + " planes (got " +
                                                    std::to_string(a.sections.size()) + ")");
    for (const std::string& plane : a.sections) r.sections.planes.push_back(parse_section_plane(plane, "--section"));
    r.sections.mode = *parse_section_mode(a.section_mode);
    r.sections.caps = !a.no_caps;
    r.sections.hatch = a.hatch;
    r.layout = *parse_view_layout(a.layout);
    if (r.layout == ViewLayout::separate && a.views.empty())
        throw CLI::ValidationError("--layout", "separate writes a file per view of --views, which is not given");
    r.explode = a.explode;
    r.explode_level = *parse_explode_level(a.explode_level);
    r.parts.hide = a.hide;
    r.parts.only = a.only;
    r.parts.ghost = a.ghost;
    for (const std::string& pc : a.part_colors) r.parts.color.push_back(parse_part_color(pc, "--part-color"));
    for (const std::string& pm : a.part_moves) r.parts.move.push_back(parse_part_move(pm, "--part-move"));
    if (!a.views.empty())  // over the request's camera (its projection, field of view, margin)
        for (const std::string& name : parse_views(a.views, "--views")) r.views.push_back(named_request_view(r, name));
    return r;
}

// The camera checks that need no model (eye at the target, up along the view)
// are usage errors found before the import, as the API finds them.
void check_camera_before_import(const Args& a, const RenderRequest& r) {
    try {
        check_camera_without_scene(r);
    } catch (const Error& e) {
        const char* flag = !a.up.empty() ? "--up" : !a.target.empty() ? "--target" : "--eye";
        throw CLI::ValidationError(flag, e.what());
    }
}

// Options are bound to the fields of `a`, which outlives the parse (the
// command's callback holds it).
void add_output_options(CLI::App* cmd, Args& a) {
    // Checked in the callback, after CLI11 has reported unknown options: with a
    // CLI11 check here, `--widht 100` would be reported as a missing file "100".
    cmd->add_option("MODEL", a.models, "STEP/IGES file(s), NURBS JSON, or a JSON scene file")->required();
    CLI::Option* output = cmd->add_option("-o,--output", a.output, "image to write: .png, .jpg, .tif or .exr")
                              ->check(output_file_validator({".png", ".jpg", ".jpeg", ".tif", ".tiff", ".exr"}));
    CLI::Option* aov = cmd->add_option("--aov", a.aov, "also write the AOV EXR (R,G,B,A,Z,face,...)")
                           ->check(output_file_validator({".exr"}));
    cmd->add_option("--out-dir", a.out_dir,
                    "render each MODEL on its own into this directory, as STEM.png (--format), in one process: "
                    "one OpenGL set-up and image module for all; a file that fails is reported and the rest go on")
        ->excludes(output)
        ->excludes(aov)
        ->check(CLI::ExistingDirectory);
    cmd->add_option("--format", a.format, "image format of --out-dir: png, jpg, tif or exr")
        ->check(CLI::IsMember({"png", "jpg", "jpeg", "tif", "tiff", "exr"}))
        ->capture_default_str();
    cmd->add_option("--stats", a.stats, "write statistics and stage timings as JSON ('-' for stdout)")
        ->check(output_file_validator({".json"}) | CLI::IsMember({"-"}));
}

// "x,y,z" of --eye, --target and --up, as the API reads its text points.
CLI::Validator point_check() {
    return shared_check([](const std::string& s) { parse_point(s, "the value"); }, "X,Y,Z");
}

void add_camera_options(CLI::App* cmd, Args& a) {
    cmd->add_option("--width", a.width, "image width in pixels (default 800; given alone, the height keeps 4:3)")
        ->check(in_range(1, 16384));
    cmd->add_option("--height", a.height, "image height in pixels (default 600; given alone, the width keeps 4:3)")
        ->check(in_range(1, 16384));
    cmd->add_option("--view", a.view,
                    "named view fitted to the model, Z up, looking along: front +Y, back -Y, left +X, right -X, "
                    "top -Z, bottom +Z (up +Y for these two), iso (-1,-1,-1) from the +X+Y+Z octant")
        ->check(CLI::IsMember({"iso", "front", "back", "left", "right", "top", "bottom"}))
        ->capture_default_str();
    cmd->add_option("--eye", a.eye, "camera position x,y,z (model units; write --eye=-1,2,3 for a leading minus)")
        ->check(point_check());
    cmd->add_option("--target", a.target, "point looked at, x,y,z")->check(point_check());
    cmd->add_option("--up", a.up, "up vector x,y,z")->check(point_check());
    cmd->add_option("--fov", a.fov, "vertical field of view in degrees (perspective)")->check(in_range(0.01, 179.0));
    cmd->add_option("--ortho-height", a.ortho_height, "orthographic view height in model units (implies orthographic)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--fit-margin", a.fit_margin,
                    "empty border left on each side of a fitted view, as a fraction of the frame's width and height")
        ->check(in_range(0.0, kMaxFitMargin))
        ->capture_default_str();
    cmd->add_option("--projection", a.projection,
                    "perspective or orthographic (default: orthographic for the named views, as CAD draws them; "
                    "perspective with --eye or --fov)")
        ->check(CLI::IsMember({"perspective", "orthographic"}));
}

void add_solver_options(CLI::App* cmd, Args& a) {
    cmd->add_option("--method", a.method, "Newton method: proposed (paper eq. 9-11) or martin (Martin et al. 2000)")
        ->check(CLI::IsMember({"proposed", "martin"}))
        ->capture_default_str();
    cmd->add_option("--map-precision", a.map_precision,
                    "preliminary map: float (32-bit id, float u,v) or rgb8 (u,v quantized as paper eq. 4)")
        ->check(CLI::IsMember({"float", "rgb8"}))
        ->capture_default_str();
    cmd->add_option("--threads", a.threads, "worker threads (0: all cores)")
        ->check(in_range(0, 1024))
        ->capture_default_str();
    cmd->add_option("--tolerance", a.tolerance,
                    "Newton stop tolerance, paper eq. (12): distance of the hit from the pixel ray as a fraction of "
                    "the bounding-box diagonal (same for both methods)")
        ->check(in_range(1e-15, 1e-3))
        ->capture_default_str();
}

void add_import_options(CLI::App* cmd, Args& a) {
    cmd->add_option("--mesh-deflection", a.load.import.mesh_relative_deflection,
                    "preliminary-map mesh deflection, fraction of the bounding-box diagonal")
        ->check(in_range(1e-6, 0.5))
        ->capture_default_str();
    cmd->add_flag("--isolated", a.load.isolated, "import in a child process with a time limit");
    cmd->add_flag("-q,--quiet", a.quiet, "no progress messages or warnings on stderr");
    cmd->add_flag("--strict", a.strict,
                  "fail with exit status 3, writing nothing, when the import has warnings (a face left empty, ...)");
}

void add_look_options(CLI::App* cmd, Args& a) {
    cmd->add_option("--background", a.background,
                    "background: r,g,b (opaque) or r,g,b,a in [0,1], or transparent (default: transparent; "
                    "opaque white for JPEG)")
        ->check(shared_check([](const std::string& s) { parse_background(s, "the value"); }, "R,G,B[,A]|transparent"));
    cmd->add_option(
           "--antialias", a.antialias,
           "extra sub-pixel samples per edge pixel (silhouettes, face borders, creases), exact rays where an edge "
           "can cross them; 0: off "
           "(default: " +
               std::to_string(kDefaultAntialias) + " for PNG/JPEG, 0 for TIFF/EXR)")
        ->check(shared_check([](const std::string& s) { parse_antialias(std::stod(s), "the value"); }, "N"));
    cmd->add_flag("--edges", a.edges, "draw feature lines: silhouettes, face borders and creases");
    cmd->add_option("--edge-color", a.edge_color, "feature line colour r,g,b in [0,1] (default 0.02,0.02,0.02)")
        ->check(shared_check([](const std::string& s) { parse_rgb(s, "the value"); }, "R,G,B"));
    cmd->add_option("--edge-width", a.edge_width, "feature line width in pixels, at any resolution")
        ->check(shared_check([](const std::string& s) { parse_edge_width(std::stod(s), "the value"); }, "PX"))
        ->capture_default_str();
    cmd->add_flag("--shadows", a.shadows,
                  "exact shadows of the key light (a preliminary map from the light, Newton along light rays)");
    cmd->add_option("--views", a.views,
                    "several named views in one image, a labelled contact sheet (about square), each view "
                    "--width x --height: e.g. front,top,right,iso (at most " +
                        std::to_string(kMaxViews) + ")")
        ->check(shared_check([](const std::string& s) { parse_views(s, "the value"); }, "V1,V2,..."));
    cmd->add_option("--layout", a.layout,
                    "of --views: sheet (one labelled image) or separate (a file per view: OUT-front.png, ...)")
        ->check(CLI::IsMember({"sheet", "separate"}))
        ->capture_default_str();
    cmd->add_option("--explode", a.explode,
                    "exploded view: each top-level part moved away from the assembly's centre by this many times "
                    "the assembly's size (0 to 10; 0.3 reads well)")
        ->check(shared_check([](const std::string& s) { checked_explode(std::stod(s), "the value"); }, "F"));
    cmd->add_option("--explode-level", a.explode_level, "what --explode moves: top (top-level parts) or leaves")
        ->check(CLI::IsMember({"top", "leaves"}))
        ->capture_default_str();
    cmd->add_flag("--ground", a.ground,
                  "a ground under the model that takes the key light's exact shadows (turns --shadows on): a grey "
                  "floor over an opaque background, only the shadow over a transparent one");
    cmd->add_option("--ground-height", a.ground_height, "the ground's height z (default: the model's lowest point)")
        ->check(shared_check(
            [](const std::string& s) {
                checked_point({std::stod(s), 0, 0}, "the value");
            },
            "Z"));
    cmd->add_option("--section", a.sections,
                    "section plane px,py,pz,nx,ny,nz: removes the side the normal points to (repeatable, at most " +
                        std::to_string(kMaxSectionPlanes) + ")")
        ->check(shared_check([](const std::string& s) { parse_section_plane(s, "the value"); }, "PX,PY,PZ,NX,NY,NZ"));
    cmd->add_option("--section-mode", a.section_mode,
                    "union: remove every plane's half-space; cutaway: only where all planes' half-spaces meet")
        ->check(CLI::IsMember({"union", "cutaway"}))
        ->capture_default_str();
    cmd->add_flag("--no-caps", a.no_caps, "cut closed bodies open (no caps on the section planes)");
    cmd->add_flag("--hatch", a.hatch, "hatching lines over the section caps");
    const CLI::Validator part_pattern =
        shared_check([](const std::string& s) { check_part_pattern(s, "the value"); }, "ID|GLOB");
    cmd->add_option("--hide", a.hide, "leave out a part: its id (0/3/1, see nurbsrt info) or a name glob (repeatable)")
        ->check(part_pattern);
    cmd->add_option("--only", a.only, "show only these parts: id or name glob (repeatable)")->check(part_pattern);
    cmd->add_option("--ghost", a.ghost,
                    "draw a part see-through over what lies behind it: id or name glob (repeatable)")
        ->check(part_pattern);
    cmd->add_option("--part-color", a.part_colors, "colour a part: ID_OR_GLOB=r,g,b in [0,1] (repeatable)")
        ->check(shared_check([](const std::string& s) { parse_part_color(s, "the value"); }, "ID|GLOB=R,G,B"));
    cmd->add_option("--part-move", a.part_moves,
                    "move a part by dx,dy,dz model units: ID_OR_GLOB=dx,dy,dz (repeatable; adds to --explode)")
        ->check(shared_check([](const std::string& s) { parse_part_move(s, "the value"); }, "ID|GLOB=DX,DY,DZ"));
}

// Progress on stderr: live on a terminal; otherwise a line per 10% once the
// render has taken over a second (logs of long renders, quiet for short ones).
class ProgressPrinter {
public:
    explicit ProgressPrinter(clock_type::time_point t0) : t0_(t0), tr_(clock_type::now()) {}
    void operator()(double f) {
        const double ms = ms_since(tr_);
        if (tty_) {
            if (ms < 300 && f < 1.0) return;
            std::fprintf(stderr, "\rnurbsrt: rendering %3.0f%%", 100.0 * f);
            if (f >= 1.0) std::fputc('\n', stderr);
            live_ = f < 1.0;
        } else if (ms > 1000 && f >= 0.1 * next_decile_) {
            std::fprintf(stderr, "nurbsrt: [%8.1f ms] rendering %3.0f%%\n", ms_since(t0_), 100.0 * f);
            next_decile_ = static_cast<int>(f * 10.0) + 1;
        }
        std::fflush(stderr);
    }
    // Ends a live line that the render left unfinished (canceled or failed: no 100 %).
    void finish() const {
        if (live_) std::fputc('\n', stderr);
    }

private:
    clock_type::time_point t0_, tr_;
    bool tty_ = isatty(STDERR_FILENO) != 0;
    bool live_ = false;
    int next_decile_ = 1;
};

// OUT's path for one view of --layout separate: part.png -> part-front.png.
std::string per_view_path(const std::string& path, const std::string& view) {
    const std::filesystem::path p(path);
    return (p.parent_path() / (p.stem().string() + "-" + view + p.extension().string())).string();
}

// The frames of a request: one, or one per view of a contact sheet.
struct Frames {
    std::vector<Camera> cameras;
    std::vector<RenderResult> results;
};

// Progress lines on stderr, stamped with the time since the command began.
class Say {
public:
    Say(bool quiet, clock_type::time_point t0) : quiet_(quiet), t0_(t0) {}
    template <class... Xs>
    void operator()(const char* fmt, Xs... xs) const {
        if (quiet_) return;
        std::fprintf(stderr, "nurbsrt: [%8.1f ms] ", ms_since(t0_));
        if constexpr (sizeof...(Xs) == 0)
            std::fputs(fmt, stderr);
        else
            std::fprintf(stderr, fmt, xs...);
        std::fputc('\n', stderr);
    }
    clock_type::time_point t0() const { return t0_; }

private:
    bool quiet_;
    clock_type::time_point t0_;
};

// Where one scene's render goes: the image (a sheet, or a file per view), the
// AOV EXR (or none).
struct Outputs {
    std::string image, aov;
};

nlohmann::json stats_of(const RenderRequest& r, const Scene& scene, const Frames& frames, StageClock& stages) {
    nlohmann::json j = render_stats_json(frames.results[0].stats, nlohmann::json::object());
    j["camera"] = camera_json(frames.cameras[0]);
    if (!r.views.empty()) {  // a sheet: the first view above, every view here
        j["views"] = nlohmann::json::array();
        for (size_t v = 0; v < r.views.size(); ++v)
            j["views"].push_back(view_stats_json(r.views[v].name, frames.cameras[v], frames.results[v].stats));
    }
    j["map_precision"] = map_precision_option(r.map_precision);
    j["warnings"] = scene.warnings;
    stages.mark("statistics");
    j["timings_ms"] = server::stage_timings_json(stages, kCliRenderStages);
    return j;
}

void write_json(const std::string& path, const nlohmann::json& j) {
    if (path == "-") {
        std::cout << j.dump(2) << "\n";
        return;
    }
    std::ofstream out(path);
    out << j.dump(2) << "\n";
    if (!out) throw Error(ErrorCode::io, "cannot write " + path);
}

// Reads `models` as one scene, with their stages on `stages`.
Scene load_scene(const Args& a, const std::vector<std::string>& models, StageClock& stages, const Say& say) {
    say("importing %zu model(s)", models.size());
    IsolationTimings isolation;
    Scene scene = load_models(models, a.load, &isolation);
    add_import_stages(scene.timings, stages);
    if (a.load.isolated) {
        stages.add("prescan", isolation.prescan_ms);
        stages.add("isolation", isolation.isolation_ms);
        stages.add("transfer", isolation.transfer_ms);
    }
    stages.mark("assemble");  // the rest: scene files, placing and joining the models
    report_warnings(scene.warnings, a.quiet, a.strict);
    say("imported %zu faces (read %.0f ms, nurbs_convert %.0f ms, mesh %.0f ms)", scene.faces.size(),
        scene.timings.read_ms, scene.timings.nurbs_convert_ms, scene.timings.mesh_ms);
    return scene;
}

// Renders `scene` as `request` asks and writes `out`; the frames for the
// statistics. `map_warm_up` (if still running) is waited for before the first frame.
Frames render_and_write(const Args& a, const RenderRequest& request, const Scene& scene, const Outputs& out,
                        StageClock& stages, std::jthread& map_warm_up, const Say& say) {
    RenderOptions options = render_options_for(request, scene);  // explode: options.face_offsets
    Frames frames;
    for (const CameraSpec& spec : camera_specs_for(request, scene, options.hidden_faces, options.face_offsets))
        frames.cameras.emplace_back(spec);
    options.threads = a.threads;
    say("rendering %zu view(s) of %dx%d with %s", frames.cameras.size(), frames.cameras[0].width(),
        frames.cameras[0].height(), a.method.c_str());
    auto progress = std::make_shared<ProgressPrinter>(say.t0());
    if (!a.quiet) options.progress = [progress](double f) { (*progress)(f); };
    // One prepare() for every view (render(scene, ...) would prepare per frame).
    const PreparedScene prepared = prepare(scene, a.threads);
    stages.add("prepare", prepared.prepare_ms());
    if (map_warm_up.joinable()) map_warm_up.join();  // what is left of it (none for a file that takes longer to read)
    stages.mark("frame_setup");
    for (const Camera& camera : frames.cameras) {
        frames.results.push_back(render(prepared, camera, options));
        add_frame_stages(frames.results.back().stats, stages);
    }
    stages.mark("frame_setup");  // the rest of the calls of render()
    progress->finish();
    for (const RenderResult& result : frames.results)
        say("rendered: %zu pixels hit, %.2f Newton iterations per primary solve, %.0f ms", result.stats.pixels_hit,
            result.stats.mean_iterations, result.stats.total_ms);

    if (request.layout == ViewLayout::separate) {  // a file per view, named after it
        for (size_t v = 0; v < frames.results.size(); ++v) {
            const std::string path = per_view_path(out.image, request.views[v].name);
            write_image(frames.results[v].image, path);
            if (!out.aov.empty()) write_image(frames.results[v].image, per_view_path(out.aov, request.views[v].name));
            say("wrote %s", path.c_str());
        }
        stages.mark("encode");
        return frames;
    }
    const RenderImage* image = &frames.results[0].image;
    RenderImage sheet;
    if (!request.views.empty()) {
        sheet = compose_sheet(frames.results, view_names(request), options);
        image = &sheet;
    }
    write_image(*image, out.image);
    if (!out.aov.empty()) write_image(*image, out.aov);
    stages.mark("encode");
    say("wrote %s%s%s", out.image.c_str(), out.aov.empty() ? "" : " and ", out.aov.c_str());
    return frames;
}

// --out-dir: DIR/STEM.EXT of every model; two models of one stem would
// overwrite each other, so that is a usage error before any work.
std::vector<std::string> out_dir_paths(const Args& a, const RenderRequest& request) {
    std::vector<std::string> paths;
    for (const std::string& m : a.models) {
        const std::string stem = std::filesystem::path(m).stem().string();
        const std::string path = (std::filesystem::path(a.out_dir) / (stem + request.format.extension)).string();
        for (size_t k = 0; k < paths.size(); ++k)
            if (paths[k] == path)
                throw CLI::ValidationError("--out-dir", a.models[k] + " and " + m + " would both write " + path);
        paths.push_back(path);
    }
    return paths;
}

// Each model on its own, one after the other, in this process: the OpenGL
// contexts, the image module and the libraries are set up once for all. A
// model that fails is reported with its error and the rest go on; the command
// then fails naming how many did.
void render_each(const Args& a, const RenderRequest& request, std::jthread& map_warm_up, const Say& say) {
    const std::vector<std::string> paths = out_dir_paths(a, request);
    nlohmann::json files = nlohmann::json::array();
    size_t failed = 0;
    for (size_t k = 0; k < a.models.size(); ++k) {
        StageClock stages(clock_type::now());
        nlohmann::json entry = {{"file", a.models[k]}, {"output", paths[k]}};
        try {
            const Scene scene = load_scene(a, {a.models[k]}, stages, say);
            const Frames frames = render_and_write(a, request, scene, {paths[k], ""}, stages, map_warm_up, say);
            entry["statistics"] = stats_of(request, scene, frames, stages);
        } catch (const WarningsRefused& e) {
            ++failed;
            std::fprintf(stderr, "nurbsrt: %s: error [strict]: %s\n", a.models[k].c_str(), e.what());
            entry["error"] = {{"code", "strict"}, {"detail", e.what()}};
        } catch (const Error& e) {
            ++failed;
            std::fprintf(stderr, "nurbsrt: %s: error [%s]: %s\n", a.models[k].c_str(), error_code_name(e.code()),
                         e.what());
            entry["error"] = {{"code", error_code_name(e.code())}, {"detail", e.what()}};
        }
        files.push_back(std::move(entry));
    }
    if (!a.stats.empty()) write_json(a.stats, {{"files", files}});
    say("rendered %zu of %zu files into %s", a.models.size() - failed, a.models.size(), a.out_dir.c_str());
    if (failed)
        throw Error(ErrorCode::invalid_argument, std::to_string(failed) + " of " + std::to_string(a.models.size()) +
                                                     " files failed (each reported above); the others were written");
}

void run_render(const Args& a) {
    for (const std::string& m : a.models)
        if (const std::string why = CLI::ExistingFile(m); !why.empty()) throw CLI::ValidationError("MODEL", why);
    if (a.output.empty() && a.out_dir.empty())
        throw CLI::ValidationError("--output",
                                   "give the image to write (-o) or a directory for each model's (--out-dir)");
    const RenderRequest request = request_of(a);
    check_camera_before_import(a, request);
    const Say say(a.quiet, clock_type::now());
    locate_image_module();                  // a missing module fails now, not after the import
    const ImageWriterPreload image_writer;  // overlaps the import: OpenImageIO's libraries take ~0.3 s to load
    // Overlaps the import too: the first map's OpenGL context, shaders and llvmpipe code.
    std::jthread map_warm_up([w = request.width, h = request.height] { warm_up_preliminary_maps(1, w, h); });
    if (!a.out_dir.empty()) return render_each(a, request, map_warm_up, say);
    // --stats timings: stages marked end to end from the start, so they sum to the total.
    StageClock stages(say.t0());
    const Scene scene = load_scene(a, a.models, stages, say);
    const Frames frames = render_and_write(a, request, scene, {a.output, a.aov}, stages, map_warm_up, say);
    if (!a.stats.empty()) write_json(a.stats, stats_of(request, scene, frames, stages));
}

}  // namespace

void add_render_command(CLI::App& app) {
    auto a = std::make_shared<Args>();
    auto* cmd = app.add_subcommand(
        "render",
        "Ray trace the exact trimmed NURBS faces of STEP/IGES models (preliminary map\n"
        "with OpenGL, then Newton iteration per pixel).\n"
        "MODEL is a STEP/IGES file, the NURBS JSON that 'nurbsrt convert IN OUT.json' writes,\n"
        "or a JSON scene file listing such files with transforms:\n"
        "  {\"models\": [{\"file\": \"duck.igs\", \"translate\": [5,0,0], \"rotate_deg\": [0,0,90], \"scale\": 1}]}\n"
        "Examples:\n"
        "  nurbsrt render part.step -o part.png --view iso --width 800 --height 600\n"
        "  nurbsrt render part.step -o part.png --aov part.exr --stats stats.json --method martin\n"
        "  nurbsrt render part.step -o top.png --view top --ortho-height 120\n"
        "  nurbsrt render part.step -o p.png --eye=-100,50,80 --target 0,0,0 --up 0,0,1 --fov 30");
    add_output_options(cmd, *a);
    add_camera_options(cmd, *a);
    add_solver_options(cmd, *a);
    add_look_options(cmd, *a);
    add_import_options(cmd, *a);
    cmd->callback([a] { run_render(*a); });
}

}  // namespace nurbsrt::cli
