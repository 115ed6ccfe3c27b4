#include "server/http/negotiation.h"

#include <cstdlib>

#include "core/ascii.h"
#include "server/http/http_framing.h"

namespace nurbsrt::server {
namespace {

// One media range of an Accept field: "type/subtype" (lower case) and its
// quality weight (RFC 9110 §12.4.2: 0 to 1, three decimals; 1 when absent).
struct MediaRange {
    std::string type;
    double q = 1;
};

std::vector<MediaRange> parse_accept(std::string_view accept) {
    std::vector<MediaRange> out;
    while (!accept.empty()) {
        const size_t comma = accept.find(',');
        std::string_view item = accept.substr(0, comma);
        accept = comma == std::string_view::npos ? std::string_view{} : accept.substr(comma + 1);
        const size_t semi = item.find(';');
        MediaRange range{ascii_lower(trim_ows(item.substr(0, semi))), 1};
        if (range.type.empty()) continue;
        for (std::string_view params = semi == std::string_view::npos ? "" : item.substr(semi + 1); !params.empty();) {
            const size_t next = params.find(';');
            const std::string_view param = trim_ows(params.substr(0, next));
            params = next == std::string_view::npos ? std::string_view{} : params.substr(next + 1);
            if (param.size() > 2 && (param[0] == 'q' || param[0] == 'Q') && param[1] == '=') {
                const std::string value(param.substr(2));
                char* end = nullptr;
                const double q = std::strtod(value.c_str(), &end);
                // A weight that is no number in [0, 1] is read as 0: the range is refused, never preferred.
                range.q = end != value.c_str() && *end == '\0' && q >= 0 && q <= 1 ? q : 0;
            }
        }
        out.push_back(std::move(range));
    }
    return out;
}

// How specifically `range` names `offer`: 3 exactly, 2 by type/*, 1 by */*, 0 not at all.
int specificity(const std::string& range, const std::string& offer) {
    if (range == offer) return 3;
    if (range == "*/*") return 1;
    const size_t slash = offer.find('/');
    if (range.size() == slash + 2 && range.compare(0, slash + 1, offer, 0, slash + 1) == 0 && range.back() == '*')
        return 2;
    return 0;
}

}  // namespace

std::optional<std::string> negotiate_media_type(std::string_view accept, const std::vector<std::string>& offers) {
    const std::vector<MediaRange> ranges = parse_accept(accept);
    if (ranges.empty()) return offers.empty() ? std::nullopt : std::optional(offers.front());
    std::optional<std::string> best;
    double best_q = 0;
    int best_specificity = 0;
    for (const std::string& offer : offers) {
        // The quality of an offer is that of the most specific range naming it.
        const std::string type = ascii_lower(offer);
        int most = 0;
        double q = 0;
        for (const MediaRange& r : ranges) {
            const int s = specificity(r.type, type);
            if (s > most || (s == most && s > 0 && r.q > q)) most = s, q = r.q;
        }
        if (most == 0 || q <= 0) continue;
        if (!best || q > best_q || (q == best_q && most == 3 && best_specificity < 3)) {
            best = offer;
            best_q = q;
            best_specificity = most;
        }
    }
    return best;
}

std::string attachment_disposition(std::string_view name) {
    name = name.substr(name.find_last_of("/\\") + 1);
    std::string quoted, encoded;
    for (const char ch : name) {
        const auto c = static_cast<unsigned char>(ch);
        quoted += c >= 0x20 && c < 0x7f && c != '"' && c != '\\' ? ch : '_';
        // RFC 8187 §3.2.1 attr-char: ALPHA / DIGIT / "!#$&+-.^_`|~"; anything else %XX.
        const bool attr_char = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                               std::string_view("!#$&+-.^_`|~").find(ch) != std::string_view::npos;
        if (attr_char) {
            encoded += ch;
        } else {
            constexpr char kHex[] = "0123456789ABCDEF";
            encoded += '%';
            encoded += kHex[c >> 4];
            encoded += kHex[c & 15];
        }
    }
    return "attachment; filename=\"" + quoted + "\"; filename*=UTF-8''" + encoded;
}

}  // namespace nurbsrt::server
