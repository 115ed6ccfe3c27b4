// Stored files (POST /v1/files): CAD files uploaded once and then rendered,
// converted or used by jobs by id. Kept in DATA_DIR/files/ by content address:
// <sha256>.cad holds the bytes and <sha256>.json the metadata beside them,
// each written to a temporary file and renamed into place (rename is atomic
// within a directory, POSIX rename(2)), the bytes first, so a metadata file
// always has its bytes.
//
// Why beside the bytes and not in the job store: the data directory is what
// every instance of a scale-out already shares (the job store may be SQLite,
// one process, or PostgreSQL, many), so one implementation serves both
// backends with no schema migration; the bytes and their record live and die
// together (a backup, a copied volume, a removed file never disagree with a
// database row); and a record changes only by its pin flag, which a rename
// replaces whole. The price: listing and the quota scan the directory
// (O(stored files)), fine for the thousands of files a quota of a few GiB
// holds. Thread-safe within a process; between instances the quota is checked
// without a lock, so simultaneous uploads on different instances may overshoot
// it by one upload each. Free of HTTP and JSON headers.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "server/common/sha256.h"

namespace nurbsrt::server {

struct StoredFile {
    std::string id;        // the SHA-256 of the bytes, 64 lowercase hex digits
    std::string format;    // STEP | IGES (by content)
    std::string filename;  // the client's label only (never a path)
    int64_t bytes = 0;
    int64_t created_ms = 0;    // Unix ms
    bool pinned = false;       // pinned files never expire
    std::string summary_json;  // the import summary (faces, units, bbox, colors) as a JSON object's text
};

// A stored file with its content, for a render, conversion or job.
struct StoredContent {
    StoredFile file;
    std::shared_ptr<const std::string> bytes;
};

struct FilePage {
    std::vector<StoredFile> files;
    std::optional<std::string> next_cursor;  // opaque; set when more may follow
};

class FileStore {
public:
    FileStore(std::string dir, int64_t max_bytes) : dir_(std::move(dir)), max_bytes_(max_bytes) {}

    // 64 lowercase hex digits: anything else names no stored file (and never a path).
    static bool valid_id(const std::string& id);

    enum class PutOutcome { created, existing, over_quota };
    // Stores `bytes` under file.id (= sha256_hex(bytes), set by the caller with
    // the other fields). `existing`: the same bytes were already stored; `file`
    // becomes that record (pinned when `file.pinned` asked for it).
    // `over_quota`: storing them would exceed max_bytes; nothing is written.
    // Throws Error(io) when the directory cannot be written.
    PutOutcome put(StoredFile& file, const std::string& bytes);
    std::optional<StoredFile> get(const std::string& id) const;
    // The record and bytes; throws Error(not_found) naming the id when there are none.
    StoredContent open(const std::string& id) const;
    // The path of the bytes of a stored file (which may be removed at any time).
    std::string content_path(const std::string& id) const;
    // False when there was no such file.
    bool remove(const std::string& id);
    // The updated record, or nullopt when there is no such file.
    std::optional<StoredFile> set_pinned(const std::string& id, bool pinned);
    // Files by creation time (then id), newest or oldest first, after `cursor`.
    // Throws Error(invalid_argument) for a cursor not made by this order.
    FilePage list(bool newest_first, int limit, const std::optional<std::string>& cursor) const;
    // Bytes of all stored files (what the quota counts).
    int64_t used_bytes() const;
    int64_t max_bytes() const { return max_bytes_; }
    // Removes unpinned files created before `before_ms`, and leftovers of
    // writes cut short (temporary files, bytes without a record) older than an
    // hour. Returns how many stored files were removed.
    int expire(int64_t before_ms);

private:
    std::vector<StoredFile> all() const;
    void write_record(const StoredFile& file) const;

    const std::string dir_;
    const int64_t max_bytes_;
    mutable std::mutex m_;  // one writer at a time in this process: the quota check and the write go together
};

}  // namespace nurbsrt::server
