// The cursors of paged lists (jobs, stored files). Opaque to clients: the
// order's letter ('n' newest first, 'o' oldest first), the last item's key in
// hex and, where keys can tie, '.' and its id; so a cursor cannot be used with
// the other order, and a forged one is refused before any lookup.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>

#include "core/error.h"

namespace nurbsrt::server {

struct PageCursor {
    int64_t key = 0;
    std::string id;  // empty for a cursor without one
};

inline std::string format_page_cursor(bool newest_first, int64_t key, std::string_view id = {}) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%c%llx", newest_first ? 'n' : 'o', static_cast<unsigned long long>(key));
    std::string out = buf;
    if (!id.empty()) out.append(".").append(id);
    return out;
}

// Throws Error(invalid_argument) unless `c` is a cursor of this order, with an
// id exactly when `with_id` (the caller checks the id's own form).
inline PageCursor parse_page_cursor(std::string_view c, bool newest_first, bool with_id) {
    const auto bad = [] {
        return Error(ErrorCode::invalid_argument, "invalid cursor: use next_cursor of a previous page");
    };
    constexpr size_t kMaxHexDigits = 16;  // an int64_t
    const size_t dot = with_id ? c.find('.') : c.size();
    if (c.empty() || c[0] != (newest_first ? 'n' : 'o') || dot == std::string_view::npos || dot < 2 ||
        dot > 1 + kMaxHexDigits || (with_id && dot + 1 == c.size()))
        throw bad();
    PageCursor cursor;
    for (size_t i = 1; i < dot; ++i) {
        const char ch = c[i];
        const int d = ch >= '0' && ch <= '9' ? ch - '0' : ch >= 'a' && ch <= 'f' ? ch - 'a' + 10 : -1;
        if (d < 0 || cursor.key > (INT64_MAX >> 4)) throw bad();
        cursor.key = cursor.key * 16 + d;
    }
    if (with_id) cursor.id = std::string(c.substr(dot + 1));
    return cursor;
}

}  // namespace nurbsrt::server
