// One owner per data directory. With SQLite the job queue, the scratch files
// and the stored files of a data directory belong to one process: a second
// `serve` on it would recover (requeue) the first one's running jobs at its
// start and clean its scratch files. An exclusive flock(2) on DATA_DIR/serve.lock,
// taken before anything in the directory is touched, makes the second one stop
// with a message naming the holder. The lock goes with the process (also when
// it is killed), so a crash never leaves a stale lock behind. Instances that share
// a PostgreSQL job store share the directory by design and take no lock.
#pragma once

#include <string>

namespace nurbsrt::server {

class DataDirLock {
public:
    // Throws Error(io) when another process holds the lock, naming the directory
    // and the holder's pid, or when the lock file cannot be made.
    explicit DataDirLock(const std::string& data_dir);
    ~DataDirLock();
    DataDirLock(const DataDirLock&) = delete;
    DataDirLock& operator=(const DataDirLock&) = delete;

private:
    int fd_ = -1;
};

}  // namespace nurbsrt::server
