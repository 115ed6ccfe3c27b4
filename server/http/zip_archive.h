// A ZIP archive made in memory (PKWARE APPNOTE 6.3, through libzip): the answer
// of a request that makes several files, such as a render's views with layout
// "separate", or a conversion whose format writes two files (OBJ and its .mtl).
#pragma once

#include <string>
#include <vector>

namespace nurbsrt::server {

inline constexpr const char* kZipMediaType = "application/zip";

struct ZipEntry {
    std::string name;  // a path inside the archive, UTF-8
    std::string bytes;
    // Deflated (text: an OBJ and its .mtl) or stored (images, compressed already).
    bool deflate = false;
};

// The archive's bytes, entries in order. Every entry carries the same fixed time, so the same
// entries make the same bytes (an ETag of a stored file's render stays valid).
// Throws Error(internal) where libzip fails.
std::string zip_archive(const std::vector<ZipEntry>& entries);

}  // namespace nurbsrt::server
