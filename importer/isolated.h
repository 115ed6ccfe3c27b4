// Import in a child process, so that a file that crashes, hangs or exhausts
// memory in OCCT fails only its own request (bad input loses nothing
// but its own answer).
//
// The child is nurbsrt-worker (cli/worker_main.cpp, a small OCCT-only program
// beside this one) run as `nurbsrt-worker import-worker IN OUT ...`, or this same
// program with those arguments where the worker is not installed
// (cli/cmd_import_worker.cpp); under an address-space limit. The parent waits
// with a wall-clock limit, kills the child when it runs over, and reads the
// serialized scene (core/io/scene_io.h) or the typed error the child wrote.
// The child dies with its parent (PR_SET_PDEATHSIG: a killed service leaves no
// worker writing files behind it) and has a CPU-time limit of the wall-clock
// limit, so even an orphan cannot run on.
#pragma once

#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/error.h"
#include "importer/importer.h"
#include "importer/prescan.h"

namespace nurbsrt {

struct IsolationLimits {
    double time_limit_s = 300.0;                  // wall clock, whole import
    size_t memory_limit_bytes = size_t(8) << 30;  // RLIMIT_AS of the child; 0 = none
    std::string worker_executable;                // empty: nurbsrt-worker beside this binary, else this binary
    std::string scratch_dir;                      // empty: $TMPDIR or /tmp
    // Polled about every kStopPollMs while the child runs; when it returns true
    // the child is killed and the call throws Error(canceled) (a deleted job,
    // a client that went away). Empty: never.
    std::function<bool()> should_stop;
    // The child's niceness (setpriority; 0: this process's): accepted batch work
    // runs its children niced so that they yield the cores to interactive
    // requests, and take them whole when nothing else runs.
    int nice = 0;
    // The input's text is pre-scanned in this process before any child starts
    // (importer/prescan.h): absurd files are refused with unreadable_file.
    PrescanLimits prescan;
};

// Where an isolated call's time went besides the stages the child measured
// itself (Scene::timings; ConvertReport's read, mesh, write and verify): with
// them, the whole call.
struct IsolationTimings {
    double prescan_ms = 0;  // the pre-scan of the input's text, in this process
    // The child process less its own stages: creating it, loading the program and
    // its libraries, writing its result for this process, and its exit.
    double isolation_ms = 0;
    double transfer_ms = 0;  // reading the child's result (scene, report) into this process
    // The whole call, on one clock. The three above and the child's own stages
    // add up to it by construction: isolation_ms is what the others leave.
    double total_ms = 0;
};

// Runs import_file(path, options) in a child process. Throws nurbsrt::Error with
// the child's own error (io, unreadable_file, no_faces, ...), or import_timeout
// when it ran over, or import_crashed when it died (signal, out of memory).
// `timings`, when given, gets this call's time beside scene.timings.
Scene import_isolated(const std::string& path, const ImportOptions& options, const IsolationLimits& limits = {},
                      IsolationTimings* timings = nullptr);

// Runs convert_file(in_path, out_path, options) in a child process (`nurbsrt
// convert-worker IN OUT REPORT --step-schema=NAME --iges-mode=NAME [--units=NAME]`)
// under the same limits, with the same errors.
ConvertReport convert_isolated(const std::string& in_path, const std::string& out_path,
                               const IsolationLimits& limits = {}, IsolationTimings* timings = nullptr,
                               const ConvertOptions& options = {});

// Everything one file's outputs need, made by one child that reads the file
// once (importer/shared_read.h): the imported scene for its renders, and its
// conversions written by the child itself (the OCCT document lives there).
struct FilePlan {
    bool scene = false;  // import the scene with `options`
    ImportOptions options;
    std::vector<std::string> conversions;  // output paths, the format by extension as for convert_file
    // Each conversion's options, in the same order; those beyond its end are the defaults.
    std::vector<ConvertOptions> conversion_options;
};

// What the child made. An error of the scene or of one conversion is that
// item's alone; a file that cannot be read gives every item the read's error.
struct FileResult {
    std::optional<Scene> scene;
    std::optional<Error> scene_error;
    struct Conversion {
        std::optional<ConvertReport> report;
        std::optional<Error> error;
    };
    std::vector<Conversion> conversions;  // in the plan's order
    int reads = 0;                        // times the child parsed the file (1 for any plan that got to it)
    int uses = 0;                         // the read's users: the import and each conversion
    double read_ms = 0;                   // that read's time
    IsolationTimings timings;             // the whole child (scene and conversions' own stages excluded)
};

// Runs the plan in one child (`nurbsrt-worker file-worker ...`) under `limits`.
// Throws what import_isolated throws when the child as a whole fails (the
// pre-scan refuses the file, a crash, the time limit, a cancel): then every
// item has failed with that error.
FileResult process_file_isolated(const std::string& path, const FilePlan& plan, const IsolationLimits& limits = {});

// The command-line arguments that carry `options` to the worker, and their
// parser (used by the import-worker subcommand); kept together so they cannot drift.
std::vector<std::string> import_options_to_args(const ImportOptions& options);
ImportOptions import_options_from_args(const std::vector<std::string>& args);

// Entry point of the worker: imports IN and writes the scene to OUT, or writes
// the error to OUT + ".error" (code name, newline, message). Returns the exit status.
int run_import_worker(const std::string& in_path, const std::string& out_path, const ImportOptions& options);

// The same for ConvertOptions and the convert-worker subcommand.
std::vector<std::string> convert_options_to_args(const ConvertOptions& options);
ConvertOptions convert_options_from_args(const std::vector<std::string>& args);

// Entry point of the file worker: `args` are IN SUMMARY SCENE|- [OUT REPORT
// OPTIONS]... [name=value import options] (OPTIONS: a conversion's, see
// process_file_isolated); each item's result or error goes to its own
// file (the scene as run_import_worker writes it, each report as
// run_convert_worker does), the read count to SUMMARY. Returns the exit status.
int run_file_worker(const std::vector<std::string>& args);

// Entry point of the conversion worker: converts IN to OUT and writes the
// report to REPORT, or the error to REPORT + ".error". Returns the exit status.
int run_convert_worker(const std::string& in_path, const std::string& out_path, const std::string& report_path,
                       const ConvertOptions& options = {});

}  // namespace nurbsrt
