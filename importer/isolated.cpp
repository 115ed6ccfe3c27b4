// Process-isolated import: see isolated.h. Plain POSIX; no OCCT here.
#include "importer/isolated.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <thread>

#include <tbb/global_control.h>

#include "core/error.h"
#include "core/process/executable_path.h"
#include "core/io/scene_io.h"
#include "importer/shared_read.h"

namespace nurbsrt {
namespace {

// How often a running worker's should_stop is asked: a canceled job or a gone
// client frees its worker within this time (plus the kill).
constexpr int kStopPollMs = 100;

// The worker program: nurbsrt-worker beside this executable when it is there
// (the build and the Docker image put it there), else this executable itself,
// which has the same entry points as hidden subcommands. A separate program
// because the service starts one on every upload it imports: `nurbsrt` links
// OSMesa's LLVM, libpq and Embree besides OCCT and starts markedly slower than
// a program that links OCCT alone (docs/BENCHMARKS.md).
std::string default_worker_executable() {
    const std::string sibling = beside_executable("nurbsrt-worker");
    return access(sibling.c_str(), X_OK) == 0 ? sibling : executable_path();
}

std::string worker_executable(const IsolationLimits& limits) {
    return limits.worker_executable.empty() ? default_worker_executable() : limits.worker_executable;
}

std::string read_small_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

// Removes the scratch files on every exit path.
struct ScratchFiles {
    std::string scene, error;
    // Removes them (once); also on every exit by the destructor.
    void remove() {
        if (!scene.empty()) unlink(scene.c_str());
        if (!error.empty()) unlink(error.c_str());
        scene.clear();
        error.clear();
    }
    ~ScratchFiles() { remove(); }
};

// Waits for `pid` for at most `seconds`; returns true and fills `status` when it
// exited. Uses a pidfd so the wait is an event, not a polling loop; falls back
// to short sleeps on kernels without pidfd_open.
bool wait_with_timeout(pid_t pid, double seconds, int& status, const std::function<bool()>& should_stop,
                       bool& stopped) {
    using clock = std::chrono::steady_clock;
    const auto deadline = clock::now() + std::chrono::duration<double>(seconds);
    const int pidfd = static_cast<int>(syscall(SYS_pidfd_open, pid, 0));
    const long long step_ms = should_stop ? kStopPollMs : 1000;
    stopped = false;
    for (;;) {
        const pid_t r = waitpid(pid, &status, WNOHANG);
        if (r == pid) {
            if (pidfd >= 0) close(pidfd);
            return true;
        }
        if (r < 0 && errno != EINTR) {
            if (pidfd >= 0) close(pidfd);
            throw Error(ErrorCode::internal, std::string("waitpid: ") + std::strerror(errno));
        }
        const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - clock::now()).count();
        stopped = should_stop && should_stop();
        if (left <= 0 || stopped) {
            if (pidfd >= 0) close(pidfd);
            return false;
        }
        if (pidfd >= 0) {
            pollfd p{pidfd, POLLIN, 0};
            poll(&p, 1, static_cast<int>(std::min<long long>(left, step_ms)));
        } else {
            std::this_thread::sleep_for(std::chrono::milliseconds(std::min<long long>(left, 5)));
        }
    }
}

}  // namespace

std::vector<std::string> import_options_to_args(const ImportOptions& o) {
    auto num = [](double v) {
        std::ostringstream s;
        s.precision(17);
        s << v;
        return s.str();
    };
    return {"--mesh-deflection=" + num(o.mesh_relative_deflection), "--mesh-angle=" + num(o.mesh_angular_deflection),
            "--mesh-time-limit=" + num(o.mesh_time_limit_s), "--trim-tolerance=" + num(o.trim_relative_tolerance),
            std::string("--attributes=") + (o.read_attributes ? "1" : "0")};
}

ImportOptions import_options_from_args(const std::vector<std::string>& args) {
    ImportOptions o;
    for (const std::string& a : args) {
        const size_t eq = a.find('=');
        if (eq == std::string::npos) throw Error(ErrorCode::invalid_argument, "bad worker option: " + a);
        const std::string key = a.substr(0, eq), value = a.substr(eq + 1);
        char* end = nullptr;
        const double v = std::strtod(value.c_str(), &end);
        if (end == value.c_str() || *end != '\0')
            throw Error(ErrorCode::invalid_argument, "bad worker option value: " + a);
        if (key == "--mesh-deflection")
            o.mesh_relative_deflection = v;
        else if (key == "--mesh-angle")
            o.mesh_angular_deflection = v;
        else if (key == "--mesh-time-limit")
            o.mesh_time_limit_s = v;
        else if (key == "--trim-tolerance")
            o.trim_relative_tolerance = v;
        else if (key == "--attributes")
            o.read_attributes = v != 0;
        else
            throw Error(ErrorCode::invalid_argument, "unknown worker option: " + a);
    }
    return o;
}

std::vector<std::string> convert_options_to_args(const ConvertOptions& o) {
    std::vector<std::string> args = {std::string("--step-schema=") + step_schema_name(o.step_schema),
                                     std::string("--iges-mode=") + iges_mode_name(o.iges_mode)};
    if (o.units != LengthUnit::unknown) args.push_back(std::string("--units=") + length_unit_name(o.units));
    auto exact = [](double v) {  // 17 digits: the double read back is the one written
        std::ostringstream d;
        d.precision(17);
        d << v;
        return d.str();
    };
    args.push_back("--angular-deflection=" + exact(o.angular_deflection));
    if (o.deflection != 0) args.push_back("--deflection=" + exact(o.deflection));
    return args;
}

ConvertOptions convert_options_from_args(const std::vector<std::string>& args) {
    ConvertOptions o;
    for (const std::string& a : args) {
        const size_t eq = a.find('=');
        const std::string key = a.substr(0, eq), value = eq == std::string::npos ? "" : a.substr(eq + 1);
        bool ok = false;
        if (key == "--units") {
            const std::optional<LengthUnit> u = length_unit_from_name(value);
            if ((ok = u.has_value())) o.units = *u;
        } else if (key == "--step-schema") {
            const std::optional<StepSchema> s = step_schema_from_name(value);
            if ((ok = s.has_value())) o.step_schema = *s;
        } else if (key == "--iges-mode") {
            const std::optional<IgesMode> m = iges_mode_from_name(value);
            if ((ok = m.has_value())) o.iges_mode = *m;
        } else if (key == "--angular-deflection" || key == "--deflection") {
            char* end = nullptr;
            (key == "--deflection" ? o.deflection : o.angular_deflection) = std::strtod(value.c_str(), &end);
            ok = !value.empty() && *end == '\0';
        }
        if (!ok) throw Error(ErrorCode::invalid_argument, "bad worker option: " + a);
    }
    return o;
}

namespace {

std::string scratch_dir_of(const IsolationLimits& limits) {
    if (!limits.scratch_dir.empty()) return limits.scratch_dir;
    const char* t = std::getenv("TMPDIR");
    return (t && *t) ? t : "/tmp";
}

// Creates the worker's result file (and names its ".error" companion).
void make_scratch(ScratchFiles& scratch, const std::string& dir, const char* stem) {
    std::string tmpl = dir + "/" + stem + "-XXXXXX";
    const int fd = mkstemp(tmpl.data());
    if (fd < 0) throw Error(ErrorCode::io, "cannot create scratch file in " + dir + ": " + std::strerror(errno));
    close(fd);
    scratch.scene = tmpl;
    scratch.error = tmpl + ".error";
}

// Runs `args` (argv[0] is the executable) under the limits. Returns normally
// when the worker exited with status 0; otherwise throws the worker's typed
// error (read from `error_path`), import_timeout, import_crashed or internal.
// `what` names the work in messages ("import", "conversion").
void run_worker(std::vector<std::string> args, const IsolationLimits& limits, const std::string& error_path,
                const std::string& what, const std::string& subject) {
    const std::string& exe = args.front();
    std::vector<char*> argv;  // built before fork: the child may only make async-signal-safe calls
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);

    // CPU seconds: the wall-clock limit on every core (meshing may run
    // threads), plus one; the soft limit sends SIGXCPU, the hard one SIGKILL.
    const double cores = std::max(1u, std::thread::hardware_concurrency());
    const rlim_t cpu_s = static_cast<rlim_t>(std::ceil(limits.time_limit_s * cores)) + 1;
    const pid_t parent = getpid();
    const pid_t pid = fork();
    if (pid < 0) throw Error(ErrorCode::internal, std::string("fork: ") + std::strerror(errno));
    if (pid == 0) {
        // Die with the service (the forking thread waits for us until we end,
        // so the thread-based death signal fires only when the service dies);
        // the parent may have died before the prctl: then end now.
        prctl(PR_SET_PDEATHSIG, SIGKILL);
        if (getppid() != parent) _exit(126);
        rlimit cpu{cpu_s, cpu_s + 1};
        setrlimit(RLIMIT_CPU, &cpu);
        if (limits.memory_limit_bytes > 0) {
            rlimit rl{limits.memory_limit_bytes, limits.memory_limit_bytes};
            setrlimit(RLIMIT_AS, &rl);
        }
        if (limits.nice > 0) setpriority(PRIO_PROCESS, 0, limits.nice);
        rlimit no_core{0, 0};  // a crashing import must not litter the data directory with cores
        setrlimit(RLIMIT_CORE, &no_core);
        // A server may block or ignore signals in its own threads; the worker starts clean.
        sigset_t none;
        sigemptyset(&none);
        sigprocmask(SIG_SETMASK, &none, nullptr);
        signal(SIGPIPE, SIG_DFL);
        // Do not leak the server's sockets and files into the worker.
        syscall(SYS_close_range, 3u, ~0u, 0u);
        execv(exe.c_str(), argv.data());
        _exit(127);
    }

    int status = 0;
    bool stopped = false;
    if (!wait_with_timeout(pid, limits.time_limit_s, status, limits.should_stop, stopped)) {
        kill(pid, SIGKILL);
        waitpid(pid, &status, 0);
        if (stopped) throw Error(ErrorCode::canceled, what + " of '" + subject + "' was canceled");
        std::ostringstream msg;
        msg << what << " of '" << subject << "' did not finish within " << limits.time_limit_s << " s";
        throw Error(ErrorCode::import_timeout, msg.str());
    }
    if (WIFSIGNALED(status) && WTERMSIG(status) == SIGXCPU) {
        std::ostringstream msg;
        msg << what << " of '" << subject << "' used more CPU time than its limit of " << limits.time_limit_s
            << " s per core";
        throw Error(ErrorCode::import_timeout, msg.str());
    }
    if (WIFSIGNALED(status)) {
        const int sig = WTERMSIG(status);
        std::ostringstream msg;
        msg << what << " process died of signal " << sig << " (" << strsignal(sig) << ")";
        if (sig == SIGKILL || sig == SIGABRT || sig == SIGSEGV)
            msg << "; the file may be malformed or exceed the memory limit of " << (limits.memory_limit_bytes >> 20)
                << " MiB";
        throw Error(ErrorCode::import_crashed, msg.str());
    }
    const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    if (code == 0) return;
    if (code == 127) throw Error(ErrorCode::internal, "cannot start " + what + " worker " + exe);

    const std::string err = read_small_file(error_path);
    const size_t nl = err.find('\n');
    if (nl == std::string::npos) {
        // No typed error written: the worker failed before or while writing it
        // (std::bad_alloc under the memory limit ends up here too).
        throw Error(ErrorCode::import_crashed,
                    what + " process exited with status " + std::to_string(code) + " without a result");
    }
    throw Error(error_code_from_name(err.substr(0, nl)).value_or(ErrorCode::internal), err.substr(nl + 1));
}

// Test hook: lets integration tests prove that a dying or hanging worker fails
// only its own request. Read only in worker processes.
void apply_fault_hook() {
    if (const char* fault = std::getenv("NURBSRT_IMPORT_WORKER_FAULT")) {
        if (std::strcmp(fault, "crash") == 0) raise(SIGSEGV);
        if (std::strcmp(fault, "hang") == 0)
            for (;;) pause();
    }
}

// A niced worker runs batch work (IsolationLimits::nice: a job's file): its job
// already runs files side by side in lanes that fill the cores, so threads of
// its own (the import's face conversion, BRepMesh, the fidelity check) only
// oversubscribe them, slowing the job and the interactive renders it must
// yield to. Measured (bench/fairness.sh, the job phase): the clients' p99 with
// the job 2.7-4.6x their p99 alone with the worker's threads, 1.9-2.4x with one.
std::optional<tbb::global_control> batch_thread_limit() {
    std::optional<tbb::global_control> one;
    errno = 0;
    if (const int nice = getpriority(PRIO_PROCESS, 0); nice > 0 && errno == 0)
        one.emplace(tbb::global_control::max_allowed_parallelism, 1);
    return one;
}

// Files that are neither STEP nor IGES are left to the worker's own, precise error.
void prescan_input(const std::string& path, const IsolationLimits& limits) {
    const CadFormat format = detect_format(path);
    // BREP is OCCT's own format: no pre-scan of its own (the child's limits hold).
    if (format == CadFormat::step || format == CadFormat::iges) prescan_cad_file(path, format, limits.prescan);
}

// A line break inside a field of the report would split it.
std::string one_line(std::string s) {
    std::replace(s.begin(), s.end(), '\n', ' ');
    return s;
}

void write_error_file(const std::string& path, ErrorCode code, const std::string& message) {
    std::ofstream e(path, std::ios::binary | std::ios::trunc);
    e << error_code_name(code) << '\n' << message;
}

}  // namespace

namespace {

using Clock = std::chrono::steady_clock;
double ms_between(Clock::time_point a, Clock::time_point b) {
    return std::chrono::duration<double, std::milli>(b - a).count();
}

// The call's stages from its time points (start, child started, child done,
// end): the pre-scan before the child, the transfer after it, and the
// isolation what the whole call leaves beside them and the child's own stages
// (measured inside the child's lifetime on the same monotonic clock, so never
// more than its wait): they cover the call exactly, by construction.
IsolationTimings call_timings(Clock::time_point t0, Clock::time_point t_child, Clock::time_point t_read,
                              Clock::time_point t_end, double child_stages_ms) {
    IsolationTimings t;
    t.total_ms = ms_between(t0, t_end);
    t.prescan_ms = ms_between(t0, t_child);
    t.transfer_ms = ms_between(t_read, t_end);
    t.isolation_ms = t.total_ms - t.prescan_ms - t.transfer_ms - child_stages_ms;
    return t;
}

ConvertReport parse_convert_report(const std::string& text) {
    std::istringstream in(text);
    ConvertReport r;
    int in_format = 0, out_format = 0, output = 0;
    if (!(in >> in_format >> out_format >> output >> r.faces >> r.triangles >> r.unmeshed_faces >>
          r.degenerate_triangles >> r.read_ms >> r.mesh_ms >> r.write_ms >> r.verify_ms) ||
        in_format < 0 || in_format > static_cast<int>(CadFormat::brep) || out_format < 0 ||
        out_format > static_cast<int>(CadFormat::brep) || output < 0 ||
        output > static_cast<int>(ConversionFormat::obj))
        throw Error(ErrorCode::internal, "conversion worker wrote no valid report");
    r.in_format = static_cast<CadFormat>(in_format);
    r.out_format = static_cast<CadFormat>(out_format);
    r.output = static_cast<ConversionFormat>(output);
    std::string line;
    std::getline(in, line);  // the rest of the numbers' line
    std::getline(in, r.in_units);
    std::getline(in, r.out_units);
    std::getline(in, r.fidelity);
    while (std::getline(in, line))
        if (!line.empty()) r.warnings.push_back(line);
    return r;
}

}  // namespace

Scene import_isolated(const std::string& path, const ImportOptions& options, const IsolationLimits& limits,
                      IsolationTimings* timings) {
    const auto t0 = Clock::now();
    prescan_input(path, limits);
    const auto t_child = Clock::now();
    const std::string exe = worker_executable(limits);
    ScratchFiles scratch;
    make_scratch(scratch, scratch_dir_of(limits), "nurbsrt-import");
    std::vector<std::string> args = {exe, "import-worker", path, scratch.scene};
    for (std::string& a : import_options_to_args(options)) args.push_back(std::move(a));
    run_worker(std::move(args), limits, scratch.error, "import", path);
    const auto t_read = Clock::now();
    Scene scene = read_scene_file(scratch.scene);
    scratch.remove();  // inside the transfer stage: the stages cover the whole call
    if (timings) {
        const ImportTimings& c = scene.timings;
        *timings = call_timings(t0, t_child, t_read, Clock::now(), c.read_ms + c.nurbs_convert_ms + c.mesh_ms);
    }
    return scene;
}

ConvertReport convert_isolated(const std::string& in_path, const std::string& out_path, const IsolationLimits& limits,
                               IsolationTimings* timings, const ConvertOptions& options) {
    const auto t0 = Clock::now();
    prescan_input(in_path, limits);
    const auto t_child = Clock::now();
    const std::string exe = worker_executable(limits);
    ScratchFiles scratch;  // here: the worker's report (and its error file)
    make_scratch(scratch, scratch_dir_of(limits), "nurbsrt-convert");
    std::vector<std::string> args = {exe, "convert-worker", in_path, out_path, scratch.scene};
    for (std::string& a : convert_options_to_args(options)) args.push_back(std::move(a));
    run_worker(std::move(args), limits, scratch.error, "conversion", in_path);
    const auto t_read = Clock::now();
    ConvertReport r = parse_convert_report(read_small_file(scratch.scene));
    scratch.remove();  // inside the transfer stage: the stages cover the whole call
    if (timings)
        *timings = call_timings(t0, t_child, t_read, Clock::now(), r.read_ms + r.mesh_ms + r.write_ms + r.verify_ms);
    return r;
}

namespace {

// The report convert_isolated reads (parse_convert_report): the numbers on one
// line, then the units and the fidelity report a line each (any may be empty),
// then one warning a line.
void write_convert_report(const std::string& report_path, const ConvertReport& r) {
    std::ofstream out(report_path, std::ios::binary | std::ios::trunc);
    out.precision(17);
    out << static_cast<int>(r.in_format) << ' ' << static_cast<int>(r.out_format) << ' ' << static_cast<int>(r.output)
        << ' ' << r.faces << ' ' << r.triangles << ' ' << r.unmeshed_faces << ' ' << r.degenerate_triangles << ' '
        << r.read_ms << ' ' << r.mesh_ms << ' ' << r.write_ms << ' ' << r.verify_ms << '\n'
        << one_line(r.in_units) << '\n'
        << one_line(r.out_units) << '\n'
        << one_line(r.fidelity) << '\n';  // compact JSON: one line
    for (const std::string& w : r.warnings) out << one_line(w) << '\n';
    if (!out) throw Error(ErrorCode::io, "cannot write the conversion report");
}

// Runs `work`; an error it throws is written to `error_path` as the parent
// reads it (`what`: "import", "conversion", for the out-of-memory message).
// Returns whether it succeeded.
bool record_outcome(const std::string& error_path, const char* what, const std::function<void()>& work) {
    try {
        work();
        return true;
    } catch (const Error& e) {
        write_error_file(error_path, e.code(), e.what());
    } catch (const std::bad_alloc&) {
        write_error_file(error_path, ErrorCode::limit_exceeded,
                         std::string(what) + " ran out of memory (memory limit of the " + what + " process)");
    } catch (const std::exception& e) {
        write_error_file(error_path, ErrorCode::internal, e.what());
    }
    return false;
}

}  // namespace

int run_convert_worker(const std::string& in_path, const std::string& out_path, const std::string& report_path,
                       const ConvertOptions& options) {
    apply_fault_hook();
    const std::optional<tbb::global_control> threads = batch_thread_limit();
    return record_outcome(report_path + ".error", "conversion",
                          [&] { write_convert_report(report_path, convert_file(in_path, out_path, options)); })
               ? 0
               : 1;
}

int run_import_worker(const std::string& in_path, const std::string& out_path, const ImportOptions& options) {
    apply_fault_hook();
    const std::optional<tbb::global_control> threads = batch_thread_limit();
    return record_outcome(out_path + ".error", "import",
                          [&] { write_scene_file(import_file(in_path, options), out_path); })
               ? 0
               : 1;
}

namespace {

// Marks the file worker's positional argument holding a conversion's options.
constexpr const char* kConversionOptionsPrefix = "convert:";

// One scratch file of a file worker's item, with its ".error" companion
// (held by pointer: ScratchFiles removes its files when destroyed, so it is never copied).
std::unique_ptr<ScratchFiles> item_scratch(const std::string& dir, const char* stem) {
    auto f = std::make_unique<ScratchFiles>();
    make_scratch(*f, dir, stem);
    return f;
}

// The item's error, when the child wrote one.
std::optional<Error> item_error(const std::string& error_path) {
    const std::string err = read_small_file(error_path);
    const size_t nl = err.find('\n');
    if (nl == std::string::npos) return std::nullopt;
    return Error(error_code_from_name(err.substr(0, nl)).value_or(ErrorCode::internal), err.substr(nl + 1));
}

}  // namespace

FileResult process_file_isolated(const std::string& path, const FilePlan& plan, const IsolationLimits& limits) {
    const auto t0 = Clock::now();
    prescan_input(path, limits);
    const auto t_child = Clock::now();
    const std::string dir = scratch_dir_of(limits);
    const std::unique_ptr<ScratchFiles> summary = item_scratch(dir, "nurbsrt-file");
    std::unique_ptr<ScratchFiles> scene;
    if (plan.scene) scene = item_scratch(dir, "nurbsrt-import");
    std::vector<std::unique_ptr<ScratchFiles>> reports;
    for (size_t i = 0; i < plan.conversions.size(); ++i) reports.push_back(item_scratch(dir, "nurbsrt-convert"));
    std::vector<std::string> args = {worker_executable(limits), "file-worker", path, summary->scene,
                                     scene ? scene->scene : std::string("-")};
    for (size_t i = 0; i < plan.conversions.size(); ++i) {
        args.push_back(plan.conversions[i]);
        args.push_back(reports[i]->scene);
        // The conversion's options as one positional argument (the import's
        // are the "--" ones): its worker arguments, comma-joined, after a prefix.
        std::string joined = kConversionOptionsPrefix;
        const ConvertOptions options =
            i < plan.conversion_options.size() ? plan.conversion_options[i] : ConvertOptions{};
        for (const std::string& a : convert_options_to_args(options))
            joined += (joined.size() > std::strlen(kConversionOptionsPrefix) ? "," : "") + a;
        args.push_back(std::move(joined));
    }
    for (std::string& a : import_options_to_args(plan.options)) args.push_back(std::move(a));
    run_worker(std::move(args), limits, summary->error, "import", path);
    const auto t_read = Clock::now();

    FileResult r;
    if (!(std::istringstream(read_small_file(summary->scene)) >> r.reads >> r.uses >> r.read_ms))
        throw Error(ErrorCode::internal, "file worker wrote no valid summary");
    double child_stages_ms = 0;
    if (scene) {
        r.scene_error = item_error(scene->error);
        if (!r.scene_error) {
            r.scene = read_scene_file(scene->scene);
            const ImportTimings& c = r.scene->timings;
            child_stages_ms += c.read_ms + c.nurbs_convert_ms + c.mesh_ms;
        }
    }
    for (const std::unique_ptr<ScratchFiles>& report : reports) {
        FileResult::Conversion c;
        c.error = item_error(report->error);
        if (!c.error) {
            c.report = parse_convert_report(read_small_file(report->scene));
            child_stages_ms += c.report->read_ms + c.report->mesh_ms + c.report->write_ms + c.report->verify_ms;
        }
        r.conversions.push_back(std::move(c));
    }
    r.timings = call_timings(t0, t_child, t_read, Clock::now(), child_stages_ms);
    return r;
}

int run_file_worker(const std::vector<std::string>& args) {
    apply_fault_hook();
    const std::optional<tbb::global_control> threads = batch_thread_limit();
    std::vector<std::string> positional, options;
    for (const std::string& a : args) (a.rfind("--", 0) == 0 ? options : positional).push_back(a);
    if (positional.size() < 3 || positional.size() % 3 != 0) {
        std::fprintf(stderr, "file-worker: IN SUMMARY SCENE|- [OUT REPORT OPTIONS]... [options]\n");
        return 2;
    }
    const std::string& in_path = positional[0];
    const std::string& summary_path = positional[1];
    const std::string& scene_path = positional[2];
    // A bad option is the parent's fault: the whole run fails with it.
    ImportOptions import_options;
    if (!record_outcome(summary_path + ".error", "import", [&] { import_options = import_options_from_args(options); }))
        return 1;
    SharedRead read(in_path);
    // The scene first: the renders wait for it, the conversions' files for nothing.
    if (scene_path != "-")
        record_outcome(scene_path + ".error", "import",
                       [&] { write_scene_file(import_file(in_path, import_options), scene_path); });
    // Then the conversions, in the plan's order: convert_file takes the
    // earlier uses' meshes off the shared shape, so each writes what it would alone.
    for (size_t i = 3; i + 2 < positional.size(); i += 3)
        record_outcome(positional[i + 1] + ".error", "conversion", [&] {
            const std::string& joined = positional[i + 2];
            if (joined.rfind(kConversionOptionsPrefix, 0) != 0)
                throw Error(ErrorCode::invalid_argument, "bad conversion options: " + joined);
            std::vector<std::string> args;
            std::istringstream list(joined.substr(std::strlen(kConversionOptionsPrefix)));
            for (std::string a; std::getline(list, a, ',');) args.push_back(a);
            write_convert_report(positional[i + 1],
                                 convert_file(in_path, positional[i], convert_options_from_args(args)));
        });
    return record_outcome(summary_path + ".error", "import",
                          [&] {
                              std::ofstream out(summary_path, std::ios::binary | std::ios::trunc);
                              out.precision(17);
                              out << read.reads() << ' ' << read.uses() << ' ' << read.read_ms() << '\n';
                              if (!out) throw Error(ErrorCode::io, "cannot write the file worker's summary");
                          })
               ? 0
               : 1;
}

}  // namespace nurbsrt
