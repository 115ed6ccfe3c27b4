#include "server/jobs/job_spec.h"

#include <nlohmann/json.hpp>

#include <regex>

#include "importer/importer.h"
#include "core/error.h"
#include "core/json_limits.h"
#include "options/render_request.h"
#include "server/render/render_limits.h"
#include "server/jobs/callback_url.h"

namespace nurbsrt::server {
namespace {

using nlohmann::json;

[[noreturn]] void bad_spec(const std::string& what) { throw Error(ErrorCode::invalid_argument, what); }

// The input an output refers to: its index among the `file` parts, or its
// filename when that names exactly one of them.
int resolve_file(const json& v, const std::vector<JobInput>& inputs, const std::string& where) {
    if (v.is_number_integer()) {
        const long long i = v.get<long long>();
        if (i < 0 || i >= static_cast<long long>(inputs.size()))
            bad_spec(where + ": 'file' " + std::to_string(i) + " is out of range (" + std::to_string(inputs.size()) +
                     " file(s) uploaded)");
        return static_cast<int>(i);
    }
    if (v.is_string()) {
        const std::string name = v.get<std::string>();
        int found = -1;
        for (const JobInput& in : inputs)
            if (in.filename == name) {
                if (found >= 0)
                    bad_spec(where + ": several uploaded files are named '" + name.substr(0, 64) + "'; use the index");
                found = in.index;
            }
        if (found < 0) bad_spec(where + ": no uploaded file is named '" + name.substr(0, 64) + "'");
        return found;
    }
    bad_spec(where + ": 'file' must be the index of a file part or its filename");
}

}  // namespace

JobSpec parse_job_spec(const std::string& job_json, const std::vector<JobInput>& inputs, const ServerConfig& config) {
    const json j = parse_json_or_throw(job_json, kRequestJsonLimits, "the 'job' part");
    if (!j.is_object()) bad_spec("the 'job' part must be a JSON object");
    for (const auto& [key, v] : j.items())
        if (key != "outputs" && key != "callback_url" && key != "force")
            bad_spec("unknown job field '" + key.substr(0, 64) + "'");
    JobSpec spec;
    if (j.contains("force")) {
        if (!j["force"].is_boolean()) bad_spec("'force' must be true or false");
        spec.force = j["force"].get<bool>();
    }
    if (j.contains("callback_url")) {
        if (!j["callback_url"].is_string()) bad_spec("'callback_url' must be a string (an http or https URL)");
        spec.callback_url = j["callback_url"].get<std::string>();
        if (config.webhook_secret.empty())
            bad_spec(
                "'callback_url' needs a signing secret, and this service has none (it is started with "
                "NURBSRT_WEBHOOK_SECRET or --webhook-secret-file to sign callbacks)");
        check_callback_url(spec.callback_url, config.webhook_allow_private);
    }
    if (!j.contains("outputs") || !j["outputs"].is_array() || j["outputs"].empty())
        bad_spec("the job needs a non-empty 'outputs' array");
    const json& list = j["outputs"];
    if (list.size() > static_cast<size_t>(config.max_job_outputs))
        throw Error(ErrorCode::limit_exceeded, "the job has " + std::to_string(list.size()) +
                                                   " outputs; the limit is " + std::to_string(config.max_job_outputs));
    std::vector<JobOutput>& outputs = spec.outputs;
    std::vector<bool> used(inputs.size(), false);
    for (size_t i = 0; i < list.size(); ++i) {
        const std::string where = "output " + std::to_string(i);
        const json& o = list[i];
        if (!o.is_object()) bad_spec(where + " must be an object");
        if (!o.contains("file")) bad_spec(where + ": 'file' is required");
        if (!o.contains("type") || !o["type"].is_string()) bad_spec(where + ": 'type' must be render or conversion");
        JobOutput out;
        out.index = static_cast<int>(i);
        out.file = resolve_file(o["file"], inputs, where);
        const std::optional<OutputKind> kind = parse_output_kind(o["type"].get<std::string>());
        if (!kind) bad_spec(where + ": 'type' must be render or conversion");
        out.kind = *kind;
        std::string extension;
        if (out.kind == OutputKind::render) {
            for (const auto& [key, v] : o.items())
                if (key != "file" && key != "type" && key != "options")
                    bad_spec(where + ": unknown field '" + key.substr(0, 64) + "' of a render");
            json options = o.value("options", json::object());
            if (options.is_null()) options = json::object();  // null: every option's default
            if (!options.is_object()) bad_spec(where + ": 'options' must be an object");
            // A null option is its default: kept out of the stored options (and the job document).
            for (auto it = options.begin(); it != options.end();)
                it = it->is_null() ? options.erase(it) : std::next(it);
            if (options.contains("camera") && options["camera"].is_object()) {
                json& camera = options["camera"];
                for (auto it = camera.begin(); it != camera.end();)
                    it = it->is_null() ? camera.erase(it) : std::next(it);
            }
            out.options_json = options.dump();
            RenderRequest r;
            try {
                r = parse_render_options(out.options_json);
                check_render_limits(config, r);
                if (r.aovs)
                    bad_spec(
                        "option 'aovs' is for POST /v1/renders with Accept: application/json; "
                        "a job's render gets the AOVs with format exr");
            } catch (const Error& e) {
                throw Error(e.code(), where + ": " + e.what());
            }
            extension = r.format.extension;
            out.content_type = r.format.content_type;
            // An artifact per view (output_artifacts): the first view's names the output's.
            if (r.layout == ViewLayout::separate) extension = "." + r.views.front().name + extension;
        } else {
            for (const auto& [key, v] : o.items())
                if (key != "file" && key != "type" && key != "format" && key != "options")
                    bad_spec(where + ": unknown field '" + key.substr(0, 64) + "' of a conversion");
            if (!o.contains("format") || !o["format"].is_string())
                bad_spec(where + ": a conversion needs 'format' (" + conversion_format_names() + ")");
            // The options of POST /v1/conversions (units, step_schema, iges_mode,
            // deflection, strict), read by its parser with the format beside them.
            json options = o.value("options", json::object());
            if (options.is_null()) options = json::object();
            if (!options.is_object()) bad_spec(where + ": 'options' must be an object");
            for (auto it = options.begin(); it != options.end();)
                it = it->is_null() ? options.erase(it) : std::next(it);
            if (options.contains("format")) bad_spec(where + ": 'format' is the output's field, not an option");
            const ConversionFormat f = conversion_format_from_name(o["format"].get<std::string>());
            if (f == ConversionFormat::unknown)
                bad_spec(where + ": 'format' must be one of " + conversion_format_names());
            options["format"] = conversion_format_short_name(f);
            try {
                // Stored resolved (every default named): the job document echoes them
                // so, and equal requests share an artifact reuse key however they were spelt.
                out.options_json = conversion_request_json(parse_conversion_request(options.dump()));
            } catch (const Error& e) {
                throw Error(e.code(), where + ": " + e.what());
            }
            extension = conversion_format_extension(f);
            out.content_type = conversion_format_content_type(f);
        }
        out.artifact = artifact_name(out.file, output_kind_name(out.kind), out.index, extension);
        used[static_cast<size_t>(out.file)] = true;
        outputs.push_back(std::move(out));
    }
    for (size_t f = 0; f < used.size(); ++f)
        if (!used[f]) bad_spec("file " + std::to_string(f) + " has no outputs");
    return spec;
}

std::string artifact_name(int file, const std::string& type, int output, const std::string& extension) {
    return std::to_string(file) + "-" + type + "-" + std::to_string(output) + extension;
}

std::vector<ArtifactFile> output_artifacts(const JobOutput& out) {
    std::vector<ArtifactFile> files = {{out.artifact, "", out.content_type}};
    const std::string stem = out.artifact.substr(0, out.artifact.find('.'));
    if (out.kind == OutputKind::render) {
        const RenderRequest r = parse_render_options(out.options_json);
        // A job stored before views were artifacts of their own has its ZIP (one file).
        if (r.layout != ViewLayout::separate || out.artifact.ends_with(".zip")) return files;
        files.clear();
        for (const std::string& view : view_names(r))
            files.push_back({stem + "." + view + r.format.extension, view, r.format.content_type});
        return files;
    }
    const ConversionFormat f = parse_conversion_format(out.options_json);
    if (const char* companion = conversion_format_companion(f))
        files.push_back({stem + companion, "", conversion_format_companion_content_type(f)});
    return files;
}

bool valid_artifact_name(const std::string& name) {
    // A view's label (checked_view_name: [A-Za-z0-9_-]{1,32}) between the output and the extension.
    static const std::regex pattern(R"(^[0-9]{1,5}-(render|conversion)-[0-9]{1,5}(\.[A-Za-z0-9_-]{1,32})?\.)"
                                    R"((png|jpg|tif|exr|zip|step|igs|stl|glb|json|brep|wrl|obj|mtl)$)");
    return name.size() <= 80 && std::regex_match(name, pattern);
}

std::string artifact_format(const std::string& name) {
    // Conversions by the formats' table (.igs -> iges, .wrl -> vrml), images by their own.
    if (const ConversionFormat f = conversion_format_from_extension(name); f != ConversionFormat::unknown)
        return conversion_format_short_name(f);
    const std::string ext = name.substr(name.rfind('.') + 1);
    if (ext == "jpg") return "jpeg";
    if (ext == "tif") return "tiff";
    return ext;
}

bool valid_job_id(const std::string& id) {
    if (id.size() != 32) return false;
    for (char c : id)
        if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) return false;
    return true;
}

}  // namespace nurbsrt::server
