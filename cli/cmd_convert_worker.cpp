// nurbsrt convert-worker IN OUT REPORT [--name=value ...]: the child side of convert_isolated
// (importer/isolated.h). Hidden from --help: run by the program itself.
#include <CLI/CLI.hpp>

#include "cli/commands.h"
#include "importer/isolated.h"

namespace nurbsrt::cli {

void add_convert_worker_command(CLI::App& app) {
    auto* cmd = app.add_subcommand("convert-worker", "internal: the child side of an isolated conversion");
    cmd->group("");  // an empty group hides it from --help
    auto in = std::make_shared<std::string>();
    auto out = std::make_shared<std::string>();
    auto report = std::make_shared<std::string>();
    cmd->add_option("IN", *in)->required();
    cmd->add_option("OUT", *out)->required();
    cmd->allow_extras();  // the options, --name=value (convert_options_to_args)
    cmd->add_option("REPORT", *report)->required();
    cmd->callback([cmd, in, out, report] {
        std::exit(run_convert_worker(*in, *out, *report, convert_options_from_args(cmd->remaining())));
    });
}

}  // namespace nurbsrt::cli
