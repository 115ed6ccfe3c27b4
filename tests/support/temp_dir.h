// A fresh directory under the system's temporary directory for one test,
// removed with all it holds when the object goes (made writable first: some
// tests take the write permission away to provoke errors).
#pragma once

#include <stdlib.h>
#include <sys/stat.h>

#include <filesystem>
#include <stdexcept>
#include <string>

namespace nurbsrt::test {

class TempDir {
public:
    explicit TempDir(const std::string& prefix) {
        std::string templ = (std::filesystem::temp_directory_path() / (prefix + "-XXXXXX")).string();
        if (!::mkdtemp(templ.data())) throw std::runtime_error("mkdtemp failed for " + templ);
        path_ = templ;
    }
    ~TempDir() {
        ::chmod(path_.c_str(), 0700);
        std::error_code ignored;
        std::filesystem::remove_all(path_, ignored);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;

    const std::string& path() const { return path_; }

private:
    std::string path_;
};

}  // namespace nurbsrt::test
