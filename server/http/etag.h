// Entity tags of job artifacts and of renders of stored files, for conditional requests (RFC 9110 §8.8.3 ETag,
// §13.1.2 If-None-Match): an artifact never changes once written, so a client
// holding it revalidates with a 304 and no body instead of a second download.
#pragma once

#include <string>

namespace nurbsrt::server {

// A strong entity tag of the file's bytes: the quoted SHA-256 in hex. Strong
// because it changes with any byte, as a content hash does (RFC 9110 §8.8.1).
// Throws Error(io) when the file cannot be read.
std::string file_etag(const std::string& path);

// A strong entity tag of the image a render of a stored file gives: a hash
// of this program's own executable, the file's SHA-256 and the options' JSON
// text. Strong because the renderer is deterministic: the same build renders
// the same bytes with the same options to the same image bytes (the API
// suite checks two renders byte for byte); another build may render
// differently, so the executable's hash is part of the tag.
std::string render_etag(const std::string& file_sha256, const std::string& options_json);

// True when the If-None-Match field value `header` matches `etag`: "*", or one
// of its comma-separated entity tags under the weak comparison that
// If-None-Match uses (W/ prefixes ignored, RFC 9110 §13.1.2 and §8.8.3.2).
bool if_none_match_matches(const std::string& header, const std::string& etag);

}  // namespace nurbsrt::server
