// nurbsrt bench: the paper's Table 1 and the peer and scaling figures
// (bench/bench.h), as Markdown (stdout by default) and JSON.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <fstream>
#include <iostream>
#include <sstream>

#include "bench/bench.h"
#include "cli/commands.h"
#include "core/error.h"
#include "cli/validators.h"

namespace nurbsrt::cli {
namespace {

void write_file(const std::string& path, const std::string& text) {
    if (path == "-") {
        std::cout << text;
        return;
    }
    std::ofstream out(path);
    out << text;
    if (!out) throw Error(ErrorCode::io, "cannot write " + path);
}

}  // namespace

void add_bench_command(CLI::App& app) {
    auto o = std::make_shared<bench::BenchOptions>();
    auto json_path = std::make_shared<std::string>();
    auto md_path = std::make_shared<std::string>("-");
    auto only = std::make_shared<std::string>();
    auto quiet = std::make_shared<bool>(false);
    auto* cmd =
        app.add_subcommand("bench",
                           "Benchmarks on this machine: the paper's Table 1 (proposed vs Martin et al. on the same\n"
                           "preliminary map), map precision, OCCT's exact intersector and a BRepMesh tessellation as\n"
                           "peers, scaling with resolution, patches and threads, and the frame-time cost of\n"
                           "anti-aliasing + feature lines and of shadows (`look`), and a batch job through the\n"
                           "service against one CLI process per output (`batch`). Progress goes to stderr.\n"
                           "Examples:\n"
                           "  nurbsrt bench --json docs/bench.json --markdown docs/bench.md\n"
                           "  nurbsrt bench --quick --json out.json\n"
                           "  nurbsrt bench --only table1,precision --runs 7");
    cmd->add_flag("--quick", o->quick,
                  "smoke run: 128x128, 2 runs, small budgets (falls back to OCCT's sample files when "
                  "../shared/models is absent)");
    cmd->add_option("--json", *json_path, "write the results as JSON to this file ('-' for stdout)");
    cmd->add_option("--markdown", *md_path, "write the Markdown report to this file ('-': stdout)")
        ->capture_default_str();
    cmd->add_option("--models", o->models_dir,
                    "the shared models directory (default: $NURBSRT_MODELS, else ../shared/models from the "
                    "working directory, then beside the source tree)");
    cmd->add_option("--runs", o->runs,
                    "minimum timed runs per figure (default 9, --quick 2); a full run's Table 1 and "
                    "precision figures go on until each variant has 4 s of frames")
        ->check(in_range(1, 100));
    cmd->add_option("--threads", o->threads, "render threads for all but the thread-scaling figures")
        ->check(in_range(1, 1024))
        ->capture_default_str();
    cmd->add_option("--size", o->size, "image width = height (default 512, --quick 128)")->check(in_range(16, 8192));
    cmd->add_option("--only", *only,
                    "comma-separated sections: table1,precision,occt,tessellation,meshtracer,scaling,look,batch");
    cmd->add_flag("-q,--quiet", *quiet, "no progress on stderr");

    cmd->callback([o, json_path, md_path, only, quiet] {
        o->progress = !*quiet;
        std::stringstream list(*only);
        for (std::string s; std::getline(list, s, ',');)
            if (!s.empty()) o->only.push_back(s);
        if (*json_path == "-" && *md_path == "-")
            throw Error(ErrorCode::invalid_argument, "--json - needs --markdown FILE (both cannot go to stdout)");
        const nlohmann::json doc = bench::run_bench(*o);
        if (!json_path->empty()) write_file(*json_path, doc.dump(2) + "\n");
        write_file(*md_path, bench::bench_markdown(doc));
    });
}

}  // namespace nurbsrt::cli
