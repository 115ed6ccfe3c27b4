#include "server/http/zip_archive.h"

#include <memory>

#include <zip.h>

#include "core/error.h"

namespace nurbsrt::server {
namespace {

[[noreturn]] void zip_failed(const std::string& what, zip_error_t* error) {
    const std::string text = error ? zip_error_strerror(error) : "unknown error";
    throw Error(ErrorCode::internal, "ZIP archive: " + what + ": " + text);
}

}  // namespace

std::string zip_archive(const std::vector<std::pair<std::string, std::string>>& files) {
    zip_error_t error;
    zip_error_init(&error);
    // An in-memory source to write into, kept past zip_close to read it back.
    zip_source_t* buffer = zip_source_buffer_create(nullptr, 0, 0, &error);
    if (!buffer) zip_failed("buffer", &error);
    zip_source_keep(buffer);
    const std::unique_ptr<zip_source_t, decltype(&zip_source_free)> keep(buffer, zip_source_free);
    zip_t* archive = zip_open_from_source(buffer, ZIP_TRUNCATE, &error);
    if (!archive) zip_failed("open", &error);
    for (const auto& [name, content] : files) {
        // libzip reads the content when the archive is closed: `files` outlives that.
        zip_source_t* s = zip_source_buffer(archive, content.data(), content.size(), 0);
        if (!s || zip_file_add(archive, name.c_str(), s, ZIP_FL_ENC_UTF_8) < 0) {
            if (s) zip_source_free(s);
            const std::string what = "adding '" + name + "'";
            zip_discard(archive);
            zip_failed(what, nullptr);
        }
    }
    if (zip_close(archive) < 0) {
        const std::string text = zip_strerror(archive);
        zip_discard(archive);
        throw Error(ErrorCode::internal, "ZIP archive: close: " + text);
    }
    zip_stat_t st;
    if (zip_source_stat(buffer, &st) < 0 || zip_source_open(buffer) < 0) zip_failed("reading back", nullptr);
    std::string bytes(static_cast<size_t>(st.size), '\0');
    const zip_int64_t n = zip_source_read(buffer, bytes.data(), st.size);
    zip_source_close(buffer);
    if (n < 0 || static_cast<zip_uint64_t>(n) != st.size) zip_failed("reading back", nullptr);
    return bytes;
}

}  // namespace nurbsrt::server
