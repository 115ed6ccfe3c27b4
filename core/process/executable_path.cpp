// The running program's own path (see executable_path.h).
#include "core/process/executable_path.h"

#include <unistd.h>

#include "core/error.h"

namespace nurbsrt {

std::string executable_path() {
    char buf[4096];
    const ssize_t n = readlink("/proc/self/exe", buf, sizeof(buf) - 1);
    if (n <= 0) throw Error(ErrorCode::internal, "cannot resolve /proc/self/exe");
    return std::string(buf, static_cast<size_t>(n));
}

std::string beside_executable(const std::string& name) {
    const std::string self = executable_path();
    return self.substr(0, self.rfind('/') + 1) + name;
}

}  // namespace nurbsrt
