#include "server/http/api_keys.h"

#include <cctype>
#include <fstream>

#include "core/error.h"

namespace nurbsrt::server {
namespace {

std::string_view trim_space(std::string_view s) {
    while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
    while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
    return s;
}

// Equal strings -> true; the loop always runs over the whole presented key and
// the whole stored key, so the time does not tell where they first differ.
bool constant_time_equal(std::string_view a, std::string_view b) {
    unsigned char diff = a.size() == b.size() ? 0 : 1;
    const size_t n = std::max(a.size(), b.size());
    for (size_t i = 0; i < n; ++i) {
        const unsigned char x = i < a.size() ? static_cast<unsigned char>(a[i]) : 0;
        const unsigned char y = i < b.size() ? static_cast<unsigned char>(b[i]) : 0;
        diff |= static_cast<unsigned char>(x ^ y);
    }
    return diff == 0;
}

}  // namespace

void ApiKeys::add(std::string_view key, const std::string& where) {
    key = trim_space(key);
    if (key.empty()) return;
    if (key.size() < 16)
        throw Error(ErrorCode::invalid_argument, "API key in " + where + " is shorter than 16 characters");
    for (const char c : key)
        if (std::isspace(static_cast<unsigned char>(c)) || std::iscntrl(static_cast<unsigned char>(c)))
            throw Error(ErrorCode::invalid_argument,
                        "API key in " + where + " contains whitespace or control characters");
    keys_.emplace_back(key);
}

void ApiKeys::add_file(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw Error(ErrorCode::invalid_argument, "cannot read the API keys file " + path);
    std::string line;
    int n = 0;
    const size_t before = keys_.size();
    while (std::getline(in, line)) {
        ++n;
        const std::string_view t = trim_space(line);
        if (t.empty() || t.front() == '#') continue;
        add(t, path + ":" + std::to_string(n));
    }
    if (in.bad()) throw Error(ErrorCode::invalid_argument, "cannot read the API keys file " + path);
    // Fail closed: a keys file that is empty, or only comments (a deployment
    // whose secret did not get mounted), must not start an open service.
    if (keys_.size() == before)
        throw Error(ErrorCode::invalid_argument,
                    "the API keys file " + path + " holds no key: refusing to start without authentication");
}

void ApiKeys::add_list(std::string_view list) {
    const size_t before = keys_.size();
    while (!list.empty()) {
        const size_t comma = list.find(',');
        add(list.substr(0, comma), "NURBSRT_API_KEYS");
        if (comma == std::string_view::npos) break;
        list.remove_prefix(comma + 1);
    }
    if (keys_.size() == before)  // set but empty (or only commas): fail closed as for the file
        throw Error(ErrorCode::invalid_argument,
                    "NURBSRT_API_KEYS is set but holds no key: refusing to start without authentication");
}

bool ApiKeys::accepts(std::string_view authorization) const {
    authorization = trim_space(authorization);
    constexpr std::string_view scheme = "bearer ";
    if (authorization.size() <= scheme.size()) return false;
    for (size_t i = 0; i < scheme.size(); ++i)
        if (std::tolower(static_cast<unsigned char>(authorization[i])) != scheme[i]) return false;
    return accepts_key(authorization.substr(scheme.size()));
}

bool ApiKeys::accepts_key(std::string_view key) const {
    const std::string_view presented = trim_space(key);
    if (presented.empty()) return false;
    bool ok = false;
    for (const std::string& k : keys_) ok |= constant_time_equal(presented, k);  // no early exit
    return ok;
}

bool ApiKeys::is_public_path(std::string_view path) {
    // The web page too: a browser loads it before the user can type a key, and
    // it holds no data (it sends the key itself, with every API request).
    return path == "/healthz" || path == "/readyz" || path == "/v1/openapi.json" || path == "/" ||
           (path.rfind("/web/", 0) == 0 && path.find('/', 5) == std::string_view::npos);
}

}  // namespace nurbsrt::server
