// The renderer's options as the CLI, the API and the statistics spell them,
// and their parsing back (once, at the edge). Apart from the solver and the map
// so that parsers of requests need neither the solver nor OpenGL (the fuzzing
// harnesses link only this).
#include "renderer/method.h"

namespace nurbsrt {

double default_newton_eps(const BBox& box, double relative) {
    const double d = box.diagonal();
    return relative * (d > 0 ? d : 1.0);
}

const char* newton_method_name(NewtonMethod m) { return m == NewtonMethod::proposed ? "proposed" : "martin"; }

std::optional<NewtonMethod> parse_newton_method(std::string_view name) {
    for (NewtonMethod m : {NewtonMethod::proposed, NewtonMethod::martin})
        if (name == newton_method_name(m)) return m;
    return std::nullopt;
}

const char* map_precision_name(MapPrecision p) { return p == MapPrecision::rgb8 ? "rgb8" : "float32"; }
const char* map_precision_option(MapPrecision p) { return p == MapPrecision::rgb8 ? "rgb8" : "float"; }
std::optional<MapPrecision> parse_map_precision(std::string_view option) {
    for (MapPrecision p : {MapPrecision::float32, MapPrecision::rgb8})
        if (option == map_precision_option(p)) return p;
    return std::nullopt;
}

}  // namespace nurbsrt
