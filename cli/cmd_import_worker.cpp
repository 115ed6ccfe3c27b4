// nurbsrt import-worker IN OUT [options] and nurbsrt file-worker IN SUMMARY
// SCENE|- [OUT REPORT]... [options]: the child sides of importer/isolated.h.
// Hidden from --help: it is run by the program itself, not by users.
#include <CLI/CLI.hpp>

#include "cli/commands.h"
#include "importer/isolated.h"

namespace nurbsrt::cli {

void add_import_worker_command(CLI::App& app) {
    auto* cmd = app.add_subcommand("import-worker", "internal: the child side of an isolated import");
    cmd->group("");  // an empty group hides it from --help
    cmd->allow_extras();
    auto in = std::make_shared<std::string>();
    auto out = std::make_shared<std::string>();
    cmd->add_option("IN", *in)->required();
    cmd->add_option("OUT", *out)->required();
    cmd->callback([cmd, in, out] {
        const ImportOptions options = import_options_from_args(cmd->remaining());
        std::exit(run_import_worker(*in, *out, options));
    });
}

void add_file_worker_command(CLI::App& app) {
    auto* cmd =
        app.add_subcommand("file-worker", "internal: the child side of a file's isolated import and conversions");
    cmd->group("");
    cmd->allow_extras();
    cmd->prefix_command();  // everything after the name is the worker's own arguments
    cmd->callback([cmd] { std::exit(run_file_worker(cmd->remaining())); });
}

}  // namespace nurbsrt::cli
