// The JSON (and query-parameter) form of the request model: POST /v1/renders'
// `options`, a job output's options and the conversions' format, parsed once
// into RenderRequest and ConversionFormat (render_request.h).
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/json_limits.h"
#include "options/query_values.h"
#include "options/render_request.h"

namespace nurbsrt {
namespace {

using nlohmann::json;

[[noreturn]] void bad(const std::string& what) { throw Error(ErrorCode::invalid_argument, what); }

// Options take JSON types only: query parameters and form fields were typed
// at the edge by the option they set (options/query_values.h).
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
    const std::string what = "option '" + key + "'";
    if (v.is_string()) return parse_point(v.get<std::string>(), what);  // "x,y,z" (query parameters)
    if (!(v.is_array() && v.size() == 3 && v[0].is_number() && v[1].is_number() && v[2].is_number()))
        bad(what + " must be an array of 3 numbers");
    return checked_point({v[0].get<double>(), v[1].get<double>(), v[2].get<double>()}, what);
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
        names = split_list(v.get<std::string>(), ',');
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
constexpr const char* kConversionOptions =
    "format, units, step_schema, iges_mode, deflection, angular_deflection, strict";
constexpr const char* kCameraOptions = "view, eye, target, up, projection, fov_deg, ortho_height, fit_margin";
constexpr const char* kRenderOptions =
    "width, height, format, background, antialias, edges, edge_color, edge_width, shadows, method, map_precision, "
    "aovs, camera, view, eye, target, up, projection, fov_deg, ortho_height, fit_margin, sections, section_mode, "
    "section_caps, section_hatch, parts, ground, ground_height, views, layout, explode, explode_level";

// Sets the camera field `key`; false when no camera field has that name.
// Messages name the field as `name` (the key, or views[2].eye).
bool camera_field(RequestCamera& r, const std::string& key, const json& v, const std::string& name) {
    if (key == "eye")
        r.eye = vec3(v, name);
    else if (key == "target")
        r.target = vec3(v, name);
    else if (key == "up")
        r.up = vec3(v, name);
    else if (key == "projection")
        r.projection = one_of(v, name, {"perspective", "orthographic"}) == "orthographic" ? Projection::orthographic
                                                                                          : Projection::perspective;
    else if (key == "fov_deg") {
        const double f = number(v, name);
        if (!(f > 0 && f < 180)) bad("option '" + name + "' must be in (0, 180)");
        r.fov_deg = f;
    } else if (key == "ortho_height") {
        const double h = number(v, name);
        if (!(h > 0)) bad("option '" + name + "' must be positive");
        r.ortho_height = h;
    } else if (key == "fit_margin") {
        const double m = number(v, name);
        if (!(m >= 0 && m <= kMaxFitMargin)) bad("option '" + name + "' must be in [0, 0.45]");
        r.fit_margin = m;
    } else if (key == "view") {
        r.view = one_of(v, name, {"iso", "front", "back", "left", "right", "top", "bottom"});
    } else {
        return false;
    }
    return true;
}
bool camera_field(RequestCamera& r, const std::string& key, const json& v) { return camera_field(r, key, v, key); }

// The name as the client sent it, bounded (a message must not echo megabytes).
// (Appended piecewise: "'" + std::string + "'" trips GCC 12's -Wrestrict false
// positive, GCC bug 105329.)
std::string quoted_name(const std::string& key) {
    std::string q(1, '\'');
    q.append(key, 0, 64);
    q += '\'';
    return q;
}

// One element of `views` (index k): a named view, or an object with a camera
// of its own (camera fields, and an optional `name`) over the request's.
RequestView request_view(const RequestCamera& base, const json& e, size_t k) {
    const std::string where = "views[" + std::to_string(k) + "]";
    if (e.is_string())
        return named_request_view(base, checked_views({e.get<std::string>()}, "option '" + where + "'")[0]);
    if (!e.is_object()) bad("option '" + where + "' must be a view name or an object with a camera");
    RequestView v{"", base};
    // A view or an eye places this camera anew: the request's placement does not carry over.
    if (e.contains("view") || e.contains("eye")) v.camera.eye = v.camera.target = v.camera.up = std::nullopt;
    for (const auto& [key, value] : e.items()) {
        if (key == "name")
            v.name = checked_view_name(text(value, where + ".name"), "option '" + where + ".name'");
        else if (!camera_field(v.camera, key, value, where + "." + key))
            bad("unknown option " + quoted_name(key) + " in '" + where + "' (name, " + kCameraOptions + ")");
    }
    if (v.name.empty())
        v.name = e.contains("view") && !e.contains("eye") ? v.camera.view : "view" + std::to_string(k + 1);
    return v;
}

// `views`: "front,top" (a query parameter), or an array of names and cameras.
std::vector<RequestView> request_views(const RequestCamera& base, const json& v) {
    std::vector<RequestView> views;
    if (v.is_string()) {
        for (const std::string& name : parse_views(v.get<std::string>(), "option 'views'"))
            views.push_back(named_request_view(base, name));
        return views;
    }
    if (!v.is_array() || v.empty() || v.size() > kMaxViews)
        bad("option 'views' must be an array of 1 to " + std::to_string(kMaxViews) + " view names or cameras");
    for (size_t k = 0; k < v.size(); ++k) views.push_back(request_view(base, v[k], k));
    return views;
}

// "sections": [{"point": [x, y, z], "normal": [x, y, z]}, ...] or, as a
// query parameter, "px,py,pz,nx,ny,nz;..." (planes separated by semicolons).
std::vector<SectionPlane> section_planes(const json& v, const std::string& key) {
    std::vector<SectionPlane> planes;
    const std::string what = "option '" + key + "'";
    if (v.is_string()) {
        const std::vector<std::string> texts = split_list(v.get<std::string>(), ';');
        check_section_count(texts.size(), what);
        for (size_t k = 0; k < texts.size(); ++k)
            planes.push_back(parse_section_plane(texts[k], what + " plane " + std::to_string(k)));
        return planes;
    }
    if (!v.is_array()) bad(what + " must be an array of planes {\"point\": [x,y,z], \"normal\": [x,y,z]}");
    check_section_count(v.size(), what);
    for (size_t k = 0; k < v.size(); ++k) {
        const std::string where = key + "[" + std::to_string(k) + "]";
        const json& p = v[k];
        if (!p.is_object() || !p.contains("point") || !p.contains("normal"))
            bad("option '" + where + "' must be an object with a point and a normal");
        for (const auto& [pk, pv] : p.items())
            if (pk != "point" && pk != "normal")
                bad("unknown option " + quoted_name(pk) + " in '" + where + "' (a plane has point and normal)");
        planes.push_back(checked_section_plane(vec3(p.at("point"), where + ".point"),
                                               vec3(p.at("normal"), where + ".normal"), "option '" + where + "'"));
    }
    return planes;
}

// "parts": {"hide": [pattern, ...], "only": [...], "color": {pattern: "r,g,b" or
// [r, g, b]}, "move": {pattern: [dx, dy, dz] or "dx,dy,dz"}}; as a query
// parameter, that object as JSON text.
PartSelection part_selection(const json& given, const std::string& key) {
    const json v =
        given.is_string() ? parse_json_or_throw(given.get<std::string>(), kRequestJsonLimits, "option 'parts'") : given;
    if (!v.is_object()) bad("option '" + key + "' must be an object with hide, only, ghost, color and move");
    PartSelection sel;
    for (const auto& [k, list] : v.items()) {
        const std::string where = key + "." + k;
        if (k == "hide" || k == "only" || k == "ghost") {
            if (!list.is_array()) bad("option '" + where + "' must be an array of part ids or name globs");
            if (list.size() > kMaxPartPatterns)
                bad("option '" + where + "' holds more than " + std::to_string(kMaxPartPatterns) + " patterns");
            std::vector<std::string>& out = k == "hide" ? sel.hide : k == "only" ? sel.only : sel.ghost;
            for (size_t n = 0; n < list.size(); ++n) {
                const std::string what = "option '" + where + "[" + std::to_string(n) + "]'";
                if (!list[n].is_string()) bad(what + " must be a string");
                check_part_pattern(list[n].get<std::string>(), what);
                out.push_back(list[n].get<std::string>());
            }
        } else if (k == "color") {
            if (!list.is_object()) bad("option '" + where + "' must be an object {part id or name glob: colour}");
            if (list.size() > kMaxPartPatterns)
                bad("option '" + where + "' holds more than " + std::to_string(kMaxPartPatterns) + " patterns");
            for (const auto& [pattern, c] : list.items()) {
                const std::string what = "option '" + where + "'";
                check_part_pattern(pattern, what + " key");
                sel.color.emplace_back(pattern, c.is_string() ? parse_rgb(c.get<std::string>(), what)
                                                              : parse_rgb(background_text(c, where, 3), what));
            }
        } else if (k == "move") {
            if (!list.is_object()) bad("option '" + where + "' must be an object {part id or name glob: [dx, dy, dz]}");
            if (list.size() > kMaxPartPatterns)
                bad("option '" + where + "' holds more than " + std::to_string(kMaxPartPatterns) + " patterns");
            for (const auto& [pattern, t] : list.items()) {
                check_part_pattern(pattern, "option '" + where + "' key");
                sel.move.emplace_back(pattern, vec3(t, where + "." + pattern.substr(0, 64)));
            }
        } else {
            bad("unknown option " + quoted_name(k) + " in '" + key +
                "' (parts options: hide, only, ghost, color, move)");
        }
    }
    return sel;
}

json parse_object(const std::string& options_json) {
    const json o = parse_json_or_throw(options_json, kRequestJsonLimits, "the options");
    if (!o.is_object()) bad("options must be a JSON object");
    return o;
}

}  // namespace

RenderRequest parse_render_options(const std::string& options_json) {
    const json o = parse_object(options_json);
    RenderRequest r;
    std::optional<int> width, height;
    const json* views = nullptr;
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
            r.format_given = true;
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
        } else if (key == "ground") {
            r.look.ground = boolean(v, key);
        } else if (key == "ground_height") {
            r.look.ground_height = checked_point({number(v, key), 0, 0}, "option '" + key + "'").x;
        } else if (key == "sections") {
            r.sections.planes = section_planes(v, key);
        } else if (key == "section_mode") {
            r.sections.mode = *parse_section_mode(one_of(v, key, {"union", "cutaway"}));
        } else if (key == "section_caps") {
            r.sections.caps = boolean(v, key);
        } else if (key == "section_hatch") {
            r.sections.hatch = boolean(v, key);
        } else if (key == "parts") {
            r.parts = part_selection(v, key);
        } else if (key == "explode") {
            r.explode = checked_explode(number(v, key), "option '" + key + "'");
        } else if (key == "explode_level") {
            r.explode_level = *parse_explode_level(one_of(v, key, {"top", "leaves"}));
        } else if (key == "views") {
            views = &v;  // over the request's camera, known once every field is read
        } else if (key == "layout") {
            r.layout = *parse_view_layout(one_of(v, key, {"sheet", "separate"}));
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
    if (views) r.views = request_views(r, *views);
    check_separate_views(r, "option 'layout'");
    complete_size(width, height, r.width, r.height);
    check_camera_without_scene(r);
    return r;
}

namespace {

// `value` as one of an option's enum values by `from_name`, or a usage error
// listing `names`.
template <typename E, typename FromName>
E conversion_enum(const std::string& key, const std::string& value, FromName from_name,
                  const std::vector<std::string>& names) {
    if (const std::optional<E> e = from_name(value)) return *e;
    std::string list;
    for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
    bad("option '" + key + "' must be one of " + list);
}

}  // namespace

ConversionRequest parse_conversion_request(const std::string& options_json) {
    const json o = parse_object(options_json);
    std::string format, units, schema, mode;
    std::optional<double> deflection, angular_deflection;
    bool strict = false;
    for (const auto& [key, v] : o.items()) {
        if (key == "format")
            format = text(v, key);
        else if (key == "units")
            units = text(v, key);
        else if (key == "step_schema")
            schema = text(v, key);
        else if (key == "iges_mode")
            mode = text(v, key);
        else if (key == "deflection")
            deflection = number(v, key);
        else if (key == "angular_deflection")
            angular_deflection = number(v, key);
        else if (key == "strict")
            strict = boolean(v, key);
        else
            bad("unknown option " + quoted_name(key) + " (a conversion takes " + kConversionOptions + ")");
    }
    const std::string formats = conversion_format_names();
    if (format.empty()) bad("option 'format' is required (" + formats + ")");
    ConversionRequest r;
    r.strict = strict;
    r.format = conversion_format_from_name(format);
    if (r.format == ConversionFormat::unknown) bad("option 'format' must be one of " + formats);
    // An option the format does not take is refused, never ignored (which
    // applies where: the formats' table, conversion_option_refusal).
    auto only_for = [&](const std::string& value, ConversionOption option) {
        if (value.empty()) return;
        if (const std::string why = conversion_option_refusal(option, r.format); !why.empty())
            bad(std::string("option '") + conversion_option_name(option) + "' " + why + ", not " + format);
    };
    only_for(units, ConversionOption::units);
    only_for(schema, ConversionOption::step_schema);
    only_for(mode, ConversionOption::iges_mode);
    if (deflection) {
        only_for("given", ConversionOption::deflection);
        if (!(*deflection > 0 && *deflection <= kMaxConversionDeflection))
            bad("option 'deflection' must be a number in (0, " + std::to_string(kMaxConversionDeflection) +
                "], a fraction of the model's diagonal");
        r.options.deflection = *deflection;
    }
    if (angular_deflection) {
        only_for("given", ConversionOption::angular_deflection);
        r.options.angular_deflection = checked_angular_deflection(*angular_deflection, "option 'angular_deflection'");
    }
    // "source": the default named (the source's declared unit), as the job document echoes it.
    if (!units.empty() && units != kSourceUnits)
        r.options.units = conversion_enum<LengthUnit>("units", units, length_unit_from_name, length_unit_names());
    if (!schema.empty())
        r.options.step_schema =
            conversion_enum<StepSchema>("step_schema", schema, step_schema_from_name, step_schema_names());
    if (!mode.empty())
        r.options.iges_mode = conversion_enum<IgesMode>("iges_mode", mode, iges_mode_from_name, iges_mode_names());
    return r;
}

double checked_angular_deflection(double radians, const std::string& what) {
    if (!(radians >= kMinAngularDeflection && radians <= kMaxAngularDeflection)) {
        char text[160];
        std::snprintf(text, sizeof text, " must be a number of radians in [%g, %.17g]", kMinAngularDeflection,
                      kMaxAngularDeflection);
        bad(what + text);
    }
    return radians;
}

std::string conversion_request_json(const ConversionRequest& r) {
    const ConvertOptions& o = r.options;
    json j = {{"format", conversion_format_short_name(r.format)}};
    auto takes = [&](ConversionOption option) { return conversion_option_refusal(option, r.format).empty(); };
    if (takes(ConversionOption::units))
        j["units"] =
            o.units == LengthUnit::unknown ? std::string(kSourceUnits) : std::string(length_unit_name(o.units));
    if (takes(ConversionOption::step_schema)) j["step_schema"] = step_schema_name(o.step_schema);
    if (takes(ConversionOption::iges_mode)) j["iges_mode"] = iges_mode_name(o.iges_mode);
    if (takes(ConversionOption::deflection))
        j["deflection"] = o.deflection > 0 ? o.deflection : ImportOptions{}.mesh_relative_deflection;
    if (takes(ConversionOption::angular_deflection)) j["angular_deflection"] = o.angular_deflection;
    j["strict"] = r.strict;
    return j.dump();
}

ConversionFormat parse_conversion_format(const std::string& options_json) {
    return parse_conversion_request(options_json).format;
}

}  // namespace nurbsrt
