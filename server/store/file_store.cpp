#include "server/store/file_store.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "core/error.h"
#include "server/store/durable_file.h"
#include "server/store/page_cursor.h"
#include "server/common/request_log.h"
#include "server/common/service_error.h"

namespace nurbsrt::server {
namespace fs = std::filesystem;
namespace {

using nlohmann::json;

constexpr const char* kContentSuffix = ".cad";
constexpr const char* kRecordSuffix = ".json";
constexpr const char* kTempPrefix = ".tmp-";
// A write in flight takes at most the time to copy an upload to the disk; an
// hour is far beyond that, so older temporary files (and bytes whose record
// was never renamed into place) are leftovers of a killed instance.
constexpr auto kLeftoverAge = std::chrono::hours(1);

// Writes `bytes` to `path` as a whole or not at all: a temporary file in the
// same directory, flushed to the disk, renamed over `path` (POSIX rename(2):
// readers see the old or the new file, never part of one), then the directory
// flushed so the new name survives a power loss too.
void write_atomically(const std::string& dir, const std::string& path, const std::string& bytes) {
    const std::string tmp = dir + "/" + kTempPrefix + new_request_id();
    try {
        write_durably(tmp, bytes);
    } catch (const Error&) {
        std::error_code ec;
        fs::remove(tmp, ec);
        throw Error(ErrorCode::io, "cannot write a stored file (disk full?)");
    }
    std::error_code ec;
    fs::rename(tmp, path, ec);
    if (ec) {
        fs::remove(tmp, ec);
        throw Error(ErrorCode::io, "cannot write a stored file (disk full?)");
    }
    sync_dir(dir);
}

json record_json(const StoredFile& f) {
    json summary = json::parse(f.summary_json, nullptr, false);
    if (summary.is_discarded()) summary = json::object();
    return {{"id", f.id},        {"format", f.format},         {"filename", f.filename},
            {"bytes", f.bytes},  {"created_ms", f.created_ms}, {"pinned", f.pinned},
            {"summary", summary}};
}

std::optional<StoredFile> read_record(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return std::nullopt;
    const json j = json::parse(std::string(std::istreambuf_iterator<char>(in), {}), nullptr, false);
    if (j.is_discarded() || !j.is_object()) return std::nullopt;
    try {
        StoredFile f;
        f.id = j.at("id").get<std::string>();
        f.format = j.at("format").get<std::string>();
        f.filename = j.at("filename").get<std::string>();
        f.bytes = j.at("bytes").get<int64_t>();
        f.created_ms = j.at("created_ms").get<int64_t>();
        f.pinned = j.at("pinned").get<bool>();
        f.summary_json = j.value("summary", json::object()).dump();
        return f;
    } catch (const json::exception&) {
        return std::nullopt;  // a record from a newer or broken writer names no file
    }
}

}  // namespace

bool FileStore::valid_id(const std::string& id) {
    constexpr size_t kSha256HexDigits = 64;
    return id.size() == kSha256HexDigits &&
           std::all_of(id.begin(), id.end(), [](char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'); });
}

std::string FileStore::content_path(const std::string& id) const { return dir_ + "/" + id + kContentSuffix; }

void FileStore::write_record(const StoredFile& file) const {
    write_atomically(dir_, dir_ + "/" + file.id + kRecordSuffix,
                     record_json(file).dump(-1, ' ', false, json::error_handler_t::replace));
}

FileStore::PutOutcome FileStore::put(StoredFile& file, const std::string& bytes) {
    std::lock_guard<std::mutex> lock(m_);
    if (std::optional<StoredFile> existing = get(file.id)) {
        if (file.pinned && !existing->pinned) {
            existing->pinned = true;
            write_record(*existing);
        }
        file = *existing;
        return PutOutcome::existing;
    }
    if (used_bytes() + static_cast<int64_t>(bytes.size()) > max_bytes_) return PutOutcome::over_quota;
    std::error_code ec;
    fs::create_directories(dir_, ec);
    if (ec) throw Error(ErrorCode::io, "cannot create the directory of stored files");
    write_atomically(dir_, content_path(file.id), bytes);  // the bytes first: a record always has them
    write_record(file);
    return PutOutcome::created;
}

std::optional<StoredFile> FileStore::get(const std::string& id) const {
    if (!valid_id(id)) return std::nullopt;
    return read_record(dir_ + "/" + id + kRecordSuffix);
}

StoredContent FileStore::open(const std::string& id) const {
    const auto missing = [&] {
        return ServiceError(ServiceCode::not_found,
                            "no stored file '" + id.substr(0, 80) + "' (POST /v1/files stores one)");
    };
    std::optional<StoredFile> f = get(id);
    if (!f) throw missing();
    std::ifstream in(content_path(id), std::ios::binary | std::ios::ate);
    if (!in) throw missing();  // removed just now
    // Sized once and read in one call: through istreambuf_iterator a byte at a
    // time, a 1.9 MB file took 5-10 ms of every render by file_id.
    std::string bytes(static_cast<size_t>(in.tellg()), '\0');
    in.seekg(0);
    if (!in.read(bytes.data(), static_cast<std::streamsize>(bytes.size())))
        throw Error(ErrorCode::io, "cannot read stored file '" + id + "'");
    return {std::move(*f), std::make_shared<const std::string>(std::move(bytes))};
}

bool FileStore::remove(const std::string& id) {
    if (!valid_id(id)) return false;
    std::lock_guard<std::mutex> lock(m_);
    std::error_code ec;
    // The record first: from then on the file is gone for every reader.
    const bool removed = fs::remove(dir_ + "/" + id + kRecordSuffix, ec);
    fs::remove(content_path(id), ec);
    return removed;
}

std::optional<StoredFile> FileStore::set_pinned(const std::string& id, bool pinned) {
    std::lock_guard<std::mutex> lock(m_);
    std::optional<StoredFile> f = get(id);
    if (!f) return std::nullopt;
    if (f->pinned != pinned) {
        f->pinned = pinned;
        write_record(*f);
    }
    return f;
}

std::vector<StoredFile> FileStore::all() const {
    std::vector<StoredFile> out;
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(dir_, ec)) {
        const std::string name = entry.path().filename().string();
        const std::string suffix = kRecordSuffix;
        if (name.size() <= suffix.size() || name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0)
            continue;
        const std::string id = name.substr(0, name.size() - suffix.size());
        if (!valid_id(id)) continue;
        if (std::optional<StoredFile> f = read_record(entry.path().string()); f && f->id == id) out.push_back(*f);
    }
    return out;
}

FilePage FileStore::list(bool newest_first, int limit, const std::optional<std::string>& cursor) const {
    std::optional<std::pair<int64_t, std::string>> after;
    if (cursor) {
        PageCursor c = parse_page_cursor(*cursor, newest_first, true);
        if (!valid_id(c.id))
            throw Error(ErrorCode::invalid_argument, "invalid cursor: use next_cursor of a previous page");
        after = std::pair{c.key, std::move(c.id)};
    }
    std::vector<StoredFile> files = all();
    const auto key = [](const StoredFile& f) { return std::make_pair(f.created_ms, f.id); };
    std::sort(files.begin(), files.end(), [&](const StoredFile& a, const StoredFile& b) {
        return newest_first ? key(a) > key(b) : key(a) < key(b);
    });
    FilePage page;
    for (const StoredFile& f : files) {
        if (after && (newest_first ? key(f) >= *after : key(f) <= *after)) continue;
        if (static_cast<int>(page.files.size()) == limit) {
            page.next_cursor = format_page_cursor(newest_first, page.files.back().created_ms, page.files.back().id);
            break;
        }
        page.files.push_back(f);
    }
    return page;
}

int64_t FileStore::used_bytes() const {
    int64_t total = 0;
    for (const StoredFile& f : all()) total += f.bytes;
    return total;
}

int FileStore::expire(int64_t before_ms) {
    int removed = 0;
    for (const StoredFile& f : all())
        if (!f.pinned && f.created_ms < before_ms && remove(f.id)) ++removed;
    std::lock_guard<std::mutex> lock(m_);
    using clock = fs::file_time_type::clock;
    const auto now = clock::now();
    std::error_code ec;
    std::vector<fs::path> leftovers;
    for (const auto& entry : fs::directory_iterator(dir_, ec)) {
        const std::string name = entry.path().filename().string();
        const bool temp = name.rfind(kTempPrefix, 0) == 0;
        const bool orphan = entry.path().extension() == kContentSuffix &&
                            !fs::exists(dir_ + "/" + entry.path().stem().string() + kRecordSuffix);
        if (!temp && !orphan) continue;
        const auto t = fs::last_write_time(entry.path(), ec);
        if (!ec && now - t > std::chrono::duration_cast<clock::duration>(kLeftoverAge))
            leftovers.push_back(entry.path());
    }
    for (const fs::path& p : leftovers) fs::remove(p, ec);
    return removed;
}

}  // namespace nurbsrt::server
