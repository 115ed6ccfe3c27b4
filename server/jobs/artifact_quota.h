// The job artifacts of all kept jobs are bounded together (--max-artifacts-mb):
// without it 100 queued jobs of 64 outputs of 4096^2 EXR images (122 MB each)
// would keep ~780 GB for the retention period. A job is refused at submission
// (507) when the artifacts already written and its own estimate exceed the
// quota, and an output whose artifact would exceed it when written fails with
// limit_exceeded. Several runners (and instances) check without a lock, so
// the quota may be overshot by one artifact per runner at a time.
#pragma once

#include <cstdint>
#include <string>

#include "server/store/job_store.h"

namespace nurbsrt::server {

// The bytes an output's artifact may take: a render's size uncompressed (a
// bound for PNG, JPEG and TIFF; EXR with every AOV channel as float), a
// conversion a fixed multiple of its input (CAD text, meshes and NURBS JSON of
// a part stay within it in practice; the write-time check is what bounds).
int64_t estimated_artifact_bytes(const JobOutput& out, int64_t input_bytes);

// The default quota: half the size of the file system that holds `data_dir`.
size_t default_artifact_quota(const std::string& data_dir);

// Throws Error(limit_exceeded) when `more` bytes of artifacts would take the
// `used` ones beyond `quota`; `what` names them in the message.
void check_artifact_quota(int64_t used, int64_t more, size_t quota, const std::string& what);

}  // namespace nurbsrt::server
