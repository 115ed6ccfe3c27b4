// Bounded parsing of JSON text that comes from outside (requests, job specs,
// scene files). nlohmann::json parses iteratively, but dump(), copies,
// comparisons and merge_patch recurse once per nesting level: a value nested
// 60,000 deep overflows a thread's stack. The text is measured first, in one
// pass without recursion or allocation, and parsed only within the limits.
#pragma once

#include <nlohmann/json.hpp>

#include <cstddef>
#include <string>
#include <string_view>

namespace nurbsrt {

struct JsonLimits {
    size_t max_bytes = 0;   // 0: no bound on the text's size
    int max_depth = 64;     // nested arrays and objects
    size_t max_values = 0;  // 0: no bound on the number of values
};

// Options, job specs and small request bodies: far above what any real one
// needs (a job of 64 outputs with every option is ~5,000 values and ~40 KiB).
inline constexpr JsonLimits kRequestJsonLimits{256 * 1024, 64, 20'000};
// Scene files hold whole NURBS models (MBs of numbers) but are never deeper
// than a handful of levels.
inline constexpr JsonLimits kDocumentJsonLimits{0, 64, 0};

enum class JsonProblem { none, not_json, too_large, too_deep, too_many_values };

struct BoundedJson {
    nlohmann::json value;  // discarded unless problem == none
    JsonProblem problem = JsonProblem::none;
    std::string detail;  // what is wrong, naming the limit ("nested deeper than 64 levels")
    bool ok() const { return problem == JsonProblem::none; }
};

// Measures `text` against `limits`, then parses it (RFC 8259; NaN, numbers
// out of double range and trailing garbage are not JSON).
BoundedJson parse_json_bounded(std::string_view text, const JsonLimits& limits);

// The same, for callers that answer a problem with an exception: the value, or
// Error(ErrorCode::invalid_json) "<what>: <detail>".
nlohmann::json parse_json_or_throw(std::string_view text, const JsonLimits& limits, const std::string& what);

}  // namespace nurbsrt
