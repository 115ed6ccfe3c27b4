// Where the running program lives: the files installed beside it (the import
// worker, the image writer module) are found from there.
#pragma once

#include <string>

namespace nurbsrt {

// The running program's own file (/proc/self/exe). Throws Error(internal) when
// it cannot be resolved.
std::string executable_path();

// The file `name` in the running program's directory.
std::string beside_executable(const std::string& name);

}  // namespace nurbsrt
