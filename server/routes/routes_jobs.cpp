// Batch jobs: POST /v1/jobs (several STEP/IGES files, uploaded or stored
// ones named by `file_id` (server/store/file_store.h), each with render and
// conversion outputs; everything is validated before 202 Accepted), GET
// /v1/jobs (paged), GET and DELETE /v1/jobs/{id}, and GET
// /v1/jobs/{id}/artifacts/{name}. The work itself is server/jobs/job_runner.h.
#include <httplib.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <ctime>
#include <filesystem>
#include <fstream>

#include "importer/importer.h"
#include "core/error.h"
#include "server/render/context.h"
#include "server/jobs/artifact_quota.h"
#include "server/http/etag.h"
#include "server/routes/handler_util.h"
#include "server/jobs/job_runner.h"
#include "server/jobs/job_document.h"
#include "server/jobs/job_spec.h"
#include "server/routes/routes.h"
#include "server/store/page_cursor.h"
#include "server/common/service_error.h"

namespace nurbsrt::server {
namespace {

using nlohmann::json;

// Retry-After of a job that is not done yet (202 on submit or cancel, 200 for
// a queued or running job), RFC 9110 §10.2.3: a poll a second later follows a
// typical render of a few hundred milliseconds to seconds closely, and costs
// one small GET.
constexpr int kJobPollAfterS = 1;

JobService& jobs_of(ServerContext& ctx) {
    if (!ctx.jobs) throw Error(ErrorCode::internal, "the job service is not running");
    return *ctx.jobs;
}

// The files of a job's outputs already in place (each view of a separate
// layout is, as soon as it is written): renamed into place whole, so there
// means complete. With a shared store the data directory is shared too.
PlacedArtifact placed_in(ServerContext& ctx, const std::string& id) {
    return [&ctx, id](const std::string& name) -> int64_t {
        std::error_code ec;
        const auto size = std::filesystem::file_size(jobs_of(ctx).artifact_path(id, name), ec);
        return ec ? -1 : static_cast<int64_t>(size);
    };
}

}  // namespace

void handle_job_submit(ServerContext& ctx, const httplib::Request& req, httplib::Response& res) {
    JobUpload up = read_job_upload(req, ctx.config.max_job_files);
    // Stored files are copied into the job's inputs when it is accepted (as
    // uploads are): deleting or expiring a stored file later never breaks a job.
    std::vector<StoredContent> stored;
    for (size_t i = 0; i < up.inputs.size(); ++i) {
        if (up.file_ids[i].empty()) continue;
        stored.push_back(ctx.files.open(up.file_ids[i]));
        const StoredFile& f = stored.back().file;
        up.inputs[i].filename = f.filename;
        up.inputs[i].format = f.format;
        up.inputs[i].bytes = f.bytes;
        up.bytes[i] = stored.back().bytes.get();
    }
    JobRecord job;
    job.inputs = std::move(up.inputs);
    JobSpec spec = parse_job_spec(*up.job_json, job.inputs, ctx.config);
    job.outputs = std::move(spec.outputs);
    job.callback_url = std::move(spec.callback_url);
    int64_t estimate = 0;
    for (const JobOutput& o : job.outputs)
        estimate += estimated_artifact_bytes(o, job.inputs[static_cast<size_t>(o.file)].bytes);
    try {
        check_artifact_quota(jobs_of(ctx).store().artifact_bytes(), estimate, ctx.config.max_artifact_bytes,
                             "the job's artifacts, estimated");
    } catch (const Error& e) {
        // 507 Insufficient Storage (RFC 4918 §11.5), as for stored files: the
        // request is fine, the service cannot keep its results now.
        send_problem_with_status(res, 507, e.code(), e.what());
        return;
    }
    jobs_of(ctx).submit(job, up.bytes, spec.force);
    res.set_header("Location", job_url(job.id));
    res.set_header("Retry-After", std::to_string(kJobPollAfterS));
    send_json(res, job_json(job), 202);
}

void handle_job_list(ServerContext& ctx, const httplib::Request& req, httplib::Response& res) {
    const PageQuery q = parse_page_query(req, {"state"});
    const int limit = q.limit;
    const bool newest = q.newest;
    std::optional<JobState> state;
    if (req.has_param("state")) {
        state = parse_job_state(req.get_param_value("state"));
        if (!state)
            throw Error(ErrorCode::invalid_argument, "'state' must be queued, running, succeeded, failed or canceled");
    }
    std::optional<int64_t> after;
    if (req.has_param("cursor")) after = parse_page_cursor(req.get_param_value("cursor"), newest, false).key;
    const JobPage page = jobs_of(ctx).store().list(state, newest, limit, after);
    json list = json::array();
    for (const JobRecord& j : page.jobs) list.push_back(job_json(j, placed_in(ctx, j.id)));
    send_json(res,
              {{"jobs", list},
               {"next_cursor", page.next_after ? json(format_page_cursor(newest, *page.next_after)) : json(nullptr)}});
}

std::string checked_id(const std::string& id) {
    if (!valid_job_id(id)) throw ServiceError(ServiceCode::not_found, "no such job");
    return id;
}

void handle_job_get(ServerContext& ctx, const httplib::Request& req, httplib::Response& res) {
    const std::string id = checked_id(req.matches[1]);
    const auto job = jobs_of(ctx).store().get(id);
    if (!job) throw ServiceError(ServiceCode::not_found, "no such job");
    if (!is_finished(job->state)) res.set_header("Retry-After", std::to_string(kJobPollAfterS));
    send_json(res, job_json(*job, placed_in(ctx, id)));
}

void handle_job_delete(ServerContext& ctx, const httplib::Request& req, httplib::Response& res) {
    const std::string id = checked_id(req.matches[1]);
    switch (jobs_of(ctx).remove(id)) {
        case JobStore::DeleteOutcome::not_found:
            throw ServiceError(ServiceCode::not_found, "no such job");
        case JobStore::DeleteOutcome::removed:
            res.status = 204;
            return;
        case JobStore::DeleteOutcome::canceling: {
            const auto job = jobs_of(ctx).store().get(id);
            if (!job) {  // the runner already removed it
                res.status = 204;
                return;
            }
            res.set_header("Retry-After", std::to_string(kJobPollAfterS));
            send_json(res, job_json(*job), 202);
            return;
        }
    }
}

void handle_job_artifact(ServerContext& ctx, const httplib::Request& req, httplib::Response& res) {
    const std::string id = checked_id(req.matches[1]);
    const std::string name = req.matches[2];
    if (!valid_artifact_name(name)) throw ServiceError(ServiceCode::not_found, "no such artifact");
    const auto job = jobs_of(ctx).store().get(id);
    if (!job) throw ServiceError(ServiceCode::not_found, "no such job");
    for (const JobOutput& o : job->outputs) {
        const std::vector<ArtifactFile> files = output_artifacts(o);
        const auto file =
            std::find_if(files.begin(), files.end(), [&](const ArtifactFile& f) { return f.name == name; });
        if (file == files.end()) continue;
        // The path is built from the stored id and name, both generated by the service.
        const std::string path = jobs_of(ctx).artifact_path(job->id, file->name);
        // A running output's file is there once placed whole (a view of a separate layout).
        std::error_code ec;
        const bool placed = o.state == JobState::running && std::filesystem::is_regular_file(path, ec);
        if (o.state != JobState::succeeded && !placed)
            throw ServiceError(ServiceCode::not_found,
                               "artifact " + name + " is not available: its output is " + job_state_name(o.state));
        auto in = std::make_shared<std::ifstream>(path, std::ios::binary);
        if (!*in) throw ServiceError(ServiceCode::not_found, "artifact " + name + " is gone");
        in->seekg(0, std::ios::end);
        const auto size = static_cast<size_t>(in->tellg());
        in->seekg(0);
        // An artifact never changes once written: its content hash is a strong
        // validator, and a client may keep it for as long as the job is kept
        // (private: it may be behind an API key; immutable: no revalidation
        // while fresh, RFC 8246).
        const std::string etag = file_etag(path);
        res.set_header("ETag", etag);
        res.set_header(
            "Cache-Control",
            "private, max-age=" + std::to_string(static_cast<long long>(ctx.config.job_retention_s)) + ", immutable");
        if (req.has_header("If-None-Match") && if_none_match_matches(req.get_header_value("If-None-Match"), etag)) {
            // 304 without content (RFC 9110 §15.4.5); its Content-Length is the
            // artifact's (§8.6), else cpp-httplib would add "Content-Length: 0".
            res.status = 304;
            res.set_header("Content-Length", std::to_string(size));
            return;
        }
        res.set_header("Content-Disposition", "attachment; filename=\"" + file->name + "\"");
        res.set_content_provider(size, file->content_type.c_str(),
                                 [in](size_t offset, size_t length, httplib::DataSink& sink) {
                                     std::vector<char> buf(std::min<size_t>(length, 1 << 16));
                                     in->seekg(static_cast<std::streamoff>(offset));
                                     in->read(buf.data(), static_cast<std::streamsize>(buf.size()));
                                     const auto n = in->gcount();
                                     if (n <= 0) return false;
                                     sink.write(buf.data(), static_cast<size_t>(n));
                                     return true;
                                 });
        return;
    }
    throw ServiceError(ServiceCode::not_found, "no such artifact");
}

}  // namespace nurbsrt::server
