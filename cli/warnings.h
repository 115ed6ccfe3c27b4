// The warnings of a command (what the import or the conversion worked around or
// lost): one line each on stderr, unless --quiet; under --strict they fail the
// command with exit status 3 before it writes anything.
#pragma once

#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

namespace nurbsrt::cli {

// Thrown under --strict when there are warnings; main() answers exit status 3.
class WarningsRefused : public std::runtime_error {
public:
    explicit WarningsRefused(size_t count)
        : std::runtime_error(std::to_string(count) + " warning(s), refused by --strict; nothing was written") {}
};

inline void report_warnings(const std::vector<std::string>& warnings, bool quiet, bool strict) {
    if (!quiet)
        for (const std::string& w : warnings) std::fprintf(stderr, "nurbsrt: warning: %s\n", w.c_str());
    if (strict && !warnings.empty()) throw WarningsRefused(warnings.size());
}

}  // namespace nurbsrt::cli
