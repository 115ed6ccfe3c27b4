// Parts chosen by id or name glob (part_selection.h).
#include "options/part_selection.h"

#include <fnmatch.h>

#include <optional>
#include <utility>

#include "core/error.h"
#include "options/render_request.h"

namespace nurbsrt {

namespace {

[[noreturn]] void bad(const std::string& what) { throw Error(ErrorCode::invalid_argument, what); }

// How many parts a "matches nothing" message lists, as examples to choose from.
constexpr size_t kPartsListed = 8;

// Per part: whether `pattern` names it, itself or through an ancestor.
std::vector<uint8_t> matching_parts(const Scene& scene, const std::string& pattern) {
    std::vector<uint8_t> hit(scene.parts.size(), 0);
    for (size_t k = 0; k < scene.parts.size(); ++k) {
        const Part& p = scene.parts[k];
        const bool self = p.id == pattern || fnmatch(pattern.c_str(), p.name.c_str(), 0) == 0;
        // A parent precedes its children (scene.h), so its flag is final here.
        hit[k] = self || (p.parent >= 0 && hit[static_cast<size_t>(p.parent)]);
    }
    return hit;
}

// Per face: whether its body's part is among `parts`.
std::vector<uint8_t> faces_of(const Scene& scene, const std::vector<uint8_t>& parts) {
    std::vector<uint8_t> faces(scene.faces.size(), 0);
    for (size_t i = 0; i < scene.faces.size(); ++i) {
        const uint32_t b = scene.faces[i].body;
        if (b >= scene.bodies.size()) continue;
        const int32_t part = scene.bodies[b].part;
        faces[i] = part >= 0 && static_cast<size_t>(part) < parts.size() && parts[static_cast<size_t>(part)];
    }
    return faces;
}

std::string some_parts(const Scene& scene) {
    if (scene.parts.empty()) return "the file has no assembly tree (nurbsrt info lists one where it has)";
    std::string list;
    for (size_t k = 0; k < scene.parts.size() && k < kPartsListed; ++k)
        list += (list.empty() ? "" : ", ") + scene.parts[k].id + " " + scene.parts[k].name;
    if (scene.parts.size() > kPartsListed) list += ", ...";
    return "parts: " + list;
}

// The faces of every part `pattern` names; throws naming `what` when it names none.
std::vector<uint8_t> selected_faces(const Scene& scene, const std::string& pattern, const std::string& what) {
    const std::vector<uint8_t> parts = matching_parts(scene, pattern);
    for (uint8_t p : parts)
        if (p) return faces_of(scene, parts);
    bad(what + " '" + pattern + "' matches no part of the model (" + some_parts(scene) + ")");
}

}  // namespace

void check_part_pattern(const std::string& pattern, const std::string& what) {
    // Longer than any part name or id path a CAD file gives; bounds fnmatch's work.
    constexpr size_t kMaxPatternBytes = 256;
    if (pattern.empty() || pattern.size() > kMaxPatternBytes)
        bad(what + " must be a part id or name glob of 1 to 256 bytes");
    for (unsigned char c : pattern)
        if (c < 0x20 || c == 0x7f) bad(what + " holds a control character");
}

namespace {

// "PATTERN=value": the last '=' splits them (a part name may hold one, a value does not).
std::pair<std::string, std::string> split_part_value(const std::string& text, const std::string& what,
                                                     const char* form) {
    const size_t eq = text.rfind('=');
    if (eq == std::string::npos || eq == 0) bad(what + " must be " + form);
    std::string pattern = text.substr(0, eq);
    check_part_pattern(pattern, what + "'s part");
    return {std::move(pattern), text.substr(eq + 1)};
}

}  // namespace

std::pair<std::string, Color> parse_part_color(const std::string& text, const std::string& what) {
    auto [pattern, value] = split_part_value(text, what, "ID_OR_GLOB=r,g,b");
    return {std::move(pattern), parse_rgb(value, what + "'s colour")};
}

std::pair<std::string, Vec3> parse_part_move(const std::string& text, const std::string& what) {
    auto [pattern, value] = split_part_value(text, what, "ID_OR_GLOB=dx,dy,dz");
    return {std::move(pattern), parse_point(value, what + "'s translation")};
}

void apply_part_selection(const PartSelection& selection, const Scene& scene, RenderOptions& options) {
    if (selection.empty()) return;
    const size_t n = scene.faces.size();
    std::vector<uint8_t> hidden(n, 0);
    if (!selection.only.empty()) {
        std::vector<uint8_t> kept(n, 0);
        for (size_t k = 0; k < selection.only.size(); ++k) {
            const std::vector<uint8_t> f =
                selected_faces(scene, selection.only[k], "parts.only[" + std::to_string(k) + "]");
            for (size_t i = 0; i < n; ++i) kept[i] |= f[i];
        }
        for (size_t i = 0; i < n; ++i) hidden[i] = !kept[i];
    }
    for (size_t k = 0; k < selection.hide.size(); ++k) {
        const std::vector<uint8_t> f =
            selected_faces(scene, selection.hide[k], "parts.hide[" + std::to_string(k) + "]");
        for (size_t i = 0; i < n; ++i) hidden[i] |= f[i];
    }
    bool any_hidden = false;
    for (uint8_t h : hidden) any_hidden |= h != 0;
    if (any_hidden) options.hidden_faces = std::move(hidden);
    if (!selection.ghost.empty()) {
        options.ghost_faces.assign(n, 0);
        for (size_t k = 0; k < selection.ghost.size(); ++k) {
            const std::vector<uint8_t> f =
                selected_faces(scene, selection.ghost[k], "parts.ghost[" + std::to_string(k) + "]");
            for (size_t i = 0; i < n; ++i) options.ghost_faces[i] |= f[i];
        }
    }
    if (!selection.color.empty()) {
        options.face_colors.assign(n, std::nullopt);
        for (const auto& [pattern, colour] : selection.color) {
            const std::vector<uint8_t> f = selected_faces(scene, pattern, "parts.color");
            for (size_t i = 0; i < n; ++i)
                if (f[i]) options.face_colors[i] = colour;
        }
    }
    if (selection.move.empty()) return;
    std::vector<std::optional<Vec3>> moved(n);
    for (const auto& [pattern, t] : selection.move) {
        const std::vector<uint8_t> f = selected_faces(scene, pattern, "parts.move");
        for (size_t i = 0; i < n; ++i)
            if (f[i]) moved[i] = t;
    }
    if (options.face_offsets.empty()) options.face_offsets.assign(n, Vec3{0, 0, 0});
    for (size_t i = 0; i < n; ++i)
        if (moved[i]) options.face_offsets[i] += *moved[i];
}

}  // namespace nurbsrt
