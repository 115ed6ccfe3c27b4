// Subcommands of the nurbsrt program; each file cmd_*.cpp adds one to the app.
#pragma once

namespace CLI {
class App;
}

namespace nurbsrt::cli {

void add_info_command(CLI::App& app);
void add_convert_command(CLI::App& app);
void add_render_command(CLI::App& app);
void add_import_worker_command(CLI::App& app);
void add_file_worker_command(CLI::App& app);
void add_convert_worker_command(CLI::App& app);
void add_serve_command(CLI::App& app);
void add_bench_command(CLI::App& app);

}  // namespace nurbsrt::cli
