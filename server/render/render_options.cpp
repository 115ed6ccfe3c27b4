#include "server/render/render_options.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <set>
#include <utility>
#include <vector>

#include "core/error.h"
#include "core/json_limits.h"
#include "server/http/query_values.h"

namespace nurbsrt::server {
namespace {

using nlohmann::json;

[[noreturn]] void bad(const std::string& what) { throw Error(ErrorCode::invalid_argument, what); }

// Options take JSON types only: query parameters and form fields were typed
// at the edge by the option they set (server/http/query_values.h).
double number(const json& v, const std::string& key) {
    if (v.is_number()) return v.get<double>();
    bad("option '" + key + "' must be a number");
}

int integer(const json& v, const std::string& key) {
    if (!v.is_number_integer()) bad("option '" + key + "' must be an integer");
    const auto n = v.get<long long>();
    if (n < -2147483648LL || n > 2147483647LL) bad("option '" + key + "' must be an integer");
    return static_cast<int>(n);
}

std::string text(const json& v, const std::string& key) {
    if (!v.is_string()) bad("option '" + key + "' must be a string");
    return v.get<std::string>();
}

bool boolean(const json& v, const std::string& key) {
    if (v.is_boolean()) return v.get<bool>();
    bad("option '" + key + "' must be true or false");
}

// An array of numbers (3, or max_size) as the "r,g,b[,a]" text the shared
// parsers read, so arrays and strings are checked alike.
std::string background_text(const json& v, const std::string& key, size_t max_size) {
    const std::string what = "option '" + key + "'";
    const std::string sizes = max_size == 3 ? "3" : "3 or 4";
    if (!v.is_array() || v.size() < 3 || v.size() > max_size)
        bad(what + " must be an array of " + sizes + " numbers, or a string");
    std::string text;
    for (const json& x : v) {
        if (!x.is_number()) bad(what + " must be an array of " + sizes + " numbers, or a string");
        char buf[40];
        std::snprintf(buf, sizeof buf, "%s%.17g", text.empty() ? "" : ",", x.get<double>());
        text += buf;
    }
    return text;
}

// A background as a string ("1,1,1", "transparent": query parameters) or an
// array of 3 (opaque) or 4 numbers.
Background background(const json& v, const std::string& key) {
    const std::string what = "option '" + key + "'";
    if (v.is_string()) return parse_background(v.get<std::string>(), what);
    return parse_background(background_text(v, key, 4), what);
}

Vec3 vec3(const json& v, const std::string& key) {
    Vec3 r;
    if (v.is_array() && v.size() == 3 && v[0].is_number() && v[1].is_number() && v[2].is_number()) {
        r = {v[0].get<double>(), v[1].get<double>(), v[2].get<double>()};
    } else if (v.is_string()) {
        // "x,y,z" (query parameters): three decimal numbers, nothing else.
        const auto xyz = decimal_list(v.get<std::string>(), 3, 3);
        if (!xyz) bad("option '" + key + "' must be x,y,z (three decimal numbers)");
        r = {(*xyz)[0], (*xyz)[1], (*xyz)[2]};
    } else {
        bad("option '" + key + "' must be an array of 3 numbers");
    }
    if (!std::isfinite(r.x) || !std::isfinite(r.y) || !std::isfinite(r.z)) bad("option '" + key + "' must be finite");
    // 1e12 mm is a million km: beyond any part, and far enough from DBL_MAX that
    // differences of two points stay finite (1e308 overflowed into "must differ").
    constexpr double kMaxCoordinate = 1e12;
    if (std::abs(r.x) > kMaxCoordinate || std::abs(r.y) > kMaxCoordinate || std::abs(r.z) > kMaxCoordinate)
        bad("option '" + key + "' has a coordinate beyond +-1e12 (model units, mm)");
    return r;
}

std::string one_of(const json& v, const std::string& key, const std::set<std::string>& allowed) {
    const std::string s = text(v, key);
    if (!allowed.count(s)) {
        std::string list;
        for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
        bad("option '" + key + "' must be one of: " + list);
    }
    return s;
}

// "aovs": ["z", "face", ...] or, as a query parameter, "z,face,...".
unsigned aov_bits(const json& v, const std::string& key) {
    std::vector<std::string> names;
    if (v.is_string()) {
        std::string s = v.get<std::string>();
        for (size_t start = 0; start <= s.size();) {
            const size_t comma = std::min(s.find(',', start), s.size());
            names.push_back(s.substr(start, comma - start));
            start = comma + 1;
        }
    } else if (v.is_array()) {
        for (const json& x : v) names.push_back(text(x, key));
    } else {
        bad("option '" + key + "' must be an array of AOV names");
    }
    unsigned bits = 0;
    for (const std::string& name : names) {
        bool known = false;
        for (Aov a : kAllAovs)
            if (name == aov_name(a)) bits |= aov_bit(a), known = true;
        if (!known)
            bad("option '" + key + "' names an unknown AOV '" + name.substr(0, 64) +
                "' (z, face, normal, uv, iterations)");
    }
    return bits;
}

// The option names, for messages that list them (kept in step with the parsers below).
constexpr const char* kCameraOptions = "view, eye, target, up, projection, fov_deg, ortho_height, fit_margin";
constexpr const char* kRenderOptions =
    "width, height, format, background, antialias, edges, edge_color, edge_width, shadows, method, map_precision, "
    "aovs, camera, view, eye, target, up, projection, fov_deg, ortho_height, fit_margin";

// Sets the camera field `key`; false when no camera field has that name.
bool camera_field(RenderRequest& r, const std::string& key, const json& v) {
    if (key == "eye")
        r.eye = vec3(v, key);
    else if (key == "target")
        r.target = vec3(v, key);
    else if (key == "up")
        r.up = vec3(v, key);
    else if (key == "projection")
        r.projection = one_of(v, key, {"perspective", "orthographic"}) == "orthographic" ? Projection::orthographic
                                                                                         : Projection::perspective;
    else if (key == "fov_deg") {
        const double f = number(v, key);
        if (!(f > 0 && f < 180)) bad("option 'fov_deg' must be in (0, 180)");
        r.fov_deg = f;
    } else if (key == "ortho_height") {
        const double h = number(v, key);
        if (!(h > 0)) bad("option 'ortho_height' must be positive");
        r.ortho_height = h;
        r.projection = Projection::orthographic;
    } else if (key == "fit_margin") {
        const double m = number(v, key);
        if (!(m >= 0 && m <= kMaxFitMargin)) bad("option 'fit_margin' must be in [0, 0.45]");
        r.fit_margin = m;
    } else if (key == "view") {
        r.view = one_of(v, key, {"iso", "front", "back", "left", "right", "top", "bottom"});
    } else {
        return false;
    }
    return true;
}

// The name as the client sent it, bounded (a message must not echo megabytes).
// (Appended piecewise: "'" + std::string + "'" trips GCC 12's -Wrestrict false
// positive, GCC bug 105329.)
std::string quoted_name(const std::string& key) {
    std::string q(1, '\'');
    q.append(key, 0, 64);
    q += '\'';
    return q;
}

json parse_object(const std::string& options_json) {
    const json o = parse_json_or_throw(options_json, kRequestJsonLimits, "the options");
    if (!o.is_object()) bad("options must be a JSON object");
    return o;
}

CameraSpec base_spec(const RenderRequest& r) {
    CameraSpec base;
    base.width = r.width;
    base.height = r.height;
    base.projection = r.projection;
    if (r.fov_deg) base.fov_deg = *r.fov_deg;
    return base;
}

ViewRequest view_request(const RenderRequest& r) {
    ViewRequest v;
    v.view = r.view;
    v.eye = r.eye;
    v.target = r.target;
    v.up = r.up;
    v.ortho_height = r.ortho_height;
    v.fit_margin = r.fit_margin;
    return v;
}

// Every camera check that needs no scene (up along the view direction, eye at
// the target, field of view, orthographic height), made by the renderer's own
// Camera on the view fitted to a unit box: a job's options are refused before
// 202 exactly as /v1/renders would refuse them later.
void check_camera_without_scene(const RenderRequest& r) {
    BBox unit;
    unit.extend(Vec3{-1, -1, -1});
    unit.extend(Vec3{1, 1, 1});
    const Camera checked(fitted_camera(view_request(r), unit, base_spec(r)));
    (void)checked;
}

}  // namespace

RenderRequest parse_render_options(const std::string& options_json) {
    const json o = parse_object(options_json);
    RenderRequest r;
    std::optional<int> width, height;
    for (const auto& [key, v] : o.items()) {
        if (v.is_null()) continue;  // null: the option's default, as if it were absent
        if (key == "width" || key == "height") {
            const int n = integer(v, key);
            if (n < 1) bad("option '" + key + "' must be at least 1");
            (key == "width" ? width : height) = n;
        } else if (key == "method") {
            r.method = *parse_newton_method(one_of(v, key, {"proposed", "martin"}));
        } else if (key == "map_precision") {
            r.map_precision = *parse_map_precision(one_of(v, key, {"float", "rgb8"}));
        } else if (key == "format") {
            r.format =
                output_format(image_format_of_extension(one_of(v, key, {"png", "jpeg", "jpg", "tiff", "tif", "exr"})));
        } else if (key == "background") {
            r.background = background(v, key);
        } else if (key == "aovs") {
            r.aovs = aov_bits(v, key);
        } else if (key == "antialias") {
            r.look.antialias = parse_antialias(number(v, key), "option '" + key + "'");
        } else if (key == "edges") {
            r.look.edges = boolean(v, key);
        } else if (key == "edge_color") {
            r.look.edge_color = v.is_string() ? parse_rgb(v.get<std::string>(), "option '" + key + "'")
                                              : parse_rgb(background_text(v, key, 3), "option '" + key + "'");
        } else if (key == "edge_width") {
            r.look.edge_width = parse_edge_width(number(v, key), "option '" + key + "'");
        } else if (key == "shadows") {
            r.look.shadows = boolean(v, key);
        } else if (key == "camera") {
            if (!v.is_object()) bad("option 'camera' must be an object");
            for (const auto& [ck, cv] : v.items())
                if (!cv.is_null() && !camera_field(r, ck, cv))
                    bad("unknown option " + quoted_name(ck) + " in 'camera' (camera options: " + kCameraOptions + ")");
        } else if (!camera_field(r, key, v)) {
            // Flat camera fields (query parameters) were tried last.
            bad("unknown option " + quoted_name(key) + " (render options: " + kRenderOptions + ")");
        }
    }
    complete_size(width, height, r.width, r.height);
    check_camera_without_scene(r);
    return r;
}

const char* aov_name(Aov a) {
    switch (a) {
        case Aov::z:
            return "z";
        case Aov::face:
            return "face";
        case Aov::normal:
            return "normal";
        case Aov::uv:
            return "uv";
        case Aov::iterations:
            break;
    }
    return "iterations";
}

Background parse_background(const std::string& s, const std::string& what) {
    if (s == "transparent") return {};
    auto given = decimal_list(s, 3, 4);
    if (!given)
        throw Error(ErrorCode::invalid_argument,
                    what + " must be r,g,b or r,g,b,a in [0,1], or transparent (got '" + s.substr(0, 64) + "')");
    std::vector<double>& c = *given;
    if (c.size() == 3) c.push_back(1);  // opaque
    for (double x : c)
        if (!(x >= 0 && x <= 1))
            throw Error(ErrorCode::invalid_argument,
                        what + " has a component outside [0, 1] (got '" + s.substr(0, 64) + "')");
    return {{c[0], c[1], c[2]}, c[3]};
}

ImageFormat image_format_of_extension(std::string ext) {
    if (!ext.empty() && ext[0] == '.') ext.erase(0, 1);
    for (char& ch : ext) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    if (ext == "png") return ImageFormat::png;
    if (ext == "jpg" || ext == "jpeg") return ImageFormat::jpeg;
    if (ext == "tif" || ext == "tiff") return ImageFormat::tiff;
    if (ext == "exr") return ImageFormat::exr;
    return ImageFormat::other;
}

OutputFormat output_format(ImageFormat kind) {
    switch (kind) {
        case ImageFormat::jpeg:
            return {kind, "jpeg", ".jpg", "image/jpeg"};
        case ImageFormat::tiff:
            return {kind, "tiff", ".tif", "image/tiff"};
        case ImageFormat::exr:
            return {kind, "exr", ".exr", "image/x-exr"};
        default:
            return {ImageFormat::png, "png", ".png", "image/png"};
    }
}

int default_antialias(ImageFormat format) {
    return format == ImageFormat::png || format == ImageFormat::jpeg ? kDefaultAntialias : 0;
}

int parse_antialias(double n, const std::string& what) {
    if (!(n >= 0 && n <= kMaxAntialias) || n != std::floor(n))
        throw Error(ErrorCode::invalid_argument, what + " must be an integer from 0 (off) to " +
                                                     std::to_string(kMaxAntialias) + " extra rays per edge pixel");
    return static_cast<int>(n);
}

double parse_edge_width(double w, const std::string& what) {
    if (!(w >= kMinEdgeWidth && w <= kMaxEdgeWidth)) {
        char msg[64];
        std::snprintf(msg, sizeof msg, " must be from %g to %g pixels", kMinEdgeWidth, kMaxEdgeWidth);
        throw Error(ErrorCode::invalid_argument, what + msg);
    }
    return w;
}

Color parse_rgb(const std::string& s, const std::string& what) {
    const auto c = decimal_list(s, 3, 3);
    if (!c) throw Error(ErrorCode::invalid_argument, what + " must be r,g,b in [0,1] (got '" + s.substr(0, 64) + "')");
    for (double x : *c)
        if (!(x >= 0 && x <= 1))
            throw Error(ErrorCode::invalid_argument,
                        what + " has a component outside [0, 1] (got '" + s.substr(0, 64) + "')");
    return {static_cast<float>((*c)[0]), static_cast<float>((*c)[1]), static_cast<float>((*c)[2])};
}

void apply_background(const Background& bg, RenderOptions& options) {
    options.background = {static_cast<float>(bg.rgb.x), static_cast<float>(bg.rgb.y), static_cast<float>(bg.rgb.z)};
    options.background_alpha = static_cast<float>(bg.alpha);
}

void apply_look(const ImageLook& look, ImageFormat format, RenderOptions& options) {
    options.antialias = look.antialias.value_or(default_antialias(format));
    options.edges = look.edges;
    options.edge_color = look.edge_color;
    options.edge_width = static_cast<float>(look.edge_width);
    options.shadows = look.shadows;
}

Background default_background(ImageFormat format) {
    if (format == ImageFormat::jpeg) return {{1, 1, 1}, 1};
    return {};
}

void complete_size(std::optional<int> width, std::optional<int> height, int& out_width, int& out_height) {
    const auto keep_aspect = [](int given, int from, int to) {
        return std::max(1, static_cast<int>(std::lround(double(given) * to / from)));
    };
    out_width = width ? *width : height ? keep_aspect(*height, kDefaultHeight, kDefaultWidth) : kDefaultWidth;
    out_height = height ? *height : width ? keep_aspect(*width, kDefaultWidth, kDefaultHeight) : kDefaultHeight;
}

void check_render_limits(const ServerConfig& c, const RenderRequest& r) {
    for (const auto& [name, value] : {std::pair{"width", r.width}, std::pair{"height", r.height}})
        if (value > c.max_dimension)
            throw Error(ErrorCode::limit_exceeded, std::string("option '") + name + "' is " + std::to_string(value) +
                                                       ", over the limit of " + std::to_string(c.max_dimension) +
                                                       " pixels per side");
    const long long pixels = static_cast<long long>(r.width) * r.height;
    if (pixels > c.max_pixels)
        throw Error(ErrorCode::limit_exceeded, "options 'width' x 'height' give " + std::to_string(r.width) + "x" +
                                                   std::to_string(r.height) + " = " + std::to_string(pixels) +
                                                   " pixels, over the limit of " + std::to_string(c.max_pixels));
}

CameraSpec camera_spec_for(const RenderRequest& r, const Scene& scene) {
    return fitted_camera(view_request(r), scene, base_spec(r));
}

ConversionFormat parse_conversion_format(const std::string& options_json) {
    const json o = parse_object(options_json);
    std::string format;
    for (const auto& [key, v] : o.items()) {
        if (key != "format") bad("unknown option " + quoted_name(key) + " (a conversion takes only 'format')");
        format = text(v, key);
    }
    if (format.empty()) bad("option 'format' is required (step, iges, stl, glb or json)");
    const ConversionFormat f = conversion_format_from_name(format);
    if (f == ConversionFormat::unknown) bad("option 'format' must be step, iges, stl, glb or json");
    return f;
}

}  // namespace nurbsrt::server
