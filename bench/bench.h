// `nurbsrt bench`: the paper's Table 1 (Sisojevs & Glazs 2010, section 3), the peers and
// scaling figures and the cost of the image options (anti-aliasing, feature lines, shadows), measured on this machine and returned as one JSON
// document; the Markdown report is generated from that same document.
#pragma once

#include <nlohmann/json_fwd.hpp>

#include <string>
#include <vector>

namespace nurbsrt::bench {

// Sections, in the order they run and are reported.
inline const std::vector<std::string> kSections = {"table1",     "precision", "occt", "tessellation",
                                                   "meshtracer", "scaling",   "look", "batch"};

struct BenchOptions {
    bool quick = false;             // small images, few runs, small budgets (a smoke run)
    std::string models_dir;         // ../shared/models; empty: the default search (see bench_scenes.cpp)
    int runs = 0;                   // timed runs per figure; 0: 9 (full) or 2 (quick)
    int threads = 1;                // render threads for every section but the thread scaling
    int size = 0;                   // image width = height; 0: 512 (the paper's) or 128 (quick)
    std::vector<std::string> only;  // sections to run; empty: all
    bool progress = true;           // progress lines on stderr
};

// Runs the selected sections. Throws nurbsrt::Error (invalid_argument for an
// unknown section, io when no models are found).
nlohmann::json run_bench(const BenchOptions& options);

// The Markdown report of a run_bench() document.
std::string bench_markdown(const nlohmann::json& doc);

}  // namespace nurbsrt::bench
