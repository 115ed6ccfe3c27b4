// The job document: the answer of GET /v1/jobs/{id} (and of the 202 of POST
// /v1/jobs, and the items of GET /v1/jobs), and the body a job's webhook
// receives (server/jobs/webhooks.h).
#pragma once

#include <nlohmann/json_fwd.hpp>

#include <string>

#include "server/store/job_store.h"

namespace nurbsrt::server {

std::string job_url(const std::string& id);
nlohmann::json job_json(const JobRecord& job);
// The body of the job's webhook: its document without the state of the
// delivery itself (every attempt sends the same bytes; the attempt is in a header).
std::string job_webhook_body(const JobRecord& job);

}  // namespace nurbsrt::server
