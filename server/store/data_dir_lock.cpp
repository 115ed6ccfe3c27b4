#include "server/store/data_dir_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

#include "core/error.h"

namespace nurbsrt::server {
namespace {

// The pid the holder wrote into the lock file ("" if unreadable).
std::string holder_pid(int fd) {
    char text[32] = {};
    const ssize_t n = ::pread(fd, text, sizeof text - 1, 0);
    std::string pid(text, n > 0 ? static_cast<size_t>(n) : 0);
    while (!pid.empty() && (pid.back() == '\n' || pid.back() == ' ')) pid.pop_back();
    return pid;
}

}  // namespace

DataDirLock::DataDirLock(const std::string& data_dir) {
    std::error_code ec;
    std::filesystem::create_directories(data_dir, ec);
    const std::string path = data_dir + "/serve.lock";
    fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) throw Error(ErrorCode::io, "cannot open " + path + ": " + std::strerror(errno));
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
        const int err = errno;
        const std::string pid = holder_pid(fd_);
        ::close(fd_);
        fd_ = -1;
        if (err != EWOULDBLOCK) throw Error(ErrorCode::io, "cannot lock " + path + ": " + std::strerror(err));
        throw Error(ErrorCode::io, "the data directory " + data_dir + " is in use by another nurbsrt serve" +
                                       (pid.empty() ? std::string() : " (pid " + pid + ")") +
                                       ": one instance owns a data directory with the SQLite job store; give this "
                                       "one another --data-dir, or share a PostgreSQL --job-store");
    }
    const std::string pid = std::to_string(::getpid()) + "\n";
    if (::ftruncate(fd_, 0) != 0 || ::pwrite(fd_, pid.data(), pid.size(), 0) != static_cast<ssize_t>(pid.size()))
        throw Error(ErrorCode::io, "cannot write " + path + ": " + std::strerror(errno));
}

DataDirLock::~DataDirLock() {
    if (fd_ >= 0) ::close(fd_);  // releases the lock; the file stays (removing it would race a starting instance)
}

}  // namespace nurbsrt::server
