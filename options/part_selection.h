// Parts of an assembly chosen by the request (RenderRequest::parts): hidden,
// isolated (`only`), see-through (`ghost`), recoloured or moved, by id ("0/3/1", Part::id) or by a name glob
// ("nut*", fnmatch's * ? [...]); a node stands for its whole subtree. Resolved
// against the imported scene into the renderer's per-face options
// (RenderOptions::hidden_faces, face_colors, face_offsets): the scene itself stays as it was
// imported and prepared, so a cached scene renders any selection without a new
// import or prepare().
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "core/scene/scene.h"
#include "renderer/render.h"

namespace nurbsrt {

// At most this many patterns in each list of a request: a catalogue shot names
// a handful of parts; a list longer than the largest assemblies' part counts
// is a mistake or an attack on the glob matcher.
inline constexpr size_t kMaxPartPatterns = 256;

struct PartSelection {
    std::vector<std::string> hide, only, ghost;
    std::vector<std::pair<std::string, Color>> color;  // pattern -> colour, later entries win
    // pattern -> translation in model units (an explicit exploded view), added
    // to explode's; a face named by several patterns takes the last.
    std::vector<std::pair<std::string, Vec3>> move;
    bool empty() const { return hide.empty() && only.empty() && ghost.empty() && color.empty() && move.empty(); }
};

// A pattern as the request gives it: non-empty, at most 256 bytes, printable.
// Throws Error(invalid_argument) naming `what`.
void check_part_pattern(const std::string& pattern, const std::string& what);

// "PART=r,g,b" (the CLI's --part-color): a pattern as above and a colour in
// [0, 1] (parse_rgb). The last '=' splits them: a part name may hold one, a
// colour does not. Throws Error(invalid_argument) naming `what`.
std::pair<std::string, Color> parse_part_color(const std::string& text, const std::string& what);
// "PART=dx,dy,dz" (the CLI's --part-move): a pattern and a translation (parse_point).
std::pair<std::string, Vec3> parse_part_move(const std::string& text, const std::string& what);

// Sets options.hidden_faces, ghost_faces and face_colors for `scene`, and adds
// the moves to options.face_offsets. Throws
// Error(invalid_argument) naming the request field (parts.hide[2], ...) for a
// pattern no part matches, listing a few of the scene's part ids and names.
void apply_part_selection(const PartSelection& selection, const Scene& scene, RenderOptions& options);

}  // namespace nurbsrt
