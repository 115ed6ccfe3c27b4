// Length units by name and by IGES unit flag (importer.h). No OCCT here: the
// CLI and the server parse the `units` option with these before any work.
#include <iterator>

#include "core/enum_names.h"
#include "importer/importer.h"

namespace nurbsrt {
namespace {

constexpr EnumName<LengthUnit> kLengthUnitNames[] = {{LengthUnit::unknown, ""},
                                                     {LengthUnit::inch, "inch"},
                                                     {LengthUnit::mm, "mm"},
                                                     {LengthUnit::foot, "foot"},
                                                     {LengthUnit::mile, "mile"},
                                                     {LengthUnit::m, "m"},
                                                     {LengthUnit::km, "km"},
                                                     {LengthUnit::mil, "mil"},
                                                     {LengthUnit::micron, "micron"},
                                                     {LengthUnit::cm, "cm"},
                                                     {LengthUnit::microinch, "microinch"}};
static_assert(names_every_value(kLengthUnitNames, LengthUnit::microinch));

// IGES 5.3 §2.2.4.3, global parameter 14, in the order of LengthUnit (flag 3,
// "named by parameter 15", has no unit of its own).
constexpr int kIgesUnitFlags[] = {0, 1, 2, 4, 5, 6, 7, 8, 9, 10, 11};
static_assert(std::size(kIgesUnitFlags) == std::size(kLengthUnitNames));

}  // namespace

const char* length_unit_name(LengthUnit u) { return enum_name(kLengthUnitNames, u, ""); }

std::optional<LengthUnit> length_unit_from_name(std::string_view name) {
    if (name.empty()) return std::nullopt;
    return enum_from_name(kLengthUnitNames, name);
}

std::vector<std::string> length_unit_names() {
    std::vector<std::string> names;
    for (size_t i = 1; i < std::size(kLengthUnitNames); ++i) names.emplace_back(kLengthUnitNames[i].second);
    return names;
}

int iges_unit_flag(LengthUnit u) {
    const auto i = static_cast<size_t>(u);
    return i < std::size(kIgesUnitFlags) ? kIgesUnitFlags[i] : 0;
}

LengthUnit length_unit_from_iges_flag(int flag) {
    for (size_t i = 1; i < std::size(kIgesUnitFlags); ++i)
        if (kIgesUnitFlags[i] == flag) return static_cast<LengthUnit>(i);
    return LengthUnit::unknown;
}

}  // namespace nurbsrt
