#include "server/http/etag.h"

#include <algorithm>
#include <fstream>
#include <memory>
#include <vector>

#include "core/error.h"
#include "server/store/file_store.h"
#include "server/common/sha256.h"

namespace nurbsrt::server {
namespace {

// Read size of the hash: large enough that reads cost little next to SHA-256
// itself, small enough for a pool thread's heap.
constexpr size_t kHashChunkBytes = 1 << 16;

std::string trimmed(const std::string& s, size_t from, size_t to) {
    while (from < to && (s[from] == ' ' || s[from] == '\t')) ++from;
    while (to > from && (s[to - 1] == ' ' || s[to - 1] == '\t')) --to;
    return s.substr(from, to - from);
}

std::string opaque_tag(std::string tag) {
    if (tag.rfind("W/", 0) == 0) tag.erase(0, 2);
    return tag;
}

}  // namespace

std::string file_etag(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(ErrorCode::io, "cannot read " + path);
    Sha256 h;
    std::vector<char> buf(kHashChunkBytes);
    while (in) {
        in.read(buf.data(), static_cast<std::streamsize>(buf.size()));
        h.update(buf.data(), static_cast<size_t>(in.gcount()));
    }
    if (in.bad()) throw Error(ErrorCode::io, "cannot read " + path);
    // Built by appends: GCC 12 warns falsely (-Wrestrict) on "\"" + std::string&&.
    std::string tag = "\"";
    tag += h.hex();
    tag += '"';
    return tag;
}

std::string render_etag(const std::string& file_sha256, const std::string& options_json) {
    // Hashed once per process (tens of MB, some tens of milliseconds).
    static const std::string build = file_etag("/proc/self/exe");
    // Appended piecewise: GCC 12 warns falsely (-Wrestrict) about a chain of operator+ here.
    std::string key = build;
    key += '\n';
    key += file_sha256;
    key += '\n';
    key += options_json;
    std::string tag = "\"";
    tag += sha256_hex(key);
    tag += '"';
    return tag;
}

bool if_none_match_matches(const std::string& header, const std::string& etag) {
    if (trimmed(header, 0, header.size()) == "*") return true;
    const std::string mine = opaque_tag(etag);
    // Entity tags hold no commas (RFC 9110 §8.8.3: etagc excludes them), so a split at commas is exact.
    for (size_t start = 0; start <= header.size();) {
        const size_t comma = std::min(header.find(',', start), header.size());
        if (opaque_tag(trimmed(header, start, comma)) == mine) return true;
        start = comma + 1;
    }
    return false;
}

}  // namespace nurbsrt::server
