// The request model of a render, one for the CLI and the service: size, view or
// camera, method, map precision, output format, background, anti-aliasing,
// feature lines, shadows, AOVs. The CLI fills it from its flags, the service from
// JSON or query parameters (parse_render_options); both validate values with the
// same parsers below and build the camera and the renderer's options from it
// with the same functions (camera_spec_for, render_options_for).
#pragma once

#include <cstdint>
#include <cstdint>
#include <optional>
#include <string_view>
#include <string>

#include "importer/importer.h"
#include "renderer/camera.h"
#include "renderer/render.h"
#include "options/image_format.h"
#include "options/part_selection.h"
#include "core/scene/explode.h"

namespace nurbsrt {

// The background of the image: colour and alpha (0 transparent, 1 opaque).
struct Background {
    Vec3 rgb{0, 0, 0};
    double alpha = 0;
};

// "transparent", "r,g,b" (opaque) or "r,g,b,a", each in [0, 1]. Throws
// Error(invalid_argument) naming `what` (the option or flag). Shared by the
// API and the CLI, so both accept and refuse the same values.
Background parse_background(const std::string& text, const std::string& what);
// A format's default: transparent where it has alpha (PNG, TIFF, EXR), opaque
// white for JPEG, which cannot carry "no background".
Background default_background(ImageFormat format);
// The renderer's background colour and alpha (floats) from `bg`.
void apply_background(const Background& bg, RenderOptions& options);

// Anti-aliasing and feature lines, the same options on the API and the CLI.
// Extra rays per edge pixel: 4 make 5 samples, an edge pixel's coverage within
// about 1/10 (stratified), for a frame's cost well under its Newton stage; 64 is
// far past where more rays change an 8-bit pixel.
constexpr int kDefaultAntialias = 4, kMaxAntialias = 64;
// Line widths in pixels: a hairline to a marker's stroke.
constexpr double kMinEdgeWidth = 0.25, kMaxEdgeWidth = 16;
struct ImageLook {
    std::optional<int> antialias;  // unset: default_antialias(format)
    bool edges = false;
    Color edge_color{0.02f, 0.02f, 0.02f};
    double edge_width = 1.0;
    bool shadows = false;
    bool ground = false;                  // RenderOptions::ground
    std::optional<double> ground_height;  // checked_point's bounds
};
// On for PNG and JPEG, pictures for people; off for TIFF and EXR, which carry
// exact per-pixel values into other tools (one centre sample per pixel).
int default_antialias(ImageFormat format);
// Each throws Error(invalid_argument) naming `what`.
int parse_antialias(double n, const std::string& what);
double parse_edge_width(double w, const std::string& what);
Color parse_rgb(const std::string& text, const std::string& what);  // "r,g,b" in [0, 1]
void apply_look(const ImageLook& look, ImageFormat format, RenderOptions& options);

// The default image size of the API and the CLI; given one side only, the
// other keeps the default aspect (width 640 alone: 640x480).
constexpr int kDefaultWidth = 800, kDefaultHeight = 600;
void complete_size(std::optional<int> width, std::optional<int> height, int& out_width, int& out_height);

// Per-pixel AOVs a render may return beside its image, in the JSON answer of
// POST /v1/renders, as raw little-endian arrays a browser reads directly
// (typed arrays) where it could not decode OpenEXR.
enum class Aov : uint8_t { z, face, normal, uv, iterations };
inline constexpr Aov kAllAovs[] = {Aov::z, Aov::face, Aov::normal, Aov::uv, Aov::iterations};
constexpr unsigned aov_bit(Aov a) { return 1u << static_cast<unsigned>(a); }
const char* aov_name(Aov a);  // z, face, normal, uv, iterations

// Section planes (renderer/section.h), the same checks for the API and the CLI.
// A plane: its point (checked_point) and a finite, non-zero normal, made unit.
// Throws Error(invalid_argument) naming `what`.
SectionPlane checked_section_plane(Vec3 point, Vec3 normal, const std::string& what);
// "px,py,pz,nx,ny,nz" (the CLI's --section, a query parameter's plane).
SectionPlane parse_section_plane(const std::string& text, const std::string& what);
// More than kMaxSectionPlanes planes: Error(invalid_argument) naming `what`.
void check_section_count(size_t planes, const std::string& what);

// Several named views of one import in one request (RenderRequest::views): a
// contact sheet of 2 to 6 views is the catalogue's use; 16 (a 4x4 sheet) is
// the most a sheet can show legibly.
inline constexpr size_t kMaxViews = 16;

// How a request's views are delivered: one labelled contact sheet, or an image
// per view (the CLI: a file each; the API: a ZIP, or in JSON a list; a job: an
// artifact each).
enum class ViewLayout : uint8_t { sheet, separate };
const char* view_layout_name(ViewLayout l);  // "sheet", "separate"
std::optional<ViewLayout> parse_view_layout(std::string_view name);

// The camera fields of a request, and of each of its views.
struct RequestCamera {
    std::string view = "iso";
    // Unset: resolved_projection() below decides.
    std::optional<Projection> projection;
    std::optional<double> fov_deg, ortho_height;
    std::optional<Vec3> eye, target, up;
    double fit_margin = kDefaultFitMargin;  // of the frame, each side (named views, and an eye alone)
};

// One view of a request's `views`: its label (the sheet's, the file's and the
// ZIP entry's name) and its camera, the request's with what the view gives
// replaced (a named view: its own placement; a camera: its fields).
struct RequestView {
    std::string name;
    RequestCamera camera;
};

struct RenderRequest : RequestCamera {
    int width = kDefaultWidth, height = kDefaultHeight;
    NewtonMethod method = NewtonMethod::proposed;
    MapPrecision map_precision = MapPrecision::float32;
    // Newton's stop tolerance (Sisojevs & Glazs 2010, eq. (12)) as a fraction of the
    // scene's bounding-box diagonal: the CLI's --tolerance; the API keeps the default.
    double tolerance = kDefaultRelativeTolerance;
    OutputFormat format = output_format(ImageFormat::png);
    bool format_given = false;             // the request named it (else the service may take it from Accept)
    std::optional<Background> background;  // unset: default_background(format)
    unsigned aovs = 0;                     // aov_bit() of each AOV asked for
    ImageLook look;
    Sections sections;    // planes (checked, unit normals), mode, caps, hatching
    PartSelection parts;  // hidden, isolated and recoloured parts (options/part_selection.h)
    // The views of a contact sheet (compose_sheet) or of layout separate, each
    // width x height; empty: the request's own camera.
    std::vector<RequestView> views;
    ViewLayout layout = ViewLayout::sheet;  // separate: only with views
    // An exploded view (core/scene/explode.h): factor in [0, kMaxExplode] of the
    // assembly's size; 0: none.
    double explode = 0;
    ExplodeLevel explode_level = ExplodeLevel::top;
};

// The explode factor checked: finite, in [0, kMaxExplode]. Throws
// Error(invalid_argument) naming `what`.
double checked_explode(double factor, const std::string& what);

// "front,top,right,iso" (the CLI's --views, a query parameter) or a list's
// names: 1 to kMaxViews known views. Throws Error(invalid_argument) naming `what`.
std::vector<std::string> checked_views(const std::vector<std::string>& names, const std::string& what);
std::vector<std::string> parse_views(const std::string& text, const std::string& what);
// The view of `views` that a named view makes: `base` (the request's camera)
// placed as that view (its eye, target and up dropped).
RequestView named_request_view(const RequestCamera& base, const std::string& name);
// A view's label: 1 to 32 of [A-Za-z0-9_-] (a file and ZIP entry name part).
// Throws Error(invalid_argument) naming `what`.
std::string checked_view_name(const std::string& name, const std::string& what);
// The labels of r.views, in order.
std::vector<std::string> view_names(const RenderRequest& r);
// Layout separate names a file per view: the labels must differ. Throws
// Error(invalid_argument) naming `what`.
void check_separate_views(const RenderRequest& r, const std::string& what);

// Throws Error(invalid_argument) naming the offending option (unknown keys too).
RenderRequest parse_render_options(const std::string& options_json);

// A point or vector option: finite, within +-kMaxCoordinate. Throws
// Error(invalid_argument) naming `what`. parse_point reads "x,y,z" (decimal numbers).
// 1e12 mm is a million km: beyond any part, and far enough from DBL_MAX that
// differences of two points stay finite.
constexpr double kMaxCoordinate = 1e12;
Vec3 checked_point(Vec3 p, const std::string& what);
Vec3 parse_point(const std::string& text, const std::string& what);

// The projection of the request: the one given; else orthographic where an
// orthographic height is given, perspective where a field of view or an eye is
// (a camera placed by hand); else orthographic: named views are the drawing's
// views (iso a true isometric), as CAD shows them.
Projection resolved_projection(const RequestCamera& r);

// The camera for a scene: the named view fitted to it, then explicit values.
// The cameras of a request: one per entry of `views`, else the one of `view`
// (camera_spec_for each).
std::vector<CameraSpec> camera_specs_for(const RenderRequest& r, const Scene& scene,
                                         const std::vector<uint8_t>& hidden_faces = {},
                                         const std::vector<Vec3>& face_offsets = {});
// Named views frame the faces shown where they are shown (render_options_for's
// hidden_faces left out, its face_offsets applied).
CameraSpec camera_spec_for(const RenderRequest& r, const Scene& scene, const std::vector<uint8_t>& hidden_faces = {},
                           const std::vector<Vec3>& face_offsets = {});
// Every camera check that needs no scene (up along the view direction, eye at
// the target, field of view, orthographic height), made by the renderer's own
// Camera on the view fitted to a unit box: usage errors found before any import,
// alike for the CLI, a render and a job's outputs. Throws Error(invalid_argument).
void check_camera_without_scene(const RenderRequest& r);
// The renderer's options of the request for `scene` (its tolerance in model
// units); threads, priority, progress and cancellation are the caller's.
RenderOptions render_options_for(const RenderRequest& r, const Scene& scene);

// Options for the conversions endpoint: {"format": "step" | "stp" | "iges" | "igs" |
// "stl" | "glb" | "json" | "brep" | "vrml" | "obj", "units": a length_unit_names() name
// or "source" (STEP/IGES only), "step_schema", "iges_mode", "deflection",
// "angular_deflection" (mesh outputs), "strict": boolean}; anything else is
// Error(invalid_argument).
struct ConversionRequest {
    ConversionFormat format = ConversionFormat::unknown;
    ConvertOptions options;
    bool strict = false;  // refuse a conversion with warnings (the CLI's --strict)
};
ConversionRequest parse_conversion_request(const std::string& options_json);
// The `units` value that names the default: the source's declared unit.
inline constexpr const char* kSourceUnits = "source";
// The request resolved, as JSON text: its format and every option the format
// takes with its default filled in (units "source", deflection 0.002, ...),
// so that parse_conversion_request reads it back to the same request.
std::string conversion_request_json(const ConversionRequest& r);
// A mesh output's angular deflection checked: radians in [kMinAngularDeflection,
// kMaxAngularDeflection] (the API's option, a job's, the CLI's
// --angular-deflection). Throws Error(invalid_argument) naming `what`.
double checked_angular_deflection(double radians, const std::string& what);
// Its format alone.
ConversionFormat parse_conversion_format(const std::string& options_json);

}  // namespace nurbsrt
