#include "server/store/job_store.h"

#include <chrono>

#include "core/error.h"

namespace nurbsrt::server {

int64_t unix_now_ms() {
    return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch())
        .count();
}

const char* job_state_name(JobState s) {
    switch (s) {
        case JobState::queued:
            return "queued";
        case JobState::running:
            return "running";
        case JobState::succeeded:
            return "succeeded";
        case JobState::failed:
            return "failed";
        case JobState::canceled:
            return "canceled";
    }
    return "";
}

std::optional<JobState> parse_job_state(std::string_view name) {
    for (JobState s : kJobStates)
        if (name == job_state_name(s)) return s;
    return std::nullopt;
}

bool is_finished(JobState s) { return s == JobState::succeeded || s == JobState::failed || s == JobState::canceled; }

JobState stored_job_state(std::string_view name) {
    if (auto s = parse_job_state(name)) return *s;
    throw Error(ErrorCode::io, "the job store holds an unknown job state '" + std::string(name.substr(0, 32)) + "'");
}

const char* output_kind_name(OutputKind k) { return k == OutputKind::render ? "render" : "conversion"; }

std::optional<OutputKind> parse_output_kind(std::string_view name) {
    if (name == "render") return OutputKind::render;
    if (name == "conversion") return OutputKind::conversion;
    return std::nullopt;
}

OutputKind stored_output_kind(std::string_view name) {
    if (auto k = parse_output_kind(name)) return *k;
    throw Error(ErrorCode::io, "the job store holds an unknown output kind '" + std::string(name.substr(0, 32)) + "'");
}

const char* job_event_type_name(JobEventType t) {
    switch (t) {
        case JobEventType::state:
            return "state";
        case JobEventType::output:
            return "output";
        case JobEventType::artifact:
            return "artifact";
        case JobEventType::progress:
            return "progress";
    }
    return "";
}

JobEventType stored_job_event_type(std::string_view name) {
    for (JobEventType t : {JobEventType::state, JobEventType::output, JobEventType::artifact, JobEventType::progress})
        if (name == job_event_type_name(t)) return t;
    throw Error(ErrorCode::io, "the job store holds an unknown event type '" + std::string(name.substr(0, 32)) + "'");
}

const char* callback_state_name(CallbackState s) {
    switch (s) {
        case CallbackState::none:
            return "";
        case CallbackState::waiting:
            return "waiting";
        case CallbackState::pending:
            return "pending";
        case CallbackState::delivered:
            return "delivered";
        case CallbackState::failed:
            return "failed";
    }
    return "";
}

CallbackState parse_callback_state(const std::string& s) {
    for (CallbackState c :
         {CallbackState::waiting, CallbackState::pending, CallbackState::delivered, CallbackState::failed})
        if (s == callback_state_name(c)) return c;
    return CallbackState::none;
}

}  // namespace nurbsrt::server
