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

// `message` with every path of a file in the scratch directory `dir` replaced by
// what the file is to the client ("the upload", "the converted file", "a scratch
// file"): the generated names (upload-qM81Gn.cad) mean nothing to a client and
// are the service's business.
std::string with_scratch_files_named(std::string message, const std::string& dir);

}  // namespace nurbsrt::server
