#include "server/common/scratch.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.h"

namespace nurbsrt::server {

namespace fs = std::filesystem;

TempFile::~TempFile() {
    if (!path_.empty()) unlink(path_.c_str());
}

ScratchDir::~ScratchDir() {
    if (lock_fd_ >= 0) close(lock_fd_);
}

void ScratchDir::own_instance_dir(const std::string& instance) {
    std::error_code ec;
    // Directories of instances that are gone: their lock is free.
    for (const auto& entry : fs::directory_iterator(dir_, ec)) {
        if (entry.path().extension() != ".lock") continue;
        const int fd = ::open(entry.path().c_str(), O_RDWR | O_CLOEXEC);
        if (fd < 0) continue;
        if (flock(fd, LOCK_EX | LOCK_NB) == 0) {
            fs::path dead = entry.path();
            fs::remove_all(dead.replace_extension(), ec);
            fs::remove(entry.path(), ec);
        }
        close(fd);
    }
    const std::string lock = dir_ + "/" + instance + ".lock";
    lock_fd_ = ::open(lock.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0600);
    if (lock_fd_ < 0 || flock(lock_fd_, LOCK_EX | LOCK_NB) != 0)
        throw Error(ErrorCode::io,
                    "cannot lock '" + lock + "': is another instance running with the id " + instance + "?");
    dir_ += "/" + instance;
    fs::create_directories(dir_, ec);
    if (ec || chmod(dir_.c_str(), 0700) != 0) throw Error(ErrorCode::io, "cannot create '" + dir_ + "'");
}

ScratchDir::ScratchDir(const std::string& data_dir, const std::string& instance) {
    std::error_code ec;
    fs::create_directories(data_dir, ec);
    if (ec) throw Error(ErrorCode::io, "cannot create data dir '" + data_dir + "': " + ec.message());
    dir_ = (fs::absolute(data_dir) / "tmp").string();
    fs::create_directories(dir_, ec);
    if (ec) throw Error(ErrorCode::io, "cannot create '" + dir_ + "': " + ec.message());
    if (chmod(dir_.c_str(), 0700) != 0)
        throw Error(ErrorCode::io, "cannot make '" + dir_ + "' private: " + std::strerror(errno));
    if (!instance.empty()) own_instance_dir(instance);
    // Remove leftovers of an earlier run: only files with the names we generate,
    // so a data dir pointed at a shared place never loses anything else.
    static const char* ours[] = {"upload-",         "render-",          "converted-",
                                 "nurbsrt-import-", "nurbsrt-convert-", "nurbsrt-file-"};
    for (const auto& entry : fs::directory_iterator(dir_, ec)) {
        const std::string name = entry.path().filename().string();
        for (const char* prefix : ours)
            if (name.rfind(prefix, 0) == 0 && entry.is_regular_file(ec)) {
                fs::remove(entry.path(), ec);
                break;
            }
    }
}

TempFile ScratchDir::create(const char* stem, const char* suffix) const {
    std::string tmpl = dir_ + "/" + stem + "-XXXXXX" + suffix;
    const int fd = mkstemps(tmpl.data(), static_cast<int>(std::strlen(suffix)));
    if (fd < 0) throw Error(ErrorCode::io, "cannot create a scratch file: " + std::string(std::strerror(errno)));
    close(fd);
    return TempFile(tmpl);
}

TempFile ScratchDir::write(const char* stem, const char* suffix, const std::string& bytes) const {
    TempFile f = create(stem, suffix);
    std::ofstream out(f.path(), std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    out.close();
    if (!out) throw Error(ErrorCode::io, "cannot write a scratch file (disk full?)");
    return f;
}

std::string read_file_bytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(ErrorCode::io, "cannot read a scratch file");
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

}  // namespace nurbsrt::server
