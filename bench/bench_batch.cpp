// The "batch" section: one job of several files, each with a render and two
// mesh conversions, through the service's job path (`nurbsrt serve` started
// here with its default settings, POST /v1/jobs, polled until done, every
// artifact downloaded) against the same outputs made by one `nurbsrt` CLI
// process per output, run after each other as a shell loop would. The two are
// interleaved, run by run, and both report per-stage sums (file reads, render
// frames, conversion meshing and writing), so that the ratio is explained.
#include <httplib.h>

#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <thread>

#include "bench/bench_context.h"
#include "core/error.h"
#include "core/process/executable_path.h"

extern char** environ;

namespace nurbsrt::bench {
namespace {

namespace fs = std::filesystem;

// Nine files users might send together, STEP and IGES, 0.1-1.2 s each through
// one CLI conversion on the 2-core machine (cylinder_block's 3.8 s would
// dominate every sum).
const char* kBatchFiles[] = {
    "step/trj8_b1-ec-214.stp", "step/linkrods.step",         "iges/bearing.iges",
    "iges/hammer.iges",        "step/as1-oc-214.stp",        "step/bug27693_cornetta-step.stp",
    "iges/torus.igs",          "duck/duck_from_glscene.igs", "step/face_recognition_sample_part.stp"};
// --quick: four small ones (a smoke run checks the section's shape, not its figures).
const char* kBatchQuickFiles[] = {"step/as1-oc-214.stp", "step/bug27693_cornetta-step.stp", "iges/torus.igs",
                                  "step/face_recognition_sample_part.stp"};
// Without ../shared/models (--quick on OCCT's samples).
const char* kBatchSampleFiles[] = {"step/screw.step", "iges/bearing.iges", "iges/hammer.iges", "step/linkrods.step"};
constexpr int kBatchWidth = 400, kBatchHeight = 300;
const char* kBatchConversions[] = {"stl", "glb"};
// Frame stages of a render's timings (the same names in the CLI's and the service's statistics).
const char* kFrameStages[] = {"frame_setup", "preliminary_map", "newton",     "shadow_map", "shade",
                              "antialias",   "edges",           "statistics", "encode"};

struct StageSums {
    int reads = 0;
    double read_ms = 0, render_ms = 0, write_ms = 0;
    nlohmann::json to_json() const {
        return {{"reads", reads}, {"read_ms", read_ms}, {"render_ms", render_ms}, {"write_ms", write_ms}};
    }
};

pid_t spawn(const std::vector<std::string>& args, const std::string& log) {
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    posix_spawn_file_actions_adddup2(&fa, 1, 2);
    pid_t pid = 0;
    const int rc = posix_spawn(&pid, argv[0], &fa, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&fa);
    if (rc != 0) throw Error(ErrorCode::internal, "cannot start " + args[0]);
    return pid;
}

void run_checked(const std::vector<std::string>& args, const std::string& log) {
    int status = 0;
    waitpid(spawn(args, log), &status, 0);
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
        throw Error(ErrorCode::internal, "batch bench: '" + args[1] + " " + args[2] + "' failed (log " + log + ")");
}

std::string slurp(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

double frame_ms(const nlohmann::json& timings) {
    double ms = 0;
    for (const char* stage : kFrameStages) ms += timings.value(stage, 0.0);
    return ms;
}

// One CLI process per output, one after the other. Returns the wall time.
double cli_loop(const std::vector<std::string>& files, const std::string& dir, StageSums& sums) {
    const std::string exe = executable_path();
    const std::regex stages(R"(read ([0-9.]+) ms(, mesh ([0-9.]+) ms)?, write ([0-9.]+) ms)");
    const auto t0 = Clock::now();
    for (size_t k = 0; k < files.size(); ++k) {
        const std::string stem = dir + "/" + std::to_string(k);
        run_checked({exe, "render", files[k], "-o", stem + ".png", "--width", std::to_string(kBatchWidth), "--height",
                     std::to_string(kBatchHeight), "--stats", stem + ".json", "-q"},
                    stem + ".render.log");
        const nlohmann::json t = nlohmann::json::parse(slurp(stem + ".json")).at("timings_ms");
        ++sums.reads;
        sums.read_ms += t.value("read", 0.0);
        sums.render_ms += frame_ms(t);
        for (const char* format : kBatchConversions) {
            const std::string log = stem + "." + format + ".log";
            run_checked({exe, "convert", files[k], stem + "." + format}, log);
            std::smatch m;
            const std::string text = slurp(log);
            if (!std::regex_search(text, m, stages))
                throw Error(ErrorCode::internal, "batch bench: no stages in " + log);
            ++sums.reads;
            sums.read_ms += std::stod(m[1]);
            sums.write_ms += (m[3].matched ? std::stod(m[3]) : 0.0) + std::stod(m[4]);
        }
    }
    return ms_since(t0);
}

int free_port() {
    const int fd = socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t len = sizeof a;
    if (fd < 0 || bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 ||
        getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) != 0)
        throw Error(ErrorCode::internal, "batch bench: no free port");
    close(fd);
    return ntohs(a.sin_port);
}

// The service with its default settings, on a data directory of its own.
struct Service {
    pid_t pid = 0;
    int port = 0;
    Service(const std::string& dir) {
        port = free_port();
        pid = spawn({executable_path(), "serve", "--host", "127.0.0.1", "--port", std::to_string(port), "--data-dir",
                     dir + "/data"},
                    dir + "/serve.log");
        httplib::Client c("127.0.0.1", port);
        for (int i = 0; i < 300; ++i) {
            if (auto r = c.Get("/healthz"); r && r->status == 200) return;
            std::this_thread::sleep_for(std::chrono::milliseconds(100));
        }
        stop();
        throw Error(ErrorCode::internal, "batch bench: the service did not start (log " + dir + "/serve.log)");
    }
    void stop() {
        if (pid <= 0) return;
        kill(pid, SIGTERM);
        waitpid(pid, nullptr, 0);
        pid = 0;
    }
    ~Service() { stop(); }
};

// The job through the service: submitted, polled until it ends, every artifact
// downloaded. Returns the wall time; `doc` gets the finished job's document.
double job_run(const Service& service, const std::vector<std::string>& files, StageSums& sums, nlohmann::json& doc) {
    httplib::Client c("127.0.0.1", service.port);
    c.set_read_timeout(600);
    nlohmann::json spec = {{"outputs", nlohmann::json::array()}};
    httplib::MultipartFormDataItems items;
    std::vector<std::string> bytes;
    for (size_t k = 0; k < files.size(); ++k) bytes.push_back(slurp(files[k]));  // the client has its files at hand
    for (size_t k = 0; k < files.size(); ++k) {
        items.push_back({"file", bytes[k], fs::path(files[k]).filename().string(), "application/octet-stream"});
        spec["outputs"].push_back(
            {{"file", k}, {"type", "render"}, {"options", {{"width", kBatchWidth}, {"height", kBatchHeight}}}});
        for (const char* format : kBatchConversions)
            spec["outputs"].push_back({{"file", k}, {"type", "conversion"}, {"format", format}});
    }
    items.push_back({"job", spec.dump(), "", "application/json"});
    const auto t0 = Clock::now();
    const auto posted = c.Post("/v1/jobs", items);
    if (!posted || posted->status != 202) throw Error(ErrorCode::internal, "batch bench: the job was not accepted");
    const std::string url = nlohmann::json::parse(posted->body).at("url");
    for (;;) {
        const auto r = c.Get(url);
        if (!r || r->status != 200) throw Error(ErrorCode::internal, "batch bench: cannot read the job");
        doc = nlohmann::json::parse(r->body);
        const std::string state = doc.at("state");
        if (state == "succeeded") break;
        if (state == "failed" || state == "canceled")
            throw Error(ErrorCode::internal, "batch bench: the job " + state + ": " + r->body.substr(0, 400));
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    for (const nlohmann::json& out : doc.at("outputs")) {
        const auto r = c.Get(out.at("artifact").at("url").get<std::string>());
        if (!r || r->status != 200) throw Error(ErrorCode::internal, "batch bench: an artifact did not download");
    }
    const double wall = ms_since(t0);
    std::set<std::string> reads;
    for (const nlohmann::json& out : doc.at("outputs")) {
        const bool render = out.at("type") == "render";
        const nlohmann::json& result = out.at(render ? "statistics" : "report");
        if (reads.insert(result.at("read").at("id").get<std::string>()).second)
            sums.read_ms += result.at("read").at("read_ms").get<double>();
        const nlohmann::json& t = result.at("timings_ms");
        if (render)
            sums.render_ms += frame_ms(t);
        else
            sums.write_ms += t.value("mesh", 0.0) + t.value("write", 0.0);
    }
    sums.reads = static_cast<int>(reads.size());
    return wall;
}

}  // namespace

void run_batch(BenchContext& ctx) {
    std::vector<std::string> files;
    if (ctx.fallback_models) {
        for (const char* f : kBatchSampleFiles) files.push_back(ctx.models_dir + "/" + f);
    } else if (ctx.opt.quick) {
        for (const char* f : kBatchQuickFiles)
            if (fs::is_regular_file(fs::path(ctx.models_dir) / f)) files.push_back(ctx.models_dir + "/" + f);
    } else {
        for (const char* f : kBatchFiles)
            if (fs::is_regular_file(fs::path(ctx.models_dir) / f)) files.push_back(ctx.models_dir + "/" + f);
    }
    if (files.empty()) throw Error(ErrorCode::io, "batch: none of its files is in " + ctx.models_dir);
    const std::string dir = fs::temp_directory_path() / ("nurbsrt-bench-batch-" + std::to_string(getpid()));
    fs::create_directories(dir);
    const int runs = ctx.opt.quick ? 1 : 5;  // a shared machine's load drifts: the median of five
    ctx.say("batch: %zu files x (render %dx%d, stl, glb), %d interleaved runs", files.size(), kBatchWidth, kBatchHeight,
            runs);
    nlohmann::json out_runs = nlohmann::json::array();
    std::vector<double> ratios;
    nlohmann::json job_statistics;
    {
        for (int r = 0; r < runs; ++r) {
            // A new service each run: its scene cache would serve the next run's renders
            // without an import, which the CLI loop pays every time.
            const std::string run_dir = dir + "/run-" + std::to_string(r);
            fs::create_directories(run_dir);
            Service service(run_dir);
            StageSums cli_run, job_run_sums;
            nlohmann::json doc;
            double cli_ms = 0, job_ms = 0;
            // Alternate which goes first, so that neither always finds the page cache warmer.
            for (int half = 0; half < 2; ++half) {
                if ((half == 0) == (r % 2 == 0))
                    cli_ms = cli_loop(files, dir, cli_run);
                else
                    job_ms = job_run(service, files, job_run_sums, doc);
            }
            ratios.push_back(job_ms / cli_ms);
            ctx.say("batch run %d: CLI loop %.0f ms, job %.0f ms, ratio %.3f", r + 1, cli_ms, job_ms, ratios.back());
            out_runs.push_back({{"cli_loop_ms", cli_ms},
                                {"job_ms", job_ms},
                                {"ratio", ratios.back()},
                                {"cli_loop_stages", cli_run.to_json()},
                                {"job_stages", job_run_sums.to_json()}});
            job_statistics = doc.at("statistics");
        }
    }
    std::error_code ec;
    fs::remove_all(dir, ec);
    nlohmann::json names = nlohmann::json::array();
    for (const std::string& f : files) names.push_back(fs::relative(f, ctx.models_dir).string());
    ctx.doc["batch"] = {{"files", names},
                        {"outputs", files.size() * (1 + std::size(kBatchConversions))},
                        {"render", {{"width", kBatchWidth}, {"height", kBatchHeight}}},
                        {"conversions", kBatchConversions},
                        {"service", "nurbsrt serve, default settings"},
                        {"runs", out_runs},
                        {"median_ratio", median(ratios)},
                        {"min_ratio", *std::min_element(ratios.begin(), ratios.end())},
                        {"max_ratio", *std::max_element(ratios.begin(), ratios.end())},
                        {"last_job_statistics", job_statistics}};
}

}  // namespace nurbsrt::bench
