// Optional API keys: when any key is configured, every request except the
// unauthenticated probes (/healthz, /readyz), the API document and the web page needs
// `Authorization: Bearer <key>` (or `X-Api-Key: <key>`); otherwise it gets 401 (problem+json) before
// any work starts. Keys come from a file (one per line, '#' comments) and/or the
// NURBSRT_API_KEYS environment variable (comma-separated), never from the
// command line (it would show in `ps`), and are never logged.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace nurbsrt::server {

class ApiKeys {
public:
    // Adds the keys of a file / of a comma-separated list. Throws
    // Error(invalid_argument) for an unreadable file or a key that is too short
    // (< 16 characters) or contains whitespace or control characters, and for a
    // file or list that holds no key at all (auth fails closed, never open).
    void add_file(const std::string& path);
    void add_list(std::string_view comma_separated);

    bool enabled() const { return !keys_.empty(); }
    size_t size() const { return keys_.size(); }
    // True when the Authorization header value carries one of the keys
    // ("Bearer <key>", scheme case-insensitive). Compared in time independent
    // of where the strings differ, so a key cannot be guessed byte by byte.
    bool accepts(std::string_view authorization) const;
    // The same for a bare key, as the X-Api-Key header carries it (the header
    // name many API gateways use; a page may find it simpler than Bearer).
    bool accepts_key(std::string_view key) const;

    // Paths open without a key: liveness/readiness probes, the API document and
    // the web page (GET / and /web/{name}).
    static bool is_public_path(std::string_view path);

private:
    void add(std::string_view key, const std::string& where);
    std::vector<std::string> keys_;
};

}  // namespace nurbsrt::server
