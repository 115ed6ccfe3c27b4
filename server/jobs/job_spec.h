// The description of a batch job (the `job` part of POST /v1/jobs), validated
// against the uploaded files and the configured limits before the job is
// accepted; the formats of its outputs; and the names the service gives to
// jobs and artifacts (generated, checked against strict patterns, never a
// path taken from a request).
#pragma once

#include <string>
#include <vector>

#include "server/common/config.h"
#include "server/store/job_store.h"

namespace nurbsrt::server {

struct JobSpec {
    std::vector<JobOutput> outputs;
    std::string callback_url;  // empty: no webhook
    // Make every output anew, even where an earlier job made the same artifact (artifact_reuse.h).
    bool force = false;
};

// Parses `job_json` ({"outputs": [{"file": 0 | "name.igs", "type": "render",
// "options": {...}} | {"file": ..., "type": "conversion", "format": "step"}],
// "callback_url": "https://...", "force": false}) for these inputs. Throws
// Error(invalid_argument) naming the problem, Error(limit_exceeded) beyond
// max_job_outputs or the image size limits. The outputs come back numbered,
// with their artifact names and content types.
JobSpec parse_job_spec(const std::string& job_json, const std::vector<JobInput>& inputs, const ServerConfig& config);

// `<file>-<type>-<output><extension>`, e.g. 0-render-1.png, 1-conversion-0.stl.
std::string artifact_name(int file, const std::string& type, int output, const std::string& extension);

// One file an output makes: its name (generated, valid_artifact_name), the
// view it shows (layout separate; else empty) and its content type.
struct ArtifactFile {
    std::string name, view, content_type;
};
// Every file of `out`, JobOutput::artifact first: a render with layout
// separate makes one per view, `<output>.<view><extension>` (0-render-1.front.png,
// the name of the API's ZIP entry after the output's); an OBJ conversion its
// .obj and the .mtl the .obj's mtllib line names (1-conversion-0.obj, 1-conversion-0.mtl);
// every other output the one file JobOutput::artifact.
std::vector<ArtifactFile> output_artifacts(const JobOutput& out);
bool valid_artifact_name(const std::string& name);
// The output format named by an artifact's extension (png, exr, step, ...).
std::string artifact_format(const std::string& name);
// Job ids are 32 lowercase hex digits.
bool valid_job_id(const std::string& id);

}  // namespace nurbsrt::server
