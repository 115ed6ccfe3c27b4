#include "options/render_request.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "core/error.h"
#include "options/query_values.h"

namespace nurbsrt {

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

Vec3 checked_point(Vec3 p, const std::string& what) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
        throw Error(ErrorCode::invalid_argument, what + " must be finite");
    if (std::abs(p.x) > kMaxCoordinate || std::abs(p.y) > kMaxCoordinate || std::abs(p.z) > kMaxCoordinate)
        throw Error(ErrorCode::invalid_argument, what + " has a coordinate beyond +-1e12 (model units, mm)");
    return p;
}

Vec3 parse_point(const std::string& text, const std::string& what) {
    const auto xyz = decimal_list(text, 3, 3);
    if (!xyz)
        throw Error(ErrorCode::invalid_argument,
                    what + " must be x,y,z: three decimal numbers (got '" + text.substr(0, 64) + "')");
    return checked_point({(*xyz)[0], (*xyz)[1], (*xyz)[2]}, what);
}

SectionPlane checked_section_plane(Vec3 point, Vec3 normal, const std::string& what) {
    SectionPlane plane;
    plane.point = checked_point(point, what + "'s point");
    checked_point(normal, what + "'s normal");
    const double len = length(normal);
    // A normal this short has no direction left to normalise (and 0 has none).
    if (!(len > 1e-12)) throw Error(ErrorCode::invalid_argument, what + "'s normal must not be zero");
    plane.normal = (1.0 / len) * normal;
    return plane;
}

SectionPlane parse_section_plane(const std::string& text, const std::string& what) {
    const auto v = decimal_list(text, 6, 6);
    if (!v)
        throw Error(ErrorCode::invalid_argument, what +
                                                     " must be px,py,pz,nx,ny,nz: a point and a normal, six decimal "
                                                     "numbers (got '" +
                                                     text.substr(0, 64) + "')");
    return checked_section_plane({(*v)[0], (*v)[1], (*v)[2]}, {(*v)[3], (*v)[4], (*v)[5]}, what);
}

void check_section_count(size_t planes, const std::string& what) {
    if (planes > kMaxSectionPlanes)
        throw Error(ErrorCode::invalid_argument, what + " holds " + std::to_string(planes) + " planes; at most " +
                                                     std::to_string(kMaxSectionPlanes) + " are allowed");
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
    options.ground = look.ground;
    options.ground_height = look.ground_height;
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

Projection resolved_projection(const RequestCamera& r) {
    if (r.projection) return *r.projection;
    if (r.ortho_height) return Projection::orthographic;
    if (r.fov_deg || r.eye) return Projection::perspective;
    return Projection::orthographic;
}

namespace {

CameraSpec base_spec(const RenderRequest& r, const RequestCamera& c) {
    CameraSpec base;
    base.width = r.width;
    base.height = r.height;
    base.projection = resolved_projection(c);
    if (c.fov_deg) base.fov_deg = *c.fov_deg;
    return base;
}

ViewRequest view_request(const RequestCamera& c) {
    return {.view = c.view,
            .eye = c.eye,
            .target = c.target,
            .up = c.up,
            .ortho_height = c.ortho_height,
            .fit_margin = c.fit_margin};
}

}  // namespace

void check_camera_without_scene(const RenderRequest& r) {
    BBox unit;
    unit.extend(Vec3{-1, -1, -1});
    unit.extend(Vec3{1, 1, 1});
    const Camera checked(fitted_camera(view_request(r), unit, base_spec(r, r)));
    for (const RequestView& v : r.views) {
        const Camera checked_view(fitted_camera(view_request(v.camera), unit, base_spec(r, v.camera)));
        (void)checked_view;
    }
    (void)checked;
}

CameraSpec camera_spec_for(const RenderRequest& r, const Scene& scene, const std::vector<uint8_t>& hidden_faces,
                           const std::vector<Vec3>& face_offsets) {
    return fitted_camera(view_request(r), scene, base_spec(r, r), hidden_faces, face_offsets);
}

std::vector<CameraSpec> camera_specs_for(const RenderRequest& r, const Scene& scene,
                                         const std::vector<uint8_t>& hidden_faces,
                                         const std::vector<Vec3>& face_offsets) {
    if (r.views.empty()) return {camera_spec_for(r, scene, hidden_faces, face_offsets)};
    std::vector<CameraSpec> specs;
    for (const RequestView& v : r.views)
        specs.push_back(
            fitted_camera(view_request(v.camera), scene, base_spec(r, v.camera), hidden_faces, face_offsets));
    return specs;
}

const char* view_layout_name(ViewLayout l) { return l == ViewLayout::separate ? "separate" : "sheet"; }

std::optional<ViewLayout> parse_view_layout(std::string_view name) {
    for (ViewLayout l : {ViewLayout::sheet, ViewLayout::separate})
        if (name == view_layout_name(l)) return l;
    return std::nullopt;
}

double checked_explode(double factor, const std::string& what) {
    if (!(factor >= 0 && factor <= kMaxExplode))
        throw Error(ErrorCode::invalid_argument, what + " must be from 0 (none) to 10 times the assembly's size");
    return factor;
}

std::vector<std::string> checked_views(const std::vector<std::string>& names, const std::string& what) {
    if (names.empty() || names.size() > kMaxViews)
        throw Error(ErrorCode::invalid_argument, what + " must name 1 to " + std::to_string(kMaxViews) +
                                                     " views (got " + std::to_string(names.size()) + ")");
    for (const std::string& n : names)
        if (!is_named_view(n))
            throw Error(ErrorCode::invalid_argument, what + " names an unknown view '" + n.substr(0, 64) +
                                                         "' (iso, front, back, left, right, top, bottom)");
    return names;
}

std::vector<std::string> parse_views(const std::string& text, const std::string& what) {
    return checked_views(split_list(text, ','), what);
}

RequestView named_request_view(const RequestCamera& base, const std::string& name) {
    RequestView v{name, base};
    v.camera.view = name;
    v.camera.eye = v.camera.target = v.camera.up = std::nullopt;
    return v;
}

std::string checked_view_name(const std::string& name, const std::string& what) {
    // Names a file (part-NAME.png) and a ZIP entry: no path separators, dots or spaces.
    constexpr size_t kMaxViewName = 32;
    bool ok = !name.empty() && name.size() <= kMaxViewName;
    for (const char c : name)
        ok = ok && ((c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-');
    if (!ok) throw Error(ErrorCode::invalid_argument, what + " must be 1 to 32 of A-Z a-z 0-9 _ -");
    return name;
}

std::vector<std::string> view_names(const RenderRequest& r) {
    std::vector<std::string> names;
    for (const RequestView& v : r.views) names.push_back(v.name);
    return names;
}

void check_separate_views(const RenderRequest& r, const std::string& what) {
    if (r.layout != ViewLayout::separate) return;
    if (r.views.empty())
        throw Error(ErrorCode::invalid_argument,
                    what + " separate makes an image per view of 'views', which is not given");
    const std::vector<std::string> names = view_names(r);
    for (size_t i = 0; i < names.size(); ++i)
        for (size_t j = 0; j < i; ++j)
            if (names[i] == names[j])
                throw Error(ErrorCode::invalid_argument, what + " separate names a file per view, and two views are '" +
                                                             names[i] + "' (give each camera view a distinct name)");
}

RenderOptions render_options_for(const RenderRequest& r, const Scene& scene) {
    RenderOptions options;
    options.method = r.method;
    options.map_precision = r.map_precision;
    apply_background(r.background.value_or(default_background(r.format.kind)), options);
    apply_look(r.look, r.format.kind, options);
    options.sections = r.sections;
    // Exploded and moved parts move in the frame, not in the scene
    // (face_offsets): one prepared scene serves every factor and move.
    options.face_offsets = explode_offsets(scene, r.explode, r.explode_level);
    apply_part_selection(r.parts, scene, options);
    options.newton.eps = default_newton_eps(moved_bbox(scene, options.face_offsets), r.tolerance);
    return options;
}

}  // namespace nurbsrt
