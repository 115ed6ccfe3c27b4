// Option values that arrive as text (query parameters, form fields) typed once,
// at the edge, by the option they set: `width=100` becomes the JSON integer
// 100 and `edges=true` the JSON boolean, exactly as a JSON body would give them,
// so the option parsers take JSON types only (a JSON "100" or "true" is refused
// there). Text of the wrong kind is refused here: integers are decimal digits
// (no hex "0x10", no NUL, no sign '+', no spaces), numbers follow RFC 8259's
// number grammar (no inf, nan or hex), booleans are true, false, 1 or 0. Names
// of other options (strings, lists "x,y,z", unknown names) stay text.
#pragma once

#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace nurbsrt {

// The JSON value of option `key` given as `text`; throws Error(invalid_argument)
// naming the option when the text is not of its type.
nlohmann::json query_value(const std::string& key, const std::string& text);

// RFC 8259 §6 number / an optional '-' and decimal digits, the whole text.
std::optional<double> decimal_number(std::string_view text);
std::optional<long long> decimal_integer(std::string_view text);
// The items of a list given as text ("z,face", "front,top", planes "a;b"):
// split at every `separator`, empty items kept (the parser of the items refuses them).
std::vector<std::string> split_list(std::string_view text, char separator);
// "a,b,c": `min_count` to `max_count` decimal numbers separated by commas,
// nothing else (no spaces, no empty item); nullopt otherwise.
std::optional<std::vector<double>> decimal_list(std::string_view text, size_t min_count, size_t max_count);

}  // namespace nurbsrt
