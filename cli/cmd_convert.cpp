// nurbsrt convert IN OUT: STEP <-> IGES, output format from OUT's extension.
#include <CLI/CLI.hpp>

#include <cstdio>

#include "cli/commands.h"
#include "importer/importer.h"

namespace nurbsrt::cli {

void add_convert_command(CLI::App& app) {
    auto* cmd = app.add_subcommand(
        "convert",
        "Convert a CAD file between STEP and IGES, preserving its geometry.\n"
        "The input format is recognised from the content, the output format from\n"
        "OUT's extension (.stp/.step or .igs/.iges).\n"
        "Example: nurbsrt convert part.step part.igs");
    auto in = std::make_shared<std::string>();
    auto out = std::make_shared<std::string>();
    cmd->add_option("IN", *in, "input STEP or IGES file")->required()->check(CLI::ExistingFile);
    cmd->add_option("OUT", *out, "output file (.stp, .step, .igs or .iges)")->required();
    cmd->callback([in, out] {
        const ConvertReport r = convert_file(*in, *out);
        std::fprintf(stderr, "nurbsrt: converted %s (%s, %d faces) to %s (%s): read %.1f ms, write %.1f ms\n",
                     in->c_str(), format_name(r.in_format), r.faces, out->c_str(),
                     format_name(r.out_format), r.read_ms, r.write_ms);
    });
}

}  // namespace nurbsrt::cli
