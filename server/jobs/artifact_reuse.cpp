#include "server/jobs/artifact_reuse.h"

#include <nlohmann/json.hpp>

#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.h"
#include "server/common/request_log.h"
#include "server/common/sha256.h"
#include "server/store/durable_file.h"

namespace nurbsrt::server {
namespace fs = std::filesystem;
namespace {

// A key is 64 hex digits: the only names the index holds, besides its temporary ones.
bool valid_reuse_key(const std::string& key) {
    if (key.size() != 64) return false;
    for (const char c : key)
        if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) return false;
    return true;
}

// Puts the file `from` at `to` (replacing it): a hard link where the file
// system allows one (no copy of the bytes), else a copy.
void place(const std::string& from, const std::string& to) {
    std::error_code ec;
    fs::remove(to, ec);
    if (::link(from.c_str(), to.c_str()) == 0) return;
    fs::copy_file(from, to, fs::copy_options::overwrite_existing, ec);
    if (ec) throw Error(ErrorCode::io, "cannot place a reused artifact: " + ec.message());
}

}  // namespace

ArtifactReuse::ArtifactReuse(std::string dir) : dir_(std::move(dir)) {
    std::error_code ec;
    fs::create_directories(dir_, ec);
    if (ec) throw Error(ErrorCode::io, "cannot create the artifact reuse directory " + dir_);
}

std::string ArtifactReuse::key(const std::string& content_sha256, const JobOutput& out, const std::string& name) {
    const std::string& artifact = name.empty() ? out.artifact : name;
    Sha256 h;
    h.update(content_sha256);
    h.update("\0kind\n", 6);
    h.update(output_kind_name(out.kind));
    h.update("\0options\n", 9);
    h.update(out.options_json);
    h.update("\0extension\n", 11);
    h.update(artifact.substr(artifact.find('.') + 1));
    return h.hex();
}

void ArtifactReuse::remember(const std::string& key, const std::string& artifact_path,
                             const std::string& result_json) noexcept {
    if (!valid_reuse_key(key)) return;
    try {
        // The artifact first, the result last: an entry counts once its result is there.
        const std::string tmp = dir_ + "/tmp-" + new_request_id();
        place(artifact_path, tmp + ".art");
        fs::rename(tmp + ".art", dir_ + "/" + key + ".art");
        write_durably(tmp + ".json", result_json);
        fs::rename(tmp + ".json", dir_ + "/" + key + ".json");
    } catch (const std::exception& e) {
        log_event("artifact_reuse_not_kept", nlohmann::json{{"key", key}, {"error", e.what()}}.dump(
                                                 -1, ' ', false, nlohmann::json::error_handler_t::replace));
    }
}

std::optional<std::string> ArtifactReuse::recall(const std::string& key, const std::string& dest) const {
    if (!valid_reuse_key(key)) return std::nullopt;
    std::ifstream in(dir_ + "/" + key + ".json", std::ios::binary);
    if (!in) return std::nullopt;
    std::ostringstream result;
    result << in.rdbuf();
    try {
        place(dir_ + "/" + key + ".art", dest);
    } catch (const Error&) {
        return std::nullopt;  // expired between the two reads, or a disk that refuses: made anew
    }
    return result.str();
}

int ArtifactReuse::expire(int64_t before_ms) noexcept {
    int removed = 0;
    std::error_code ec;
    // before_ms is on the system clock, file times on the file clock: as an age from now.
    const auto cutoff = fs::file_time_type::clock::now() - std::chrono::milliseconds(unix_now_ms() - before_ms);
    for (const auto& entry : fs::directory_iterator(dir_, ec)) {
        const std::string name = entry.path().filename().string();
        const auto t = fs::last_write_time(entry.path(), ec);
        if (ec || t >= cutoff) continue;
        if (name.rfind("tmp-", 0) == 0) {  // left by a remember() cut short
            fs::remove(entry.path(), ec);
            continue;
        }
        if (name.size() < 5 || name.compare(name.size() - 5, 5, ".json") != 0) continue;
        const std::string stem = entry.path().string().substr(0, entry.path().string().size() - 5);
        fs::remove(entry.path(), ec);  // the result first: the entry is gone before its artifact
        fs::remove(stem + ".art", ec);
        ++removed;
    }
    return removed;
}

}  // namespace nurbsrt::server
