#include "server/http/upload.h"

#include <nlohmann/json.hpp>

#include <cctype>

#include "importer/importer.h"
#include "core/error.h"
#include "core/json_limits.h"
#include "options/query_values.h"
#include "core/ascii.h"

namespace nurbsrt::server {
namespace {

// As nlohmann::json checks it when writing a string (the parser checks the same).
bool is_utf8(const std::string& s) {
    try {
        (void)nlohmann::json(s).dump();
        return true;
    } catch (const nlohmann::json::type_error&) {
        return false;
    }
}

// A stored file's id as sent: never empty (an empty id would read as "no
// stored file" and leave the route without bytes), at most a line long.
std::string checked_file_id(const std::string& id) {
    if (id.empty())
        throw Error(ErrorCode::invalid_argument,
                    "'file_id' is empty: name a stored file by the id POST /v1/files answered");
    return id;
}

// The parts of a multipart upload: `file` or `file_id`, `options`, and the
// plain form fields named in `form_options`.
void read_multipart(const httplib::Request& req, std::initializer_list<const char*> form_options,
                    nlohmann::json& options, Upload& up) {
    using nlohmann::json;
    const auto file = req.files.find("file");
    const auto file_id = req.files.find("file_id");
    if (file == req.files.end() && file_id == req.files.end())
        throw Error(ErrorCode::invalid_argument,
                    "multipart upload without a 'file' part (or a 'file_id' field naming a stored file)");
    if (file != req.files.end() && file_id != req.files.end())
        throw Error(ErrorCode::invalid_argument, "send either a 'file' part or a 'file_id' field, not both");
    for (const char* name : {"file", "file_id", "options"})
        if (req.files.count(name) > 1)
            throw Error(ErrorCode::invalid_argument, std::string("more than one '") + name +
                                                         "' part: send one file and one options part "
                                                         "(several files: POST /v1/jobs)");
    if (file != req.files.end()) {
        up.bytes = &file->second.content;
        up.filename = file->second.filename;
    } else {
        up.file_id = checked_file_id(file_id->second.content);
    }
    up.multipart = true;
    if (const auto part = req.files.find("options"); part != req.files.end()) {
        const json o = parse_json_or_throw(part->second.content, kRequestJsonLimits, "the 'options' part");
        if (!o.is_object()) throw Error(ErrorCode::invalid_argument, "the 'options' part must be a JSON object");
        options.merge_patch(o);
    }
    for (const auto& [name, part] : req.files) {
        if (name == "file" || name == "file_id" || name == "options") continue;
        bool field = false;
        for (const char* f : form_options) field = field || name == f;
        if (!field) throw Error(ErrorCode::invalid_argument, "unexpected multipart part '" + name.substr(0, 64) + "'");
        if (req.files.count(name) > 1 || options.contains(name))
            throw Error(ErrorCode::invalid_argument, "option '" + name + "' is given more than once");
        if (!is_utf8(part.content))
            throw Error(ErrorCode::invalid_argument, "form field '" + name + "' must be UTF-8 text");
        options[name] = query_value(name, part.content);
    }
}

// {"file_id": "...", <options>}: a stored file and the options, over the query parameters.
void read_json_body(const std::string& body, nlohmann::json& options, Upload& up) {
    BoundedJson parsed = parse_json_bounded(body, kRequestJsonLimits);
    // Not JSON: most likely a CAD file sent with the wrong type.
    if (parsed.problem == JsonProblem::not_json)
        throw Error(ErrorCode::invalid_json,
                    "the body of type 'application/json' is " + parsed.detail +
                        ": send the STEP/IGES file raw (application/octet-stream, model/step, model/iges) or as the "
                        "'file' part of multipart/form-data, or name a stored file in a JSON body {\"file_id\": ...}");
    if (!parsed.ok()) throw Error(ErrorCode::invalid_json, "the JSON body: " + parsed.detail);
    nlohmann::json& j = parsed.value;
    if (!j.is_object())
        throw Error(ErrorCode::invalid_argument, "a JSON body must be an object: {\"file_id\": \"...\", <options>}");
    if (!j.contains("file_id") || !j["file_id"].is_string())
        throw Error(ErrorCode::invalid_argument,
                    "a JSON body names a stored file: {\"file_id\": \"...\", <options>} (send a CAD file raw or "
                    "as the 'file' part of multipart/form-data)");
    up.file_id = checked_file_id(j["file_id"].get<std::string>());
    j.erase("file_id");
    for (const auto& [k, v] : j.items())
        if (options.contains(k))
            throw Error(ErrorCode::invalid_argument, "option '" + k.substr(0, 64) + "' is given more than once");
    options.merge_patch(j);
}

}  // namespace

Upload read_upload(const httplib::Request& req, std::initializer_list<const char*> form_options) {
    using nlohmann::json;
    json options = json::object();
    for (const auto& [k, v] : req.params) {
        // A repeated parameter or part is refused, never resolved silently one way.
        if (options.contains(k))
            throw Error(ErrorCode::invalid_argument,
                        "query parameter '" + k.substr(0, 64) + "' is given more than once");
        // Query strings are bytes, options are JSON text: a name or value that is
        // not UTF-8 names no option and could not be written as JSON.
        if (!is_utf8(k) || !is_utf8(v))
            throw Error(ErrorCode::invalid_argument, "query parameter names and values must be UTF-8 text");
        options[k] = query_value(k, v);
    }

    Upload up;
    if (req.is_multipart_form_data()) {
        read_multipart(req, form_options, options, up);
    } else {
        const std::string type = ascii_lower(req.get_header_value("Content-Type"));
        const std::string base = type.substr(0, type.find(';'));
        if (base == "application/json") {
            read_json_body(req.body, options, up);
        } else {
            static const char* accepted[] = {"",
                                             "application/octet-stream",
                                             "model/step",
                                             "model/iges",
                                             "application/step",
                                             "application/iges",
                                             "application/p21"};
            bool ok = false;
            for (const char* a : accepted) ok = ok || base == a;
            if (!ok)
                throw Error(ErrorCode::unsupported_format,
                            "request body of type '" + base.substr(0, 64) +
                                "': send the STEP/IGES file raw (application/octet-stream, model/step, model/iges) "
                                "or as the 'file' part of multipart/form-data, or name a stored file in a JSON body "
                                "{\"file_id\": ...}");
            up.bytes = &req.body;
        }
    }
    up.options_json = options.dump();
    return up;
}

namespace {
constexpr const char* kHowToSendAFile =
    "send a STEP or IGES file, raw (Content-Type: application/octet-stream) or as the 'file' part of "
    "multipart/form-data";
constexpr const char* kHowToSendAJob =
    "a job is multipart/form-data with one or more 'file' parts (STEP or IGES) and one 'job' part (JSON)";
}  // namespace

std::string empty_upload_detail(const Upload& upload) {
    return std::string(upload.multipart ? "the 'file' part is empty: " : "the request body is empty: ") +
           kHowToSendAFile;
}

std::string no_body_detail(const std::string& route) {
    return std::string("the request has no body (neither Content-Length nor Transfer-Encoding): ") +
           (route == "/v1/jobs" ? kHowToSendAJob : kHowToSendAFile);
}

std::string download_name(const std::string& upload_filename, const std::string& extension) {
    // Browsers send a bare name, some clients a path (either separator).
    std::string name = upload_filename.substr(upload_filename.find_last_of("/\\") + 1);
    if (const size_t dot = name.rfind('.'); dot != std::string::npos && dot > 0) name.resize(dot);
    std::string stem;
    for (char c : name)
        if (std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '-' || c == '_') stem += c;
    constexpr size_t kMaxStem = 100;  // file systems take 255 bytes; leave room for the extension
    if (stem.size() > kMaxStem) stem.resize(kMaxStem);
    while (!stem.empty() && stem.front() == '.') stem.erase(stem.begin());  // no hidden files
    return (stem.empty() ? std::string("converted") : stem) + extension;
}

JobUpload read_job_upload(const httplib::Request& req, int max_job_files) {
    if (!req.is_multipart_form_data())
        throw Error(ErrorCode::unsupported_format,
                    "a job is multipart/form-data: one or more 'file' parts and one 'job' part (JSON)");
    JobUpload up;
    for (const auto& [name, part] : req.files) {
        if (name == "file") {
            if (static_cast<int>(up.inputs.size()) >= max_job_files)
                throw Error(ErrorCode::limit_exceeded,
                            "more than " + std::to_string(max_job_files) + " files in one job");
            const std::string& b = part.content;
            const int index = static_cast<int>(up.inputs.size());
            if (b.empty()) throw Error(ErrorCode::invalid_argument, "file " + std::to_string(index) + " is empty");
            const CadFormat f = detect_format_bytes(b.data(), b.size());
            if (f == CadFormat::unknown)
                throw Error(
                    ErrorCode::unsupported_format,
                    "file " + std::to_string(index) + " is neither STEP, IGES nor BREP (recognised by content)");
            // The filename is only a label for the client (and to refer to the file): bounded, never a path.
            up.inputs.push_back({index, part.filename.substr(0, 255), format_name(f), static_cast<int64_t>(b.size())});
            up.bytes.push_back(&b);
        } else if (name == "file_id") {
            continue;  // after the uploaded files, below
        } else if (name == "job") {
            if (up.job_json) throw Error(ErrorCode::invalid_argument, "more than one 'job' part");
            up.job_json = &part.content;
        } else {
            throw Error(ErrorCode::invalid_argument, "unexpected multipart part '" + name.substr(0, 64) + "'");
        }
    }
    up.file_ids.assign(up.inputs.size(), std::string());
    // cpp-httplib keeps the parts by name, so their order among other names is
    // lost: stored files come after the uploaded ones, each in its own order.
    const auto [first, last] = req.files.equal_range("file_id");
    for (auto it = first; it != last; ++it) {
        if (static_cast<int>(up.inputs.size()) >= max_job_files)
            throw Error(ErrorCode::limit_exceeded, "more than " + std::to_string(max_job_files) + " files in one job");
        up.inputs.push_back({static_cast<int>(up.inputs.size()), "", "", 0});
        up.bytes.push_back(nullptr);
        up.file_ids.push_back(checked_file_id(it->second.content));
    }
    if (up.inputs.empty())
        throw Error(ErrorCode::invalid_argument, "a job needs at least one 'file' part or 'file_id' field");
    if (!up.job_json) throw Error(ErrorCode::invalid_argument, "a job needs a 'job' part (JSON with 'outputs')");
    return up;
}

}  // namespace nurbsrt::server
