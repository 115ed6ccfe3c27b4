// Stable names of an enum's values: one table per enum, checked at compile time
// to list every value once in declaration order, read both ways (name of a
// value for JSON and logs, value of a name at the edge where text comes in).
#pragma once

#include <cstddef>
#include <optional>
#include <string_view>
#include <utility>

namespace nurbsrt {

template <typename E>
using EnumName = std::pair<E, const char*>;

// True when `table` holds the values 0 .. last, in order, each once.
template <typename E, std::size_t N>
constexpr bool names_every_value(const EnumName<E> (&table)[N], E last) {
    for (std::size_t i = 0; i < N; ++i)
        if (static_cast<std::size_t>(table[i].first) != i) return false;
    return N == static_cast<std::size_t>(last) + 1;
}

// The name of `value`; `fallback` for a value outside the enum (an integer cast to it).
template <typename E, std::size_t N>
constexpr const char* enum_name(const EnumName<E> (&table)[N], E value, const char* fallback) {
    const auto i = static_cast<std::size_t>(value);
    return i < N ? table[i].second : fallback;
}

// The value named `name`, if any.
template <typename E, std::size_t N>
constexpr std::optional<E> enum_from_name(const EnumName<E> (&table)[N], std::string_view name) {
    for (const auto& [value, text] : table)
        if (name == text) return value;
    return std::nullopt;
}

}  // namespace nurbsrt
