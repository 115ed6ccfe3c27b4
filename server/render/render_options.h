// The options of POST /v1/renders, from the JSON `options` part or query
// parameters (values as strings), validated: width, height, view or camera,
// method, map precision, output format, background, anti-aliasing, feature lines.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "importer/importer.h"
#include "renderer/camera.h"
#include "renderer/render.h"
#include "server/common/config.h"

namespace nurbsrt::server {

// The image formats, decided once from the API's `format` or the CLI's file
// extension; `other`: a file extension the CLI hands to OpenImageIO as it is.
enum class ImageFormat : uint8_t { png, jpeg, tiff, exr, other };
// By extension, with or without its dot, any case: png, jpg/jpeg, tif/tiff, exr.
ImageFormat image_format_of_extension(std::string extension);

struct OutputFormat {
    ImageFormat kind = ImageFormat::png;
    std::string name;          // png, jpeg, tiff, exr
    std::string extension;     // .png, .jpg, .tif, .exr
    std::string content_type;  // image/png, ...
};
// The API's output format of each kind (not `other`).
OutputFormat output_format(ImageFormat kind);

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

struct RenderRequest {
    int width = kDefaultWidth, height = kDefaultHeight;
    std::string view = "iso";
    Projection projection = Projection::perspective;
    std::optional<double> fov_deg, ortho_height;
    std::optional<Vec3> eye, target, up;
    double fit_margin = kDefaultFitMargin;  // of the frame, each side (named views, and an eye alone)
    NewtonMethod method = NewtonMethod::proposed;
    MapPrecision map_precision = MapPrecision::float32;
    OutputFormat format = output_format(ImageFormat::png);
    std::optional<Background> background;  // unset: default_background(format)
    unsigned aovs = 0;                     // aov_bit() of each AOV asked for
    ImageLook look;
};

// Throws Error(invalid_argument) naming the offending option (unknown keys too).
RenderRequest parse_render_options(const std::string& options_json);

// Throws Error(limit_exceeded) when the image is over the configured size limits.
void check_render_limits(const ServerConfig& config, const RenderRequest& r);

// The camera for a scene: the named view fitted to it, then explicit values.
CameraSpec camera_spec_for(const RenderRequest& r, const Scene& scene);

// Options for the conversions endpoint: {"format": "step" | "stp" | "iges" | "igs" |
// "stl" | "glb" | "json"}; anything else is Error(invalid_argument).
ConversionFormat parse_conversion_format(const std::string& options_json);

}  // namespace nurbsrt::server
