// Shared by the libFuzzer harnesses: what counts as a normal outcome.
//
// Our parsers promise to refuse bad input with nurbsrt::Error (a 4xx answer or a
// clean CLI error). Anything else is a finding: libFuzzer reports crashes and
// sanitizer errors itself, and an exception of another type escaping here ends
// in std::terminate, which it reports as a crash with the input that caused it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "core/error.h"

namespace nurbsrt::fuzz {

inline std::string as_string(const uint8_t* data, size_t size) {
    return std::string(reinterpret_cast<const char*>(data), size);
}

// Runs `body`; nurbsrt::Error is an expected answer to bad input.
template <class Body>
void expect_only_errors(Body&& body) {
    try {
        body();
    } catch (const Error&) {}
}

}  // namespace nurbsrt::fuzz
