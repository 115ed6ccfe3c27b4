// Section planes (section.h): which side of them a point is on, and where a ray
// crosses into the kept space.
#include "renderer/section.h"

#include <cmath>

namespace nurbsrt {

const char* section_mode_name(SectionMode m) { return m == SectionMode::cutaway ? "cutaway" : "union"; }

std::optional<SectionMode> parse_section_mode(std::string_view name) {
    for (SectionMode m : {SectionMode::union_of, SectionMode::cutaway})
        if (name == section_mode_name(m)) return m;
    return std::nullopt;
}

namespace {

// Whether the planes' removed flags make a point removed.
bool combine(SectionMode mode, const bool* removed, size_t n) {
    if (n == 0) return false;
    for (size_t k = 0; k < n; ++k)
        if (removed[k] == (mode == SectionMode::union_of)) return mode == SectionMode::union_of;
    return mode == SectionMode::cutaway;
}

}  // namespace

bool Sections::removes(Vec3 p) const {
    bool removed[kMaxSectionPlanes] = {};
    const size_t n = std::min(planes.size(), kMaxSectionPlanes);
    for (size_t k = 0; k < n; ++k) removed[k] = planes[k].distance(p) > 0;
    return combine(mode, removed, n);
}

std::optional<Sections::Entry> Sections::entry_before(const Ray& ray, double t_limit) const {
    const size_t n = std::min(planes.size(), kMaxSectionPlanes);
    double s0[kMaxSectionPlanes], ds[kMaxSectionPlanes];
    for (size_t k = 0; k < n; ++k) {
        s0[k] = planes[k].distance(ray.origin);
        ds[k] = dot(ray.dir, planes[k].normal);
    }
    // Each plane's crossing, latest first: the ray's removed state only changes
    // there. Just before and just after a crossing at c, a plane's side is the
    // sign of its distance at c, or, where that is 0 (the crossing plane itself,
    // or another through the same point), the sign of its rate along the ray.
    std::optional<Entry> best;
    for (size_t k = 0; k < n; ++k) {
        if (ds[k] == 0) continue;
        const double c = -s0[k] / ds[k];
        if (!(c > 0 && c < t_limit) || (best && c <= best->t)) continue;
        bool before[kMaxSectionPlanes], after[kMaxSectionPlanes];
        for (size_t j = 0; j < n; ++j) {
            const double s = j == k ? 0.0 : s0[j] + c * ds[j];
            before[j] = s == 0 ? ds[j] < 0 : s > 0;
            after[j] = s == 0 ? ds[j] > 0 : s > 0;
        }
        if (combine(mode, before, n) && !combine(mode, after, n)) best = Entry{c, static_cast<int>(k)};
    }
    return best;
}

}  // namespace nurbsrt
