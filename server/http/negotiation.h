// What an answer's representation is and is called, from the request's side:
// proactive negotiation of the media type by Accept (RFC 9110 §12.5.1), and the
// file name a download is saved under (Content-Disposition, RFC 6266 with the
// UTF-8 form of RFC 8187).
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace nurbsrt::server {

// The offer an Accept field value prefers among `offers` (media types, most
// preferred first): the highest quality of the media range each offer matches
// most specifically (type/subtype over type/* over */*); at equal quality an
// offer named exactly beats one matched by a wildcard, then the earlier offer.
// An absent or empty field accepts anything (the first offer). nullopt: the
// client accepts none of them (406 Not Acceptable).
std::optional<std::string> negotiate_media_type(std::string_view accept, const std::vector<std::string>& offers);

// `attachment; filename="..."; filename*=UTF-8''...` for a download named
// `name` (a client's label, never a path: only its last path segment is used).
// The quoted form carries the name where it is printable ASCII (other bytes
// become '_'), the RFC 8187 form the exact bytes, percent-encoded.
std::string attachment_disposition(std::string_view name);

}  // namespace nurbsrt::server
