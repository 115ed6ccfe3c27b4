// POST /v1/conversions: one synchronous conversion of a STEP/IGES upload (or
// of a stored file named by `file_id`, server/store/file_store.h) to
// STEP, IGES, BREP, STL, glb, VRML or NURBS JSON, run in a child process
// (importer/isolated.h) under the import time and memory limits.
#include <filesystem>

#include <httplib.h>
#include <nlohmann/json.hpp>

#include "importer/importer.h"
#include "importer/isolated.h"
#include "core/error.h"
#include "server/common/base64.h"
#include "server/render/context.h"
#include "server/http/http_server.h"
#include "core/ascii.h"
#include "server/http/negotiation.h"
#include "server/http/zip_archive.h"
#include "server/routes/handler_util.h"
#include "options/render_request.h"
#include "server/routes/routes.h"
#include "server/render/stage_timings.h"
#include "server/render/work.h"

namespace nurbsrt::server {
namespace {

// The extension of a download: STEP as .stp, the three-letter form most CAD
// systems write, like IGES's .igs (the worker's own file keeps .step, which
// picks its writer).
const char* download_extension(ConversionFormat f) {
    return f == ConversionFormat::step ? ".stp" : conversion_format_extension(f);
}

// A format written as two files (OBJ and its .mtl) is answered as one ZIP of
// both, named after the download; the .obj's mtllib line names the .mtl's new name.

std::string zip_with_companion(const std::string& companion_path, std::string main, const std::string& stem,
                               ConversionFormat format) {
    const std::string companion_ext = conversion_format_companion(format);
    const std::string written = std::filesystem::path(companion_path).filename().string();
    const std::string renamed = stem + companion_ext;
    main = with_companion_renamed(std::move(main), format, written, renamed);
    return zip_archive({{stem + conversion_format_extension(format), std::move(main), true},
                        {renamed, read_file_bytes(companion_path), true}});
}

}  // namespace

void handle_conversion(ServerContext& ctx, const httplib::Request& req, httplib::Response& res) {
    // Stages marked end to end from the request's arrival (see
    // kConversionStages): they sum to the total.
    StageClock stages(GuardedServer::request_received_at());
    Upload upload =
        read_upload(req, {"format", "units", "step_schema", "iges_mode", "deflection", "angular_deflection", "strict"});
    const ConversionRequest request = parse_conversion_request(upload.options_json);
    const ConversionFormat format = request.format;
    // The converted file itself, or JSON with it inside (RFC 9110 §12.5.1): refused before any work.
    // A NURBS JSON file is application/json itself: the wrapper only when Accept names that type.
    const char* companion = conversion_format_companion(format);
    const std::string file_type = companion ? kZipMediaType : conversion_format_content_type(format);
    const bool json_answer = negotiate_answer(req, {file_type, kJsonMediaType}) == kJsonMediaType &&
                             (file_type != kJsonMediaType ||
                              ascii_lower(req.get_header_value("Accept")).find(kJsonMediaType) != std::string::npos);
    StoredContent stored;
    if (!upload.file_id.empty()) load_stored_file(ctx, upload, stored);
    const std::string& bytes = *upload.bytes;
    if (bytes.empty()) throw Error(ErrorCode::invalid_argument, empty_upload_detail(upload));
    if (detect_format_bytes(bytes.data(), bytes.size()) == CadFormat::unknown)
        throw Error(ErrorCode::unsupported_format, "the upload is neither STEP, IGES nor BREP (recognised by content)");
    stages.mark("upload");

    auto ticket = admit(ctx);
    stages.mark("queue");
    const TempFile in = ctx.scratch.write("upload", ".cad", bytes);
    // The worker picks the writer by this extension.
    const TempFile out = ctx.scratch.create("converted", conversion_format_extension(format));
    // What the writer puts beside it, removed with it.
    const TempFile beside(companion ? std::filesystem::path(out.path()).replace_extension(companion).string() : "");
    stages.mark("isolation");  // handing the bytes to the child
    ConvertReport report;
    IsolationTimings isolated;
    try {
        IsolationLimits limits = isolation_limits(ctx);
        limits.should_stop = GuardedServer::client_gone_check();  // a gone client's conversion is killed
        report = convert_isolated(in.path(), out.path(), limits, &isolated, request.options);
    } catch (const Error& e) {
        ctx.metrics.count_import_failure(error_code_name(e.code()));
        throw;
    }
    add_conversion_stages(report, isolated, stages);
    // Nothing of the file is answered: the problem says why.
    if (request.strict && !report.warnings.empty()) throw strict_refusal(report.warnings);
    stages.mark("isolation");
    const std::string stem = download_name(upload.filename, "");
    const std::string data = companion ? zip_with_companion(beside.path(), read_file_bytes(out.path()), stem, format)
                                       : read_file_bytes(out.path());
    ticket.reset();
    stages.mark("transfer");  // the converted file into this process

    if (json_answer) {
        nlohmann::json body = {{"request_id", request_id(res)},
                               {"input_format", format_name(report.in_format)},
                               {"output_format", conversion_format_name(report.output)},
                               {"faces", report.faces},
                               {"triangles", report.triangles},
                               {"unmeshed_faces", report.unmeshed_faces},
                               {"degenerate_triangles", report.degenerate_triangles},
                               {"input_units", report.in_units},
                               {"output_units", report.out_units},
                               {"warnings", report.warnings},
                               {"content_type", file_type},
                               {"data_base64", base64_encode(data)}};
        // Every output but NURBS JSON (the imported scene itself) has one.
        if (!report.fidelity.empty()) body["fidelity"] = nlohmann::json::parse(report.fidelity);
        // The last stage, this answer, ends before its serialization: the text
        // cannot hold the time it takes to write itself.
        stages.mark("response");
        body["timings_ms"] = stage_timings_json(stages, kConversionStages);
        res.set_header("Server-Timing", server_timing(stages, kConversionStages));
        res.set_content(body.dump(), kBulkJsonContentType);
    } else {
        res.set_header("Content-Disposition",
                       attachment_disposition(stem + (companion ? ".zip" : download_extension(format))));
        set_warnings_header(res, report.warnings);
        res.set_content(data, file_type.c_str());
        stages.mark("response");
        res.set_header("Server-Timing", server_timing(stages, kConversionStages));
    }
}

}  // namespace nurbsrt::server
