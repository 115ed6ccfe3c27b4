// nurbsrt: direct ray tracing of trimmed NURBS surfaces from STEP and IGES files.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>
#include <string>

#include "cli/commands.h"
#include "cli/warnings.h"
#include "core/error.h"
#include "core/process/heap_tuning.h"

int main(int argc, char** argv) {
    nurbsrt::tune_heap_for_frames();
    CLI::App app{
        "nurbsrt renders STEP and IGES files by ray tracing their exact trimmed NURBS\n"
        "surfaces, and converts between CAD formats.\n"
        "Run 'nurbsrt <command> --help' for the options of a command."};
    app.require_subcommand(1);
    app.set_version_flag("--version", "nurbsrt 0.1.0");
    // The same table is in the README's "Commands" section (a test compares them).
    app.footer(
        "Exit status:\n"
        "  0  success\n"
        "  1  the command failed; the message names an error code such as\n"
        "     unreadable_file, no_faces, import_timeout or io\n"
        "  2  bad command line: unknown option, bad value, missing input, an output\n"
        "     path or format that cannot be written; all checked before any import,\n"
        "     with CLI11's message naming the option\n"
        "  3  --strict, and the command had warnings (printed above); nothing written");
    nurbsrt::cli::add_render_command(app);
    nurbsrt::cli::add_info_command(app);
    nurbsrt::cli::add_convert_command(app);
    nurbsrt::cli::add_serve_command(app);
    nurbsrt::cli::add_bench_command(app);
    nurbsrt::cli::add_import_worker_command(app);
    nurbsrt::cli::add_file_worker_command(app);
    nurbsrt::cli::add_convert_worker_command(app);

    // CLI11 answers a mistyped command with "A subcommand is required".
    const auto named = [&](const CLI::App* s) { return s->check_name(argv[1]); };
    if (argc > 1 && argv[1][0] != '-' && app.get_subcommands(named).empty()) {
        std::string commands;
        for (const CLI::App* sub : app.get_subcommands([](const CLI::App* s) { return !s->get_group().empty(); }))
            commands += (commands.empty() ? "" : ", ") + sub->get_name();
        std::fprintf(stderr, "nurbsrt: unknown command '%s'; commands: %s\nRun with --help for more information.\n",
                     argv[1], commands.c_str());
        return 2;
    }
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        const int rc = app.exit(e);
        return rc == 0 ? 0 : 2;
    } catch (const nurbsrt::cli::WarningsRefused& e) {
        std::fprintf(stderr, "nurbsrt: error [strict]: %s\n", e.what());
        return 3;
    } catch (const nurbsrt::Error& e) {
        std::fprintf(stderr, "nurbsrt: error [%s]: %s\n", nurbsrt::error_code_name(e.code()), e.what());
        return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "nurbsrt: error [internal]: %s\n", e.what());
        return 1;
    }
    return 0;
}
