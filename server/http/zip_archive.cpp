// ZIP archives in memory (zip_archive.h).
#include "server/http/zip_archive.h"

#include <zip.h>

#include <ctime>
#include <memory>

#include "core/error.h"

namespace nurbsrt::server {
namespace {

// 1980-01-01 00:00 UTC, the first time a ZIP entry's DOS date can hold: a
// fixed time keeps the archive's bytes a function of its entries alone.
constexpr time_t kEntryTime = 315532800;

[[noreturn]] void fail(const std::string& what, zip_error_t* error) {
    const std::string detail = error ? zip_error_strerror(error) : "";
    throw Error(ErrorCode::internal, "cannot make the ZIP archive: " + what + (detail.empty() ? "" : ": " + detail));
}

}  // namespace

std::string zip_archive(const std::vector<ZipEntry>& entries) {
    zip_error_t error;
    zip_error_init(&error);
    // The archive is written into this growing buffer source, which outlives zip_close.
    zip_source_t* buffer = zip_source_buffer_create(nullptr, 0, 0, &error);
    if (!buffer) fail("buffer", &error);
    const std::unique_ptr<zip_source_t, decltype(&zip_source_free)> keep_buffer(buffer, zip_source_free);
    zip_t* archive = zip_open_from_source(buffer, ZIP_TRUNCATE, &error);
    if (!archive) fail("open", &error);
    zip_source_keep(buffer);  // the archive now holds it too; zip_close drops that hold
    for (const ZipEntry& e : entries) {
        // The data is copied by libzip only at zip_close, from e.bytes, which lives until then.
        zip_source_t* data = zip_source_buffer(archive, e.bytes.data(), e.bytes.size(), 0);
        const zip_int64_t index = data ? zip_file_add(archive, e.name.c_str(), data, ZIP_FL_ENC_UTF_8) : -1;
        if (index < 0) {
            if (data) zip_source_free(data);
            zip_discard(archive);
            fail("entry '" + e.name + "'", nullptr);
        }
        const auto i = static_cast<zip_uint64_t>(index);
        if (zip_set_file_compression(archive, i, e.deflate ? ZIP_CM_DEFLATE : ZIP_CM_STORE, 0) != 0 ||
            zip_file_set_mtime(archive, i, kEntryTime, 0) != 0) {
            zip_discard(archive);
            fail("entry '" + e.name + "'", nullptr);
        }
    }
    if (zip_close(archive) != 0) {
        zip_error_t* e = zip_get_error(archive);
        const std::string detail = zip_error_strerror(e);
        zip_discard(archive);
        throw Error(ErrorCode::internal, "cannot make the ZIP archive: close: " + detail);
    }
    if (zip_source_open(buffer) != 0) fail("read back", zip_source_error(buffer));
    std::string out;
    char chunk[1 << 16];
    for (zip_int64_t n; (n = zip_source_read(buffer, chunk, sizeof chunk)) > 0;)
        out.append(chunk, static_cast<size_t>(n));
    zip_source_close(buffer);
    return out;
}

}  // namespace nurbsrt::server
