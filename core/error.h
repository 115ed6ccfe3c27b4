// The library's error type. Every failure of reading, converting or rendering a
// model that can reach a user (CLI message, HTTP problem+json body, job error) is
// an nurbsrt::Error with a stable code, so callers map codes to exit statuses /
// HTTP statuses in one place each. The service's own conditions (no such route,
// a full queue, a missing API key) are server/common/service_error.h's, not these.
#pragma once

#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

namespace nurbsrt {

enum class ErrorCode {
    io,                  // file cannot be opened/read/written (not the CAD content)
    unsupported_format,  // neither STEP nor IGES (by content), or unknown output extension
    unreadable_file,     // STEP/IGES whose content OCCT cannot read (truncated, malformed)
    no_faces,            // read fine but holds no faces to render
    import_timeout,      // import exceeded its time limit
    import_crashed,      // the isolated import process died (signal, out of memory)
    occt_failure,        // an OCCT algorithm threw (message carries OCCT's text)
    corrupt_scene,       // serialized scene is truncated, has a bad header or checksum
    invalid_argument,    // a parameter out of range (camera, size, options)
    invalid_json,        // JSON text that is not JSON, or beyond the limits it is parsed within (core/json_limits.h)
    limit_exceeded,      // a configured limit (pixels, faces, bytes) was exceeded
    canceled,            // the work was canceled (RenderOptions::cancel, a deleted job)
    internal,            // a bug: should never reach a user
};

// Stable machine-readable name of a code ("unreadable_file", ...), used in JSON errors.
const char* error_code_name(ErrorCode code);
// The code of such a name (the isolated import reports its failure by name).
std::optional<ErrorCode> error_code_from_name(std::string_view name);

class Error : public std::runtime_error {
public:
    Error(ErrorCode code, const std::string& message) : std::runtime_error(message), code_(code) {}
    ErrorCode code() const { return code_; }

private:
    ErrorCode code_;
};

}  // namespace nurbsrt
