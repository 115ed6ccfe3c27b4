// GET /v1/jobs/{id}/events: the job's events (server/store/job_store.h,
// JobEvent) as Server-Sent Events (WHATWG HTML, "Server-sent events"): each
// event is `id: <seq>`, `event: <type>`, `data: <one JSON line>`. A client
// resumes after the seq it names in Last-Event-ID (or ?last_event_id=, for
// clients that cannot set headers); the stream ends after the job's terminal
// state event. The events are read from the job store, polled, so a client
// reconnecting to another instance (PostgreSQL) misses nothing.
#include <httplib.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <functional>
#include <memory>
#include <thread>

#include "core/error.h"
#include "server/http/http_server.h"
#include "server/jobs/job_runner.h"
#include "server/render/context.h"
#include "server/routes/handler_util.h"
#include "server/routes/routes.h"
#include "server/common/service_error.h"

namespace nurbsrt::server {
namespace {

// How often a stream reads the store for new events: an event reaches the
// client within this (plus the store's read), small next to an output's
// hundreds of milliseconds, and one indexed read per stream 4 times a second.
constexpr auto kEventPoll = std::chrono::milliseconds(250);
// A comment line this often while nothing happens, so that proxies and
// clients do not take a quiet stream for a dead one (WHATWG HTML,
// "Server-sent events", Authoring notes: "a comment line ... every 15 seconds").
constexpr auto kKeepAlive = std::chrono::seconds(15);
// Events read from the store at once.
constexpr int kEventBatch = 100;
// Longest seq text accepted: 18 digits fits int64_t.
constexpr size_t kMaxSeqDigits = 18;

// The seq to resume after: Last-Event-ID, else ?last_event_id=, else 0 (from
// the first event). Throws Error(invalid_argument) naming the one that is not
// a seq.
int64_t resume_after(const httplib::Request& req) {
    const char* name = "Last-Event-ID";
    std::string text;
    if (req.has_header(name)) {
        text = req.get_header_value(name);
    } else if (req.has_param("last_event_id")) {
        name = "last_event_id";
        text = req.get_param_value("last_event_id");
    }
    if (text.empty()) return 0;
    const bool digits = text.size() <= kMaxSeqDigits && text.find_first_not_of("0123456789") == std::string::npos;
    if (!digits)
        throw Error(ErrorCode::invalid_argument,
                    std::string("'") + name + "' must be the id (a non-negative integer) of an event of this stream");
    return std::stoll(text);
}

std::string sse_event(const JobEvent& e) {
    // The data is one JSON line (dump() escapes control characters): one data field.
    return "id: " + std::to_string(e.seq) + "\nevent: " + job_event_type_name(e.type) + "\ndata: " + e.data_json +
           "\n\n";
}

bool terminal(const JobEvent& e) {
    if (e.type != JobEventType::state) return false;
    const auto d = nlohmann::json::parse(e.data_json, nullptr, false);
    if (!d.is_object() || !d.contains("state") || !d["state"].is_string()) return false;
    const auto state = parse_job_state(d["state"].get<std::string>());
    return state && is_finished(*state);
}

// One stream's place among the capped ones: released when the response (and
// its provider) is destroyed, however the stream ended.
class StreamSlot {
public:
    explicit StreamSlot(std::atomic<int>& open) : open_(open) {}
    ~StreamSlot() { open_.fetch_sub(1); }
    StreamSlot(const StreamSlot&) = delete;
    StreamSlot& operator=(const StreamSlot&) = delete;

private:
    std::atomic<int>& open_;
};

// What a stream's provider keeps between calls.
struct EventStream {
    std::string job_id;
    int64_t after = 0;
    std::chrono::steady_clock::time_point last_write = std::chrono::steady_clock::now();
    std::function<bool()> client_gone;
    std::unique_ptr<StreamSlot> slot;
};

// Writes the next events (or a keep-alive), waiting for them; false when the
// stream is over (the job ended, is gone, the client left or the service stops).
bool pump(ServerContext& ctx, EventStream& st, httplib::DataSink& sink) {
    while (!ctx.stopping.load()) {
        if (st.client_gone && st.client_gone()) return false;
        std::optional<std::vector<JobEvent>> events;
        try {
            events = ctx.jobs->store().events(st.job_id, st.after, kEventBatch);
        } catch (const Error&) {
            return false;  // the store failed: the client reconnects with its Last-Event-ID
        }
        if (!events) return false;  // deleted or expired
        if (!events->empty()) {
            std::string out;
            bool end = false;
            for (const JobEvent& e : *events) {
                out += sse_event(e);
                st.after = e.seq;
                if (terminal(e)) {
                    end = true;
                    break;
                }
            }
            if (!sink.write(out.data(), out.size())) return false;
            st.last_write = std::chrono::steady_clock::now();
            return !end;
        }
        if (std::chrono::steady_clock::now() - st.last_write >= kKeepAlive) {
            static constexpr char kComment[] = ": keep-alive\n\n";
            if (!sink.write(kComment, sizeof kComment - 1)) return false;
            st.last_write = std::chrono::steady_clock::now();
        }
        std::this_thread::sleep_for(kEventPoll);
    }
    return false;
}

}  // namespace

void handle_job_events(ServerContext& ctx, const httplib::Request& req, httplib::Response& res) {
    const std::string id = checked_id(req.matches[1]);
    const int64_t after = resume_after(req);
    if (!ctx.jobs) throw Error(ErrorCode::internal, "the job service is not running");
    const auto job = ctx.jobs->store().get(id);
    if (!job) throw ServiceError(ServiceCode::not_found, "no such job");
    const int cap = ctx.config.event_stream_cap();
    if (ctx.event_streams.fetch_add(1) >= cap) {
        ctx.event_streams.fetch_sub(1);
        send_problem(res, ServiceCode::overloaded,
                     "too many event streams are open (" + std::to_string(cap) +
                         ", --max-event-streams); retry later or poll GET /v1/jobs/{id}",
                     ctx.config.retry_after_s);
        return;
    }
    auto st = std::make_shared<EventStream>();
    st->slot = std::make_unique<StreamSlot>(ctx.event_streams);
    st->job_id = id;
    st->after = after;
    st->client_gone = GuardedServer::client_gone_check();
    // A job already over whose events the client has all: nothing will follow.
    const bool over = is_finished(job->state) && [&] {
        const auto rest = ctx.jobs->store().events(id, after, 1);
        return !rest || rest->empty();
    }();
    res.set_header("Cache-Control", "no-store");
    // Proxies that buffer answers (nginx) pass this one through as it comes.
    res.set_header("X-Accel-Buffering", "no");
    res.set_chunked_content_provider("text/event-stream", [&ctx, st, over](size_t, httplib::DataSink& sink) {
        if (over || !pump(ctx, *st, sink)) sink.done();
        return true;
    });
}

}  // namespace nurbsrt::server
