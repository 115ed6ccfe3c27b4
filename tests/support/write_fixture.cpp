// nurbsrt_fixture: writes one generated test fixture to a file, for the API
// tests and the benchmark scripts (which cannot call OCCT themselves).
//   nurbsrt_fixture NAME OUT        NAME: any of fixture_names(), or cube10
//   nurbsrt_fixture dense_bspline DEGREE POLES OUT
#include <cstdio>
#include <exception>
#include <filesystem>
#include <string>

#include "tests/support/fixtures.h"

int main(int argc, char** argv) {
    namespace T = nurbsrt::test;
    try {
        std::string from;
        std::string out;
        if (argc == 5 && std::string(argv[1]) == "dense_bspline") {
            from = T::dense_bspline(std::stoi(argv[2]), std::stoi(argv[3]));
            out = argv[4];
        } else if (argc == 3) {
            from = T::fixture_by_name(argv[1]);
            out = argv[2];
        } else {
            std::fprintf(stderr, "usage: nurbsrt_fixture NAME OUT | nurbsrt_fixture dense_bspline DEGREE POLES OUT\n");
            return 2;
        }
        std::filesystem::copy_file(from, out, std::filesystem::copy_options::overwrite_existing);
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "nurbsrt_fixture: %s\n", e.what());
        return 1;
    }
}
