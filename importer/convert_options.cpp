// Names of the conversion options' enums (importer.h). No OCCT here: the CLI
// and the server parse the options with these before any work.
#include "core/enum_names.h"
#include "importer/importer.h"

namespace nurbsrt {
namespace {

constexpr EnumName<StepSchema> kStepSchemaNames[] = {{StepSchema::ap214, "ap214"}, {StepSchema::ap242, "ap242"}};
static_assert(names_every_value(kStepSchemaNames, StepSchema::ap242));

constexpr EnumName<IgesMode> kIgesModeNames[] = {{IgesMode::brep, "brep"}, {IgesMode::faces, "faces"}};
static_assert(names_every_value(kIgesModeNames, IgesMode::faces));

template <typename E, std::size_t N>
std::vector<std::string> all_names(const EnumName<E> (&table)[N]) {
    std::vector<std::string> names;
    for (const auto& [value, name] : table) names.emplace_back(name);
    return names;
}

}  // namespace

std::vector<std::string> step_schema_names() { return all_names(kStepSchemaNames); }
std::vector<std::string> iges_mode_names() { return all_names(kIgesModeNames); }

const char* step_schema_name(StepSchema s) { return enum_name(kStepSchemaNames, s, "ap214"); }
std::optional<StepSchema> step_schema_from_name(std::string_view name) {
    return enum_from_name(kStepSchemaNames, name);
}
const char* iges_mode_name(IgesMode m) { return enum_name(kIgesModeNames, m, "brep"); }
std::optional<IgesMode> iges_mode_from_name(std::string_view name) { return enum_from_name(kIgesModeNames, name); }

}  // namespace nurbsrt
