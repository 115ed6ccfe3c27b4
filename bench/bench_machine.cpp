// The machine a run's figures come from (every figure comes with its machine):
// CPU model, cores, load, memory, kernel, date, compiler and build type.
#include <sys/utsname.h>
#include <unistd.h>

#include <cstdio>
#include <ctime>
#include <fstream>
#include <string>
#include <thread>

#include "bench/bench_context.h"

#ifndef NURBSRT_BUILD_TYPE
#define NURBSRT_BUILD_TYPE "unknown"
#endif

namespace nurbsrt::bench {
namespace {

// The value of the first "key<spaces>: value" line of a /proc file.
std::string proc_field(const char* path, const std::string& key) {
    std::ifstream in(path);
    std::string line;
    while (std::getline(in, line))
        if (line.rfind(key, 0) == 0) {
            const size_t colon = line.find(':');
            if (colon == std::string::npos) continue;
            size_t b = line.find_first_not_of(" \t", colon + 1);
            return b == std::string::npos ? "" : line.substr(b);
        }
    return "";
}

}  // namespace

nlohmann::json machine_json() {
    nlohmann::json m;
    m["cpu"] = proc_field("/proc/cpuinfo", "model name");
    m["logical_cpus"] = std::thread::hardware_concurrency();
    const long online = sysconf(_SC_NPROCESSORS_ONLN);
    m["online_cpus"] = online;
    double load[3] = {0, 0, 0};
    if (getloadavg(load, 3) == 3) m["load_average"] = {load[0], load[1], load[2]};
    m["memory_total"] = proc_field("/proc/meminfo", "MemTotal");
    utsname u{};
    if (uname(&u) == 0) m["kernel"] = std::string(u.sysname) + " " + u.release + " " + u.machine;
    char host[256] = {};
    if (gethostname(host, sizeof host - 1) == 0) m["hostname"] = host;
    const std::time_t now = std::time(nullptr);
    char date[64];
    std::strftime(date, sizeof date, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
    m["date_utc"] = date;
#if defined(__clang__)
    m["compiler"] = std::string("clang ") + __clang_version__;
#elif defined(__GNUC__)
    m["compiler"] = std::string("gcc ") + __VERSION__;
#endif
    m["build_type"] = NURBSRT_BUILD_TYPE;
    if (const char* lp = std::getenv("LP_NUM_THREADS")) m["LP_NUM_THREADS"] = lp;
    return m;
}

}  // namespace nurbsrt::bench
