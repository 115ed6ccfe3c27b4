// CLI11 validators for the values the commands check before any work, so that
// a bad value is a usage error (exit 2, CLI11's message naming the flag) found
// before an import, not a failure after it.
#pragma once

#include <CLI/CLI.hpp>

#include <cstdio>
#include <filesystem>
#include <initializer_list>
#include <string>
#include <type_traits>
#include <unistd.h>

#include "core/ascii.h"
#include "core/error.h"

namespace nurbsrt::cli {

// CLI::Range, with a message that says what is wrong: CLI11 2.1 answers text
// that is no number ("--width abc") with "not in range". A range of integers
// takes whole numbers only.
template <typename T>
CLI::Validator in_range(T lo, T hi) {
    const CLI::Range range(lo, hi);
    return CLI::Validator(
        [range](std::string& s) -> std::string {
            T value{};
            if (!CLI::detail::lexical_cast(s, value))
                return "'" + s + "' is not " + (std::is_integral_v<T> ? "a whole number" : "a number");
            return range(s);
        },
        range.get_description());
}

// The request model's parsers as CLI11 checks, so that the CLI and the API
// accept and refuse the same values.
template <class Parse>
CLI::Validator shared_check(Parse parse, const char* description) {
    return CLI::Validator(
        [parse](std::string& s) -> std::string {
            try {
                parse(s);
                return {};
            } catch (const Error& e) {
                return e.what();
            } catch (const std::exception&) {
                return "not a number: " + s;
            }
        },
        description);
}

// A file we are going to write: one of `extensions` (lower case, with the dot),
// in a directory that exists and that we may write.
inline CLI::Validator output_file_validator(std::initializer_list<const char*> extensions) {
    std::string list;
    for (const char* e : extensions) list += (list.empty() ? "" : ", ") + std::string(e);
    return CLI::Validator(
        [exts = std::vector<std::string>(extensions.begin(), extensions.end()), list](std::string& s) -> std::string {
            namespace fs = std::filesystem;
            const fs::path p(s);
            const std::string ext = ascii_lower(p.extension().string());
            bool known = false;
            for (const std::string& e : exts) known = known || ext == e;
            if (!known) return "'" + s + "' must end in one of " + list;
            const fs::path dir = p.has_parent_path() ? p.parent_path() : fs::path(".");
            std::error_code ec;
            if (!fs::is_directory(dir, ec)) return "the directory '" + dir.string() + "' does not exist";
            if (::access(dir.c_str(), W_OK) != 0) return "the directory '" + dir.string() + "' is not writable";
            if (fs::is_directory(p, ec)) return "'" + s + "' is a directory";
            return {};
        },
        "FILE(" + list + ")");
}

}  // namespace nurbsrt::cli
