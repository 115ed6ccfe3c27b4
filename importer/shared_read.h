// One read of a CAD file for every use of it in this process: the file
// worker (importer/isolated.h, run_file_worker) imports a file for its renders
// and writes all its conversions, and STEP/IGES parsing is most of each of
// those. While a SharedRead lives, every read of its path (import_file,
// convert_file and its writers) is served from the first one, including its
// error: a file that cannot be read is tried once. OCCT-free on purpose.
#pragma once

#include <string>

namespace nurbsrt {

class SharedRead {
public:
    explicit SharedRead(const std::string& path);
    ~SharedRead();  // closes the kept XDE document
    SharedRead(const SharedRead&) = delete;
    SharedRead& operator=(const SharedRead&) = delete;

    // Uses share the shape as the last one left it, with the triangulations its
    // meshing added: a mesher finding them keeps them instead of meshing at its
    // own parameters, and an exact writer (BREP) writes them. Removes them
    // (BRepTools::Clean); convert_file does so before each conversion, so that
    // every output is what a lone conversion writes.
    void forget_meshes();

    // How many times the file was really read (0 or 1) and what that cost.
    int reads() const;
    double read_ms() const;
    // How many reads were asked for: the read itself and those it served.
    int uses() const;
};

}  // namespace nurbsrt
