// One input file of a claimed job: everything its outputs need from one read.
// STEP/IGES parsing is most of an import and of a conversion alike, so the
// file's child (process_file_isolated, importer/isolated.h) reads it once,
// writes the file's conversions itself, where the OCCT document lives, and
// hands back the scene, which is prepared here once for all the file's renders.
#include <nlohmann/json.hpp>

#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

#include "core/error.h"
#include "importer/isolated.h"
#include "options/render_request.h"
#include "renderer/prepared_scene.h"
#include "server/common/request_log.h"
#include "server/common/scratch.h"
#include "server/common/service_error.h"
#include "server/common/sha256.h"
#include "server/jobs/job_runner.h"
#include "server/jobs/job_spec.h"
#include "server/render/context.h"
#include "server/render/render_service.h"
#include "server/render/scene_cache.h"
#include "server/render/stage_timings.h"
#include "server/render/work.h"
#include "server/store/durable_file.h"

namespace nurbsrt::server {
namespace {

nlohmann::json file_read_json(const FileRead& read) {
    return {{"id", read.id}, {"file", read.file}, {"served", read.served}, {"read_ms", read.read_ms}};
}

// The result of an artifact an earlier job made, for this output that reuses
// it: the same statistics or report (how it was made), without that job's
// read (none served this job) and saying it was reused.
nlohmann::json reused_result(const std::string& made) {
    nlohmann::json result = nlohmann::json::parse(made, nullptr, false);
    if (!result.is_object()) result = nlohmann::json::object();
    result.erase("read");
    result["reused"] = true;
    return result;
}

std::string dump_result(const nlohmann::json& result) {
    return result.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

// A conversion's report as POST /v1/conversions answers it: its own stages
// (read, mesh, write, verify: read is 0 where another output's use paid it)
// and the child's share of the file's run.
nlohmann::json conversion_result(const ConvertReport& report, const FileResult& file, StageClock stages,
                                 const FileRead& read) {
    add_conversion_stages(report, file.timings, stages);
    stages.mark("isolation");
    nlohmann::json result = {{"input_format", format_name(report.in_format)},
                             {"output_format", conversion_format_name(report.output)},
                             {"faces", report.faces},
                             {"warnings", report.warnings},
                             {"read", file_read_json(read)}};
    // The fidelity report (importer.h), as POST /v1/conversions answers it; none for NURBS JSON.
    if (!report.fidelity.empty()) result["fidelity"] = nlohmann::json::parse(report.fidelity);
    // The artifact is already in place (partial): no transfer; this result is the answer.
    stages.mark("response");
    result["timings_ms"] = stage_timings_json(stages, kConversionStages);
    return result;
}

// OBJ's .obj names its .mtl by the partial name it was written beside: renamed
// to the .mtl's artifact, so that the two downloaded side by side work.
void name_companion(const JobOutput& out, const std::vector<std::string>& partials) {
    const ConversionFormat format = parse_conversion_format(out.options_json);
    const std::string written = std::filesystem::path(partials.at(1)).filename().string();
    write_durably(partials.front(), with_companion_renamed(read_file_bytes(partials.front()), format, written,
                                                           output_artifacts(out).at(1).name));
}

}  // namespace

void JobService::run_file(const JobClaim& job, const std::vector<int>& indices,
                          const std::shared_ptr<std::atomic<bool>>& cancel) {
    const int file = job.outputs.at(static_cast<size_t>(indices.front())).file;
    const std::string input = input_path(job.id, file);
    // The file's digest: the key of its scene in the cache and of its artifacts for reuse.
    std::string content_sha256;
    try {
        content_sha256 = sha256_hex(read_file_bytes(input));
    } catch (const std::exception& e) {  // the stored input cannot be read: every output of it fails
        for (const int index : indices) output_failed(job, job.outputs.at(static_cast<size_t>(index)), e);
        return;
    }
    std::vector<const JobOutput*> renders, conversions;
    for (const int index : reuse_artifacts(job, indices, content_sha256, cancel)) {
        const JobOutput& out = job.outputs.at(static_cast<size_t>(index));
        (out.kind == OutputKind::render ? renders : conversions).push_back(&out);
    }
    // Ends quietly when the job was canceled or deleted, else fails `outs` with `e`.
    auto ended = [&](const std::vector<const JobOutput*>& outs, const std::exception& e) {
        const auto* error = dynamic_cast<const Error*>(&e);
        if (error && error->code() == ErrorCode::canceled && (cancel->load() || !store_->running(job.id))) return;
        for (const JobOutput* out : outs) output_failed(job, *out, e);
    };
    FileRead read;  // the read that served the renders; none when their scene came from the cache
    read.file = file;
    bool child_ran = false;
    std::shared_ptr<const PreparedScene> prepared;
    if (!renders.empty()) {
        const std::string key = scene_cache_key(content_sha256, ImportOptions{});
        // The cache's single flight: a scene already cached (a stored file
        // rendered before, another job's file) or being imported by another
        // user of the same bytes serves the renders without a read of this
        // file's own; else this file's child reads it, with its conversions.
        SceneCache::Source source = SceneCache::Source::loaded;
        try {
            prepared = ctx_.cache.get_or_load(
                key,
                [&] {
                    child_ran = true;
                    return run_file_child(job, input, conversions, true, cancel, read, content_sha256);
                },
                source);
            ctx_.metrics.count_cache(source != SceneCache::Source::loaded);
        } catch (const std::exception& e) {
            ended(renders, e);  // the child's own failure already ended its conversions
            if (child_ran) return;
        }
        if (source != SceneCache::Source::loaded) read.id.clear();  // no read of this file served them
    }
    if (!child_ran && !conversions.empty()) {
        FileRead conversions_read = read;
        try {
            run_file_child(job, input, conversions, false, cancel, conversions_read, content_sha256);
        } catch (const std::exception& e) {
            ended({}, e);  // its conversions are ended; nothing else is left to it
            return;
        }
    }
    if (!prepared) return;
    for (const JobOutput* out : renders) {
        if (cancel->load()) return;
        try {
            run_render(job, *out, prepared, read, cancel, content_sha256);
        } catch (const std::exception& e) {
            ended({out}, e);
        }
    }
}

std::shared_ptr<const PreparedScene> JobService::run_file_child(const JobClaim& job, const std::string& input,
                                                                const std::vector<const JobOutput*>& conversions,
                                                                bool want_scene,
                                                                const std::shared_ptr<std::atomic<bool>>& cancel,
                                                                FileRead& read, const std::string& content_sha256) {
    const auto t0 = std::chrono::steady_clock::now();
    auto fail_all = [&](const std::exception& e) {
        for (const JobOutput* out : conversions) output_failed(job, *out, e);
    };
    // The child takes an import slot, as a conversion or an uncached render
    // does, and keeps it while the scene is prepared (as imported_scene does);
    // accepted work waits for it as long as it takes, in its place.
    const AdmissionWait patient{true, [&cancel] { return cancel->load(); }};
    std::shared_ptr<AdmissionGate::Ticket> ticket;
    try {
        ticket = admit(ctx_, ctx_.gate, 0, patient);
    } catch (const std::exception& e) {
        const auto* error = dynamic_cast<const Error*>(&e);
        if (!error || error->code() != ErrorCode::canceled || !cancel->load()) fail_all(e);
        throw;
    }
    StageClock queued(t0);  // no upload: the input is on disk
    queued.mark("queue");
    // A conversion runs from its child's start; a render from when its scene is
    // there (so a render's span is its frame, as for a cached scene).
    for (const JobOutput* out : conversions)
        if (!store_->output_running(job.id, out->index, unix_now_ms(), job.lease))
            throw Error(ErrorCode::canceled, "the job was deleted");

    FilePlan plan;
    plan.scene = want_scene;
    // Each output's files as it writes them: the converted file, and OBJ's .mtl beside it.
    std::vector<std::vector<std::string>> partials;
    for (const JobOutput* out : conversions) {
        partials.push_back(partial_paths(job, *out));
        plan.conversions.push_back(partials.back().front());
        plan.conversion_options.push_back(parse_conversion_request(out->options_json).options);
    }
    auto remove_partials = [&](size_t i) {
        std::error_code ec;
        for (const std::string& partial : partials[i]) std::filesystem::remove(partial, ec);
    };
    FileResult result;
    try {
        IsolationLimits limits = isolation_limits(ctx_);
        limits.should_stop = [cancel] { return cancel->load(); };  // a deleted job's child is killed
        limits.nice = kJobNice;                                    // as the runner's threads (JobService::run_loop)
        result = process_file_isolated(input, plan, limits);
    } catch (const std::exception& e) {
        // Any failure of the child's run (not only an Error: reading its scene
        // may throw bad_alloc) ends every output of the file, never leaves them
        // running: the conversions here, the renders by the caller.
        ticket.reset();
        for (size_t i = 0; i < partials.size(); ++i) remove_partials(i);
        const auto* error = dynamic_cast<const Error*>(&e);
        if (error && error->code() == ErrorCode::canceled && cancel->load()) throw;
        ctx_.metrics.count_import_failure(error ? error_code_name(error->code()) : "internal");
        fail_all(e);
        throw;
    }
    std::shared_ptr<const PreparedScene> prepared;
    std::exception_ptr scene_failure;
    if (want_scene) {
        try {
            if (result.scene_error) {
                ctx_.metrics.count_import_failure(error_code_name(result.scene_error->code()));
                throw *result.scene_error;
            }
            prepared = std::make_shared<const PreparedScene>(
                prepare(std::make_shared<const Scene>(std::move(*result.scene)), kJobRenderThreads));
        } catch (const std::exception&) {
            scene_failure = std::current_exception();
        }
    }
    ticket.reset();
    read = FileRead{new_request_id(), read.file, result.uses, result.read_ms};
    log_event("job_file_read", nlohmann::json{{"job_id", job.id},
                                              {"file", read.file},
                                              {"read", read.id},
                                              {"reads", result.reads},
                                              {"served", result.uses},
                                              {"read_ms", result.read_ms}}
                                   .dump());
    for (size_t i = 0; i < conversions.size(); ++i) {
        const JobOutput& out = *conversions[i];
        const FileResult::Conversion& c = result.conversions.at(i);
        try {
            if (c.error) {
                ctx_.metrics.count_import_failure(error_code_name(c.error->code()));
                remove_partials(i);
                throw *c.error;
            }
            if (parse_conversion_request(out.options_json).strict && !c.report->warnings.empty()) {
                remove_partials(i);
                throw strict_refusal(c.report->warnings);
            }
            if (partials[i].size() > 1) name_companion(out, partials[i]);
            store_artifact(job, out, partials[i], dump_result(conversion_result(*c.report, result, queued, read)),
                           cancel, content_sha256);
        } catch (const Error& e) {
            remove_partials(i);
            if (e.code() == ErrorCode::canceled && cancel->load()) throw;
            output_failed(job, out, e);
        } catch (const std::exception& e) {
            remove_partials(i);
            output_failed(job, out, e);
        }
    }
    if (scene_failure) std::rethrow_exception(scene_failure);
    return prepared;
}

void JobService::run_render(const JobClaim& job, const JobOutput& out,
                            const std::shared_ptr<const PreparedScene>& scene, const FileRead& read,
                            const std::shared_ptr<std::atomic<bool>>& cancel, const std::string& content_sha256) {
    if (!store_->output_running(job.id, out.index, unix_now_ms(), job.lease))
        throw Error(ErrorCode::canceled, "the job was deleted");
    const RenderRequest r = parse_render_options(out.options_json);
    RenderControl control;
    control.cancel = cancel;
    control.start = std::chrono::steady_clock::now();
    control.patient = true;
    control.scene = scene;
    // One thread: the frame's arena then has no slot for oneTBB's workers, which
    // are the process's, shared by every arena and not niced; the whole frame
    // runs in the render's own thread, niced as this runner's (kJobNice), and
    // the workers stay free for the clients' frames. The job's files still
    // fill the cores: its lanes render and read side by side.
    control.threads = kJobRenderThreads;
    // The callback may run after this job is gone (a canceled render stops
    // at its next block of rows): it holds the store, not `this`.
    auto last = std::make_shared<std::atomic<int>>(0);
    control.progress = [store = store_, id = job.id, index = out.index, lease = job.lease, last](double f) {
        const int pct = static_cast<int>(f * 100);
        if (pct >= last->load() + 5 && pct < 100) {
            last->store(pct);
            try {
                store->output_progress(id, index, f, lease);
            } catch (const Error&) {
                // Progress is advisory; the output's end state is what counts.
            }
        }
    };
    // Layout separate: each view is an artifact of its own, placed (and
    // downloadable) as soon as it is encoded; the output's progress counts the
    // views done and the running one's share.
    const std::vector<ArtifactFile> files = output_artifacts(out);
    std::vector<int64_t> sizes;
    int64_t placed = 0;
    // Shared: like the progress callback, it may outlive this call (see above).
    auto done = std::make_shared<std::atomic<size_t>>(0);
    if (r.layout == ViewLayout::separate) {
        const double views = static_cast<double>(files.size());
        control.progress = [progress = control.progress, done, views](double f) {
            progress((static_cast<double>(done->load()) + f) / views);
        };
        control.view_done = [&, views](const RenderedImage::View& view) {
            const std::string& name = files.at(done->load()).name;
            const std::string partial = partial_path(job, name);
            write_durably(partial, view.bytes);
            // The views done, past the callback's 5% steps, recorded before the
            // view is placed: whoever sees its file sees the progress that counts it.
            const double now_done = static_cast<double>(done->load() + 1) / views;
            if (now_done < 1) store_->output_progress(job.id, out.index, now_done, job.lease);
            sizes.push_back(place_artifact(job, name, partial, placed, cancel));
            placed += sizes.back();
            ++*done;
        };
    }
    const RenderedImage image = render_upload(ctx_, std::string(), r, control);
    nlohmann::json result = statistics_json(image);
    // The scene came from the cache (or another user's import of the same
    // bytes) unless this file's own read made it: RenderControl::scene alone
    // cannot tell, and would say hit.
    result["cache"] = read.id.empty() ? "hit" : "miss";
    if (!read.id.empty()) result["read"] = file_read_json(read);  // none: the scene was cached
    if (r.layout == ViewLayout::separate) {
        output_stored(job, out, sizes, dump_result(result), content_sha256);
        return;
    }
    const std::string partial = partial_path(job, out.artifact);
    write_durably(partial, image.bytes);
    store_artifact(job, out, {partial}, dump_result(result), cancel, content_sha256);
}

std::vector<int> JobService::reuse_artifacts(const JobClaim& job, const std::vector<int>& indices,
                                             const std::string& content_sha256,
                                             const std::shared_ptr<std::atomic<bool>>& cancel) {
    if (forced(job.id)) return indices;
    std::vector<int> rest;
    for (const int index : indices) {
        const JobOutput& out = job.outputs.at(static_cast<size_t>(index));
        // Each of its files kept under its own key; all of them, or the output is made anew.
        const std::vector<std::string> partials = partial_paths(job, out);
        const std::vector<ArtifactFile> files = output_artifacts(out);
        std::optional<std::string> made;
        for (size_t i = 0; i < files.size(); ++i) {
            made = reuse_.recall(ArtifactReuse::key(content_sha256, out, files[i].name), partials[i]);
            if (!made) break;
        }
        auto remove_partials = [&partials] {
            std::error_code ec;
            for (const std::string& partial : partials) std::filesystem::remove(partial, ec);
        };
        if (!made) {
            remove_partials();
            rest.push_back(index);
            continue;
        }
        try {
            if (!store_->output_running(job.id, out.index, unix_now_ms(), job.lease)) {  // deleted
                remove_partials();
                return {};
            }
            store_artifact(job, out, partials, dump_result(reused_result(*made)), cancel);
        } catch (const Error& e) {
            if (e.code() == ErrorCode::canceled && cancel->load()) return {};
            output_failed(job, out, e);
        } catch (const std::exception& e) {
            output_failed(job, out, e);
        }
    }
    return rest;
}

}  // namespace nurbsrt::server
