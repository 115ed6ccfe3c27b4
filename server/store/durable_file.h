// Files that must outlive a crash or a power loss as a database row does: an
// accepted job's inputs, a finished output's artifact, a stored file.
#pragma once

#include <string>

namespace nurbsrt::server {

// Creates or truncates `path`, writes `bytes` whole and flushes them to the
// disk (fsync) before returning. Throws Error(io) naming only the file's name.
void write_durably(const std::string& path, const std::string& bytes);

// Flushes a directory, so that names created or renamed in it survive a power
// loss too (POSIX: fsync on the file does not cover its directory entry).
void sync_dir(const std::string& dir);

}  // namespace nurbsrt::server
