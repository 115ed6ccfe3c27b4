// The options of POST /v1/renders, from the JSON `options` part or query
// parameters (values as strings), validated: width, height, view or camera,
// method, map precision, output format, background.
#pragma once

#include <optional>
#include <string>

#include "importer/importer.h"
#include "renderer/camera.h"
#include "renderer/render.h"
#include "server/config.h"

namespace nurbsrt::server {

struct OutputFormat {
    std::string name;          // png, jpeg, tiff, exr
    std::string extension;     // .png, .jpg, .tif, .exr
    std::string content_type;  // image/png, ...
};

struct RenderRequest {
    int width = 800, height = 600;
    std::string view = "iso";
    Projection projection = Projection::perspective;
    std::optional<double> fov_deg, ortho_height;
    std::optional<Vec3> eye, target, up;
    std::string method = "proposed";         // proposed | martin
    std::string map_precision = "float";     // float | rgb8
    OutputFormat format{"png", ".png", "image/png"};
    std::optional<Vec3> background;
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
