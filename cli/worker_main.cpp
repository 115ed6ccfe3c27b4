// nurbsrt-worker: the child process of an isolated import or conversion
// (importer/isolated.h), run by the service as
//   nurbsrt-worker import-worker IN OUT [name=value ...]
//   nurbsrt-worker convert-worker IN OUT REPORT [--name=value ...]
//   nurbsrt-worker file-worker IN SUMMARY SCENE|- [OUT REPORT]... [name=value ...]
// the same arguments as the hidden subcommands of `nurbsrt` itself.
//
// Why a program of its own: a child pays the dynamic linking of everything its
// executable links before it reads a byte. `nurbsrt` links OSMesa (LLVM), the
// HTTP and database clients and Embree besides OCCT (107 libraries; OpenImageIO
// is a module it loads only to write images, renderer/image_module.h); the child
// needs only OCCT. Linked with --as-needed, this program starts in a fraction of
// the time (figures in importer/isolated.cpp), and every upload the service
// imports waits for that start.
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

#include "importer/isolated.h"
#include "core/error.h"

int main(int argc, char** argv) {
    // Exit status 2 for a malformed command line, as `nurbsrt` uses; the parent
    // reads the error file the worker entry points write, or the status alone.
    if (argc < 4) {
        std::fprintf(stderr,
                     "usage: nurbsrt-worker import-worker IN OUT [name=value ...]\n"
                     "       nurbsrt-worker convert-worker IN OUT REPORT [--name=value ...]\n"
                     "       nurbsrt-worker file-worker IN SUMMARY SCENE|- [OUT REPORT]... [name=value ...]\n");
        return 2;
    }
    const std::string command = argv[1];
    try {
        if (command == "import-worker") {
            const std::vector<std::string> rest(argv + 4, argv + argc);
            return nurbsrt::run_import_worker(argv[2], argv[3], nurbsrt::import_options_from_args(rest));
        }
        if (command == "file-worker") return nurbsrt::run_file_worker(std::vector<std::string>(argv + 2, argv + argc));
        if (command == "convert-worker" && argc >= 5) {
            const std::vector<std::string> rest(argv + 5, argv + argc);
            return nurbsrt::run_convert_worker(argv[2], argv[3], argv[4], nurbsrt::convert_options_from_args(rest));
        }
    } catch (const nurbsrt::Error& e) {
        std::fprintf(stderr, "nurbsrt-worker: error [%s]: %s\n", nurbsrt::error_code_name(e.code()), e.what());
        return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "nurbsrt-worker: error [internal]: %s\n", e.what());
        return 1;
    }
    std::fprintf(stderr, "nurbsrt-worker: unknown command or arguments: %s\n", command.c_str());
    return 2;
}
