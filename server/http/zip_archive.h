// A ZIP archive (PKWARE APPNOTE 6.3.x) of named in-memory files, built with
// libzip: the answer of a conversion whose format writes more than one file
// (OBJ and its .mtl).
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace nurbsrt::server {

// The archive's bytes: each (name, content) deflated, in order. Throws
// nurbsrt::Error (internal) when libzip fails.
std::string zip_archive(const std::vector<std::pair<std::string, std::string>>& files);

}  // namespace nurbsrt::server
