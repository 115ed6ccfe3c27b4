// Error messages shown to clients must not name the service's private files: an
// error from a child process or the file system may carry the path of an upload
// or a job directory. One helper for every place that forwards such a message.
#pragma once

#include <initializer_list>
#include <string>

namespace nurbsrt::server {

// `message` with every occurrence of each prefix erased, in the order given
// (give a longer prefix before one it contains).
std::string without_prefixes(std::string message, std::initializer_list<std::string> prefixes);

}  // namespace nurbsrt::server
