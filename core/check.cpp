#include "core/check.h"

#include <string>

#include "core/error.h"

namespace nurbsrt {

void check_failed(const char* condition, const char* file, int line) {
    // The file's name only: the build's directories are none of a client's business.
    const std::string path = file;
    const std::string name = path.substr(path.find_last_of('/') + 1);
    throw Error(ErrorCode::internal,
                std::string("invariant broken: ") + condition + " (" + name + ":" + std::to_string(line) + ")");
}

}  // namespace nurbsrt
