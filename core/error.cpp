#include "core/error.h"

namespace nurbsrt {

const char* error_code_name(ErrorCode code) {
    switch (code) {
        case ErrorCode::io:
            return "io";
        case ErrorCode::unsupported_format:
            return "unsupported_format";
        case ErrorCode::unreadable_file:
            return "unreadable_file";
        case ErrorCode::no_faces:
            return "no_faces";
        case ErrorCode::import_timeout:
            return "import_timeout";
        case ErrorCode::import_crashed:
            return "import_crashed";
        case ErrorCode::occt_failure:
            return "occt_failure";
        case ErrorCode::corrupt_scene:
            return "corrupt_scene";
        case ErrorCode::invalid_argument:
            return "invalid_argument";
        case ErrorCode::invalid_json:
            return "invalid_json";
        case ErrorCode::limit_exceeded:
            return "limit_exceeded";
        case ErrorCode::canceled:
            return "canceled";
        case ErrorCode::internal:
            return "internal";
    }
    return "internal";  // out-of-range value cast to ErrorCode
}

}  // namespace nurbsrt
