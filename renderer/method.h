// The choices that select how a frame is solved, as public options: the Newton
// method and its parameters (solve/newton.h implements them), and the precision
// of the preliminary map (map/preliminary_map.h). Their names are the spelling
// of the CLI, the API and the statistics, parsed once at the edge.
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>

#include "core/scene/scene.h"

namespace nurbsrt {

// proposed: Sisojevs & Glazs 2010, eq. (8)-(11); martin: Martin et al. 2000.
enum class NewtonMethod : uint8_t { proposed, martin };
const char* newton_method_name(NewtonMethod m);  // "proposed", "martin"
// The method of a name as newton_method_name spells it; nullopt for anything else.
std::optional<NewtonMethod> parse_newton_method(std::string_view name);

// Termination of every solve; the criteria are Sisojevs & Glazs 2010, eq. (12)-(14)
// (solve/newton.h says how each is measured).
struct NewtonParams {
    double eps = 0;          // (12), model units, must be > 0 (see default_newton_eps)
    double eps_det = 1e-12;  // (14), relative
    int max_iterations = 8;
    bool robust = false;  // clamp-and-continue at the box, backtracking on (13); see solve/newton.h
    // robust: halvings of a step that raises the residual before (13) declares
    // divergence. Four shrink the step to 1/16: enough to get back under an
    // overshoot near a silhouette (a light ray grazing an occluder needs them).
    int backtracks = 4;
};

// The renderer's default (12) tolerance: 1e-8 x the scene's bounding-box diagonal.
// It is what the output can show, with margin: the Z AOV is a float, whose
// resolution at a typical depth (t ~ the diagonal) is ~6e-8 of it, and one pixel
// of a 4096-pixel-wide view of the whole scene is ~2e-4 of it; 1e-8 is below
// both, and 100x below the 1e-6 agreement with OCCT's intersector that the
// accuracy tests demand. Tighter costs iterations for nothing visible (each
// decade is at most one more quadratic step). Double evaluation of a patch is accurate to
// ~1e-15 of its size, so even 1e-12 stays reachable (tests use 1e-9 and tighter).
constexpr double kDefaultRelativeTolerance = 1e-8;
double default_newton_eps(const BBox& scene_box, double relative = kDefaultRelativeTolerance);

enum class MapPrecision : uint8_t {
    float32,  // u, v as interpolated by GL (float)
    rgb8,     // u, v quantized to 8 bits of the face's parameter box (Sisojevs & Glazs 2010, eq. 4)
};
const char* map_precision_name(MapPrecision p);  // "float32", "rgb8"
// The spelling of the CLI and the API options: "float", "rgb8"; parse_map_precision
// reads it back (nullopt for anything else).
const char* map_precision_option(MapPrecision p);
std::optional<MapPrecision> parse_map_precision(std::string_view option);

}  // namespace nurbsrt
