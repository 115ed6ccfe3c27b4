// The job document: the answer of GET /v1/jobs/{id} (and of the 202 of POST
// /v1/jobs, and the items of GET /v1/jobs), and the body a job's webhook
// receives (server/jobs/webhooks.h).
#pragma once

#include <nlohmann/json_fwd.hpp>

#include <cstdint>
#include <functional>
#include <string>

#include "server/store/job_store.h"

namespace nurbsrt::server {

std::string job_url(const std::string& id);
// The size of a job's artifact already in place, -1 when it is not (yet):
// how the document lists the files a running output has placed (the views of
// a separate layout, each downloadable as soon as it is written).
using PlacedArtifact = std::function<int64_t(const std::string& name)>;
nlohmann::json job_json(const JobRecord& job, const PlacedArtifact& placed = {});
// The body of the job's webhook: its document without the state of the
// delivery itself (every attempt sends the same bytes; the attempt is in a header).
std::string job_webhook_body(const JobRecord& job);

}  // namespace nurbsrt::server
