// Uploads as the service receives them: a raw HTTP request goes through
// cpp-httplib's request parsing (request line, headers, query, multipart body)
// exactly as on a connection, and then through our handling of what it parsed
// for the three upload routes: picking the `file`, `options` and `job` parts
// (server/http/upload.h), refusing duplicate or unknown ones, merging query
// parameters into the options, and validating those (render options, limits,
// conversion format, job spec, format detection by content), and a refusal's
// problem+json body as the routes write it (service paths taken out).
//
// cpp-httplib is Debian's shared library, not instrumented: libFuzzer's
// coverage guidance comes from our code, while AddressSanitizer still checks
// every access our code makes to the parsed request.
//
// The input is the request as sent. When its head (up to the first blank
// line) has no Content-Length and no Transfer-Encoding, the harness adds the
// body's true length, so that mutated bodies are still read whole.
#include <httplib.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "fuzz/fuzz_common.h"
#include "importer/importer.h"
#include "server/common/config.h"
#include "server/http/http_framing.h"
#include "server/jobs/job_spec.h"
#include "server/http/problem.h"
#include "server/common/redact.h"
#include "options/render_request.h"
#include "server/render/render_limits.h"
#include "server/http/upload.h"

using namespace nurbsrt;

namespace {

// One request in, the answer discarded.
class InputStream final : public httplib::Stream {
public:
    explicit InputStream(const std::string& in) : in_(in) {}
    bool is_readable() const override { return true; }
    bool is_writable() const override { return true; }
    ssize_t read(char* ptr, size_t size) override {
        const size_t n = std::min(size, in_.size() - pos_);
        std::memcpy(ptr, in_.data() + pos_, n);
        pos_ += n;
        return static_cast<ssize_t>(n);
    }
    ssize_t write(const char*, size_t size) override { return static_cast<ssize_t>(size); }
    void get_remote_ip_and_port(std::string& ip, int& port) const override { ip = "127.0.0.1", port = 40000; }
    void get_local_ip_and_port(std::string& ip, int& port) const override { ip = "127.0.0.1", port = 8080; }
    socket_t socket() const override { return INVALID_SOCKET; }

private:
    const std::string& in_;
    size_t pos_ = 0;
};

class Harness final : public httplib::Server {
public:
    Harness() {
        set_payload_max_length(config_.max_upload_bytes);
        Post("/v1/renders", [this](const httplib::Request& req, httplib::Response& res) {
            handle(res, [&] {
                const server::Upload up = server::read_upload(req);
                const nurbsrt::RenderRequest r = nurbsrt::parse_render_options(up.options_json);
                server::check_render_limits(config_, r);
                if (up.bytes) (void)detect_format_bytes(up.bytes->data(), up.bytes->size());  // else a file_id
            });
        });
        Post("/v1/conversions", [](const httplib::Request& req, httplib::Response& res) {
            handle(res, [&] {
                const server::Upload up = server::read_upload(req);
                (void)nurbsrt::parse_conversion_format(up.options_json);
                if (up.bytes) (void)detect_format_bytes(up.bytes->data(), up.bytes->size());  // else a file_id
            });
        });
        Post("/v1/jobs", [this](const httplib::Request& req, httplib::Response& res) {
            handle(res, [&] {
                const server::JobUpload up = server::read_job_upload(req, config_.max_job_files);
                if (up.inputs.size() != up.bytes.size() || up.inputs.size() != up.file_ids.size() || !up.job_json)
                    __builtin_trap();
                (void)server::parse_job_spec(*up.job_json, up.inputs, config_);
            });
        });
    }

    void run(const std::string& request) {
        InputStream stream(request);
        bool closed = false;
        process_request(stream, true, closed, nullptr);
    }

private:
    // cpp-httplib turns a handler's exception into a 500: anything but our
    // Error must stop the run here to be seen as a finding.
    template <class Body>
    static void handle(httplib::Response& res, Body&& body) {
        try {
            body();
            res.status = 200;
        } catch (const Error& e) {
            const std::string detail = server::without_prefixes(
                server::with_scratch_files_named(e.what(), "/var/nurbsrt/tmp"), {"/var/nurbsrt/"});
            const server::Problem p = server::make_problem(e.code(), detail, "0123456789abcdef");
            if (!nlohmann::json::accept(p.body)) __builtin_trap();  // a problem body is always JSON
            res.status = p.status;
        } catch (const std::exception& e) {
            std::fprintf(stderr, "unexpected exception: %s\n", e.what());
            std::abort();
        } catch (...) {
            std::fprintf(stderr, "unexpected exception of a non-standard type\n");
            std::abort();
        }
    }

    server::ServerConfig config_;
};

bool has_header(const std::string& head, const char* name) {
    std::string lower = head;
    for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return lower.find(std::string("\n") + name + ":") != std::string::npos;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static Harness harness;
    std::string request = fuzz::as_string(data, size);
    const size_t end = request.find("\r\n\r\n");
    if (end != std::string::npos) {
        const std::string head = request.substr(0, end + 2);
        if (!has_header(head, "content-length") && !has_header(head, "transfer-encoding"))
            request.insert(end + 2, "Content-Length: " + std::to_string(request.size() - end - 4) + "\r\n");
        // The service checks the head's framing before cpp-httplib reads on
        // (server/http/http_framing.h); a refused head gets a problem answer only.
        const server::FramingVerdict v =
            server::check_request_head(std::string_view(request).substr(0, request.find("\r\n\r\n") + 4));
        if (!v.ok()) {
            if (v.status != 400 && v.status != 501) __builtin_trap();
            if (!nlohmann::json::accept(server::make_problem(v.code, v.detail, "0123456789abcdef").body))
                __builtin_trap();
            return 0;
        }
    }
    harness.run(request);
    return 0;
}
