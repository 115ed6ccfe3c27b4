#include "core/error.h"

#include "core/enum_names.h"

namespace nurbsrt {

namespace {

constexpr EnumName<ErrorCode> kErrorCodeNames[] = {{ErrorCode::io, "io"},
                                                   {ErrorCode::unsupported_format, "unsupported_format"},
                                                   {ErrorCode::unreadable_file, "unreadable_file"},
                                                   {ErrorCode::no_faces, "no_faces"},
                                                   {ErrorCode::import_timeout, "import_timeout"},
                                                   {ErrorCode::import_crashed, "import_crashed"},
                                                   {ErrorCode::occt_failure, "occt_failure"},
                                                   {ErrorCode::corrupt_scene, "corrupt_scene"},
                                                   {ErrorCode::invalid_argument, "invalid_argument"},
                                                   {ErrorCode::invalid_json, "invalid_json"},
                                                   {ErrorCode::limit_exceeded, "limit_exceeded"},
                                                   {ErrorCode::canceled, "canceled"},
                                                   {ErrorCode::internal, "internal"}};
static_assert(names_every_value(kErrorCodeNames, ErrorCode::internal));

}  // namespace

const char* error_code_name(ErrorCode code) {
    return enum_name(kErrorCodeNames, code, "internal");  // "internal": an out-of-range value cast to ErrorCode
}

std::optional<ErrorCode> error_code_from_name(std::string_view name) { return enum_from_name(kErrorCodeNames, name); }

}  // namespace nurbsrt
