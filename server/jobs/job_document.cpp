#include "server/jobs/job_document.h"

#include <algorithm>

#include <nlohmann/json.hpp>

#include <set>
#include <string>

#include "core/error.h"
#include "options/render_request.h"
#include "server/common/rfc3339.h"
#include "server/jobs/job_spec.h"

namespace nurbsrt::server {
namespace {

using nlohmann::json;

// RFC 3339 UTC with milliseconds, or null for "not yet".
json timestamp(int64_t ms) {
    if (ms <= 0) return nullptr;
    return rfc3339_utc(ms);
}

json span(int64_t from, int64_t to) {
    if (from <= 0 || to <= 0) return nullptr;
    // Stamps come from the system clock, which a time service may step back
    // between two of them (a -32 ms queue time was seen once): a span is never negative.
    return std::max<int64_t>(0, to - from);
}

json parse_or_null(const std::string& text) {
    if (text.empty()) return nullptr;
    json j = json::parse(text, nullptr, false);
    return j.is_discarded() ? json(nullptr) : j;
}

json callback_json(const JobRecord& j) {
    const CallbackStatus& c = j.callback;
    json out = {{"url", j.callback_url},
                {"state", callback_state_name(c.state)},
                {"attempts", c.attempts},
                {"last_status", c.last_status > 0 ? json(c.last_status) : json(nullptr)},
                {"last_error", c.last_error.empty() ? json(nullptr) : json(c.last_error)},
                {"next_attempt_at", c.state == CallbackState::pending ? timestamp(c.due_ms) : json(nullptr)},
                {"finished_at", timestamp(c.done_ms)}};
    return out;
}

// A conversion's options as resolved (every default named), whatever the
// stored text spells: conversion_request_json of what it parses to.
json resolved_conversion_options(const std::string& options_json) {
    try {
        return json::parse(conversion_request_json(parse_conversion_request(options_json)));
    } catch (const Error&) {
        return parse_or_null(options_json);  // written by something else than this parser
    }
}

// The files of an output: every one when it succeeded (`bytes` from its
// result), else those already in place (`placed`), each with its view.
json artifacts_json(const JobRecord& j, const JobOutput& o, const json& result, const PlacedArtifact& placed) {
    json list = json::array();
    std::vector<ArtifactFile> files;
    try {
        files = output_artifacts(o);
    } catch (const Error&) {
        files = {{o.artifact, "", o.content_type}};  // options this build no longer reads: the one name
    }
    const bool succeeded = o.state == JobState::succeeded;
    if (!succeeded && (!placed || files.size() < 2)) return list;
    const json sizes = result.is_object() ? result.value("artifacts", json::array()) : json::array();
    for (size_t i = 0; i < files.size(); ++i) {
        int64_t bytes = -1;
        if (succeeded)
            bytes = files.size() == 1  ? o.artifact_bytes
                    : i < sizes.size() ? sizes[i].value("bytes", int64_t{-1})
                                       : int64_t{-1};
        if (bytes < 0 && placed) bytes = placed(files[i].name);
        if (bytes < 0) continue;
        json a = {{"name", files[i].name},
                  {"url", job_url(j.id) + "/artifacts/" + files[i].name},
                  {"content_type", files[i].content_type},
                  {"bytes", bytes}};
        if (!files[i].view.empty()) a["view"] = files[i].view;
        list.push_back(std::move(a));
    }
    return list;
}

}  // namespace

std::string job_url(const std::string& id) { return "/v1/jobs/" + id; }

json job_json(const JobRecord& j, const PlacedArtifact& placed) {
    json files = json::array();
    for (const JobInput& in : j.inputs)
        files.push_back({{"index", in.index}, {"filename", in.filename}, {"format", in.format}, {"bytes", in.bytes}});
    json outputs = json::array();
    double progress = 0;
    int succeeded = 0, failed = 0, reused = 0, artifact_count = 0;
    int64_t artifact_bytes = 0;
    std::set<std::string> reads;  // the reads of input files that served the outputs so far
    for (const JobOutput& o : j.outputs) {
        json out = {{"index", o.index},
                    {"file", o.file},
                    {"type", output_kind_name(o.kind)},
                    {"format", artifact_format(o.artifact)},
                    {"state", job_state_name(o.state)},
                    {"progress", o.state == JobState::succeeded ? 1.0 : o.progress},
                    {"started_at", timestamp(o.started_ms)},
                    {"finished_at", timestamp(o.finished_ms)},
                    {"duration_ms", span(o.started_ms, o.finished_ms)}};
        const json options =
            o.kind == OutputKind::render ? parse_or_null(o.options_json) : resolved_conversion_options(o.options_json);
        out["options"] = options.is_object() ? options : json::object();
        if (!o.error_code.empty()) out["error"] = {{"code", o.error_code}, {"message", o.error_message}};
        const json result = parse_or_null(o.result_json);
        // Every file of the output (several: a view each, OBJ and its .mtl),
        // those of a running one as they are placed.
        const json files = artifacts_json(j, o, result, placed);
        artifact_count += static_cast<int>(files.size());
        if (!files.empty() || o.state == JobState::succeeded) out["artifacts"] = files;
        if (o.state == JobState::succeeded) {
            // The first file, as the output's own (a single file's name, size and type).
            out["artifact"] = files.empty() ? json{{"name", o.artifact},
                                                   {"url", job_url(j.id) + "/artifacts/" + o.artifact},
                                                   {"content_type", o.content_type},
                                                   {"bytes", o.artifact_bytes}}
                                            : files.front();
            if (result.is_object()) out[o.kind == OutputKind::render ? "statistics" : "report"] = result;
            if (result.is_object() && result.contains("read") && result["read"].contains("id"))
                reads.insert(result["read"]["id"].dump());
            if (result.is_object() && result.value("reused", false)) ++reused;
            ++succeeded;
            artifact_bytes += o.artifact_bytes;
        }
        if (o.state == JobState::failed) ++failed;
        progress += o.state == JobState::succeeded || o.state == JobState::failed ? 1.0 : o.progress;
        outputs.push_back(std::move(out));
    }
    json body = {
        {"id", j.id},
        {"url", job_url(j.id)},
        {"state", job_state_name(j.state)},
        {"progress", j.outputs.empty() ? 0.0 : progress / static_cast<double>(j.outputs.size())},
        {"attempts", j.attempts},
        {"created_at", timestamp(j.created_ms)},
        {"started_at", timestamp(j.started_ms)},
        {"finished_at", timestamp(j.finished_ms)},
        {"timings_ms", {{"queued", span(j.created_ms, j.started_ms)}, {"run", span(j.started_ms, j.finished_ms)}}},
        {"statistics",
         {{"outputs", j.outputs.size()},
          {"succeeded", succeeded},
          {"failed", failed},
          {"artifacts", artifact_count},
          {"artifact_bytes", artifact_bytes},
          {"reads", reads.size()},
          {"reused", reused}}},
        {"files", files},
        {"outputs", outputs}};
    if (!j.error_code.empty()) body["error"] = {{"code", j.error_code}, {"message", j.error_message}};
    if (!j.callback_url.empty()) body["callback"] = callback_json(j);
    return body;
}

std::string job_webhook_body(const JobRecord& job) {
    json body = job_json(job);
    body.erase("callback");
    return body.dump(-1, ' ', false, json::error_handler_t::replace);
}

}  // namespace nurbsrt::server
