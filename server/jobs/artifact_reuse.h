// Artifacts made before, served again: an output whose input file (by its
// SHA-256), kind and options are those of an artifact an earlier job made gets
// that artifact (a hard link to the same bytes, else a copy) instead of being
// made again, unless its job asks `force`. The index is a directory beside
// the jobs' (DATA_DIR/reuse): per key the artifact (hard-linked, so it outlives
// the job that made it) and its result JSON. Shared by the instances of a
// shared data directory; entries expire with the jobs' retention. Free of
// HTTP and JSON headers.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "server/store/job_store.h"

namespace nurbsrt::server {

class ArtifactReuse {
public:
    // Creates `dir` when needed; throws Error(io) when it cannot.
    explicit ArtifactReuse(std::string dir);

    // The key of an artifact of an output of a file whose bytes hash to
    // `content_sha256`: its kind, its canonical options (job_spec.cpp stores
    // them so) and what the artifact's name says past the output's number (its
    // view and extension: "front.png", "mtl"); `artifact` empty: JobOutput::artifact.
    static std::string key(const std::string& content_sha256, const JobOutput& out, const std::string& artifact = {});

    // Keeps a succeeded output's artifact and result under `key`. Best effort:
    // an index that cannot be written only means no later reuse.
    void remember(const std::string& key, const std::string& artifact_path, const std::string& result_json) noexcept;
    // The result kept under `key`, its artifact placed at `dest`; nullopt when
    // there is none (or it cannot be placed).
    std::optional<std::string> recall(const std::string& key, const std::string& dest) const;
    // Removes entries made before `before_ms` (Unix ms); returns how many.
    int expire(int64_t before_ms) noexcept;

private:
    std::string dir_;
};

}  // namespace nurbsrt::server
