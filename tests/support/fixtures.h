// Test fixtures: small CAD files generated with OCCT itself, plus access to the
// real test models in ../shared/models (which are never copied into the repo).
//
// Every fixture is written once per process, on first use, into a private
// temporary directory (mkdtemp) that is removed when the process exits. Each
// function returns the file's path. The geometry is fully deterministic (no
// random numbers, fixed dimensions); only the STEP/IGES header timestamps vary.
// Generation is fast (all fixtures together well under a second).
//
// Not thread-safe with concurrent STEP/IGES reading elsewhere in the process
// (OCCT's STEP/IGES readers share global state): call these from the test's main thread.
#pragma once

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace nurbsrt::test {

// Directory of the fixtures of this process (created on first call).
std::string fixture_dir();

// --- solids -----------------------------------------------------------------
// Box 60 x 40 x 20 with two through-holes (radius 5 and 7) along Z, made with
// BRepAlgoAPI_Cut: 6 planar faces + 2 cylindrical hole faces = 8 faces; the top
// and bottom faces each carry two inner trim loops.
std::string box_with_holes();
// Box 40 x 30 x 20 with every edge filleted (radius 4, BRepFilletAPI_MakeFillet):
// 6 planes + 12 cylinders + 8 spherical corners = 26 faces.
std::string filleted_box();
// filleted_box with a through-hole (radius 6, along Z, through the top and
// bottom faces) cut after the fillets: 26 + 1 faces. Not in fixture_names()
// (the feature-line test's part).
std::string holed_filleted_box();
// The same box with a different radius per edge direction (x 2, y 3.5, z 5):
// where three fillets of different radii meet, OCCT builds a free-form vertex
// blend (no sphere), the corner where fillet cracks were seen on real files.
std::string filleted_box_blend();
// A fan: a hub cylinder (r 8, h 8, axis Z) fused with 7 thin twisted blades
// (lofted B-spline faces, 0.6 thick, 9 chord, radius 6 to 38, 50 deg twist).
std::string blade_fan();
// A flat ring kThinRingWidth wide (a third of a pixel at 512 px) in the plane
// y = -kThinRingGap, centred on (kThinRingCentre, y, kThinRingCentre), in front of
// the face y = 0 of a 100 x 4 x 100 plate as seen from the front (along +y).
std::string thin_ring();
inline constexpr double kThinRingRadius = 30.0, kThinRingWidth = 0.08, kThinRingGap = 1.0, kThinRingCentre = 50.0;
// BRepPrimAPI primitives (analytic surfaces; NURBS conversion makes them rational).
std::string cylinder();  // r 10, h 30, 3 faces
std::string sphere();    // r 15, 1 face (two degenerate pole edges)
std::string cone();      // r1 12, r2 4, h 25, 3 faces (lateral + 2 discs)
std::string torus();     // R 20, r 6, 1 face (doubly periodic)
// A rod 15 times longer than thick: cylinder r 4, h 120 along (1, 0.25, 0.1),
// so that no named view sees it square (not in fixture_names(): only the
// fitted-view test needs its shape).
std::string elongated_rod();

// A 10 mm cube with its lowest corner at kCube10Corner (off the origin, so that a
// measurement cannot pass by ignoring the placement): the web page's measuring
// test. Not in fixture_names() (only that test needs it; nurbsrt_fixture writes it).
std::string cube10();
struct Offset {
    double x, y, z;
};
constexpr Offset kCube10Corner{5.0, -3.0, 2.0};

// --- free-form faces ----------------------------------------------------------
// A non-planar, non-rational degree 3x3 Geom_BSplineSurface (6 x 5 poles,
// non-uniform knots with a double interior knot in u, parameter box
// u in [0, 20], v in [-1, 3]) as a single face trimmed by one circular inner
// hole, written as STEP (shell-based surface model). 1 face.
std::string freeform_bspline();
// The same net with non-uniform weights in [0.4, 2.5] (rational), and an
// elliptical hole. 1 face.
std::string freeform_rational();
// A dense, high-degree net for cost and fairness measurements (not in
// fixture_names(): rendering it is deliberately expensive): one untrimmed
// non-rational face of degree `degree` x `degree` on `poles` x `poles` poles
// (uniform clamped knots) over a 100 x 100 square, a smooth height field of
// amplitude 8. Written once per (degree, poles).
std::string dense_bspline(int degree, int poles);

// --- assembly -----------------------------------------------------------------
// XDE document written with STEPCAFControl_Writer: one part (the part of
// kAssemblyPartFaces faces, a 30 x 20 x 10 box with a through-hole) placed
// twice, at kAssemblyOffsets[0] and kAssemblyOffsets[1] (pure translations), with
// the part named kAssemblyPartName, the instances kAssemblyInstanceNames, and the
// part coloured kAssemblyColor (surface colour).
std::string assembly();
constexpr int kAssemblyPartFaces = 7;
inline const char* const kAssemblyPartName = "bracket";
inline const char* const kAssemblyInstanceNames[2] = {"bracket_left", "bracket_right"};
struct Rgb {
    double r, g, b;
};
constexpr Rgb kAssemblyColor{0.9, 0.1, 0.2};
constexpr Offset kAssemblyOffsets[2] = {{-40.0, 0.0, 0.0}, {60.0, 25.0, 5.0}};

// IGES (BRep mode, IGESControl_Writer("MM", 1)) copy of a STEP file, written
// next to the fixtures once per input path.
std::string to_iges(const std::string& step_path);

// A fixture by name ("box_with_holes", ..., "assembly", and "<name>_iges" for
// the IGES copy). Throws std::invalid_argument for an unknown name.
std::string fixture_by_name(const std::string& name);
// All fixture names accepted by fixture_by_name (cheap: generates nothing).
std::vector<std::string> fixture_names();

// --- shared real-world models -----------------------------------------------------
// $NURBSRT_MODELS if set, else NURBSRT_SOURCE_DIR "/../shared/models"; "" when
// that directory does not exist.
std::string shared_models_dir();
// The .stp/.step/.igs/.iges files (any case) in shared_models_dir()/subdir,
// sorted by name, as full paths; empty when absent.
std::vector<std::string> shared_model_files(const std::string& subdir);
// Full path of shared_models_dir()/relative ("" when the models are absent).
std::string shared_model(const std::string& relative);

// A name usable in a gtest parameter name: [A-Za-z0-9_] only.
std::string sanitize_test_name(const std::string& s);

}  // namespace nurbsrt::test

// Skips the current test, with a visible reason, when ../shared/models is absent.
#define NURBSRT_REQUIRE_SHARED_MODELS()                                                   \
    do {                                                                                  \
        if (::nurbsrt::test::shared_models_dir().empty())                                 \
            GTEST_SKIP() << "../shared/models is absent: skipping this test on real CAD " \
                            "models (set NURBSRT_MODELS to point elsewhere)";             \
    } while (0)
