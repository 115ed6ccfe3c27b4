// The service's private scratch directory (DATA_DIR/tmp, mode 0700) and the
// temporary files in it. Names are generated (never taken from a request);
// files are removed when their TempFile goes away, and leftovers of an earlier
// run (files with those generated names only) are removed at start. Instances
// sharing DATA_DIR (a shared job store) each get DATA_DIR/tmp/<instance>/,
// held by a lock (flock) on DATA_DIR/tmp/<instance>.lock while they live: at
// start, only directories whose lock nobody holds (dead instances) are removed.
#pragma once

#include <string>

namespace nurbsrt::server {

class TempFile {
public:
    TempFile() = default;
    explicit TempFile(std::string path) : path_(std::move(path)) {}
    ~TempFile();
    TempFile(TempFile&& o) noexcept : path_(std::move(o.path_)) { o.path_.clear(); }
    TempFile& operator=(TempFile&&) = delete;
    TempFile(const TempFile&) = delete;
    TempFile& operator=(const TempFile&) = delete;
    const std::string& path() const { return path_; }

private:
    std::string path_;
};

class ScratchDir {
public:
    // Creates DATA_DIR and DATA_DIR/tmp (0700) and removes our leftovers from it;
    // with an instance, DATA_DIR/tmp/<instance> and dead instances' directories.
    // Throws Error(io) when that is not possible.
    explicit ScratchDir(const std::string& data_dir, const std::string& instance = {});
    ~ScratchDir();
    ScratchDir(const ScratchDir&) = delete;
    ScratchDir& operator=(const ScratchDir&) = delete;
    const std::string& path() const { return dir_; }

    // A new empty file named `<stem>-XXXXXX<suffix>` (suffix such as ".png").
    TempFile create(const char* stem, const char* suffix) const;
    // A new file holding `bytes`.
    TempFile write(const char* stem, const char* suffix, const std::string& bytes) const;

private:
    void own_instance_dir(const std::string& instance);
    std::string dir_;
    int lock_fd_ = -1;
};

// Reads a whole file (throws Error(io)).
std::string read_file_bytes(const std::string& path);

}  // namespace nurbsrt::server
