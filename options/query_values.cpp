#include "options/query_values.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <set>

#include "core/error.h"

namespace nurbsrt {
namespace {

// The options whose values are not text, by kind (render options; `pinned` of
// a stored file).
const std::set<std::string, std::less<>> kIntegerOptions = {"width", "height", "antialias"};
const std::set<std::string, std::less<>> kNumberOptions = {"edge_width", "fov_deg",           "ortho_height",
                                                           "fit_margin", "ground_height",     "explode",
                                                           "deflection", "angular_deflection"};
const std::set<std::string, std::less<>> kBooleanOptions = {"edges",         "shadows", "pinned", "section_caps",
                                                            "section_hatch", "ground",  "strict"};

bool is_digit(char c) { return c >= '0' && c <= '9'; }

// Consumes 1*DIGIT at `i`; false if there is none.
bool digits(std::string_view s, size_t& i) {
    const size_t start = i;
    while (i < s.size() && is_digit(s[i])) ++i;
    return i > start;
}

std::string bounded(const std::string& text) {
    std::string out;
    for (char c : text.substr(0, 64)) out += (c >= 0x20 && c < 0x7f) ? c : '?';
    return out;
}

}  // namespace

std::optional<double> decimal_number(std::string_view s) {
    // number = [ minus ] int [ frac ] [ exp ]  (RFC 8259 §6)
    size_t i = 0;
    if (i < s.size() && s[i] == '-') ++i;
    if (!digits(s, i)) return std::nullopt;
    if (i < s.size() && s[i] == '.' && !digits(s, ++i)) return std::nullopt;
    if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
        ++i;
        if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
        if (!digits(s, i)) return std::nullopt;
    }
    if (i != s.size()) return std::nullopt;
    double d = 0;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), d);
    if (ec != std::errc() || end != s.data() + s.size() || !std::isfinite(d)) return std::nullopt;
    return d;
}

std::optional<long long> decimal_integer(std::string_view s) {
    size_t i = 0;
    if (i < s.size() && s[i] == '-') ++i;
    if (!digits(s, i) || i != s.size()) return std::nullopt;
    long long n = 0;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), n);
    if (ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
    return n;
}

std::vector<std::string> split_list(std::string_view text, char separator) {
    std::vector<std::string> items;
    for (size_t start = 0; start <= text.size();) {
        const size_t end = std::min(text.find(separator, start), text.size());
        items.emplace_back(text.substr(start, end - start));
        start = end + 1;
    }
    return items;
}

std::optional<std::vector<double>> decimal_list(std::string_view text, size_t min_count, size_t max_count) {
    std::vector<double> out;
    for (size_t start = 0;;) {
        const size_t comma = text.find(',', start);
        const auto d = decimal_number(text.substr(start, comma == std::string_view::npos ? comma : comma - start));
        if (!d || out.size() == max_count) return std::nullopt;
        out.push_back(*d);
        if (comma == std::string_view::npos) break;
        start = comma + 1;
    }
    if (out.size() < min_count) return std::nullopt;
    return out;
}

nlohmann::json query_value(const std::string& key, const std::string& text) {
    if (kIntegerOptions.count(key)) {
        if (const auto n = decimal_integer(text)) return *n;
        throw Error(ErrorCode::invalid_argument,
                    "option '" + key + "' must be a decimal integer (got '" + bounded(text) + "')");
    }
    if (kNumberOptions.count(key)) {
        if (const auto d = decimal_number(text)) return *d;
        throw Error(ErrorCode::invalid_argument,
                    "option '" + key + "' must be a decimal number (got '" + bounded(text) + "')");
    }
    if (kBooleanOptions.count(key)) {
        if (text == "true" || text == "1") return true;
        if (text == "false" || text == "0") return false;
        throw Error(ErrorCode::invalid_argument,
                    "option '" + key + "' must be true, false, 1 or 0 (got '" + bounded(text) + "')");
    }
    return text;
}

}  // namespace nurbsrt
