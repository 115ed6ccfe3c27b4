#include "server/jobs/artifact_quota.h"

#include <sys/statvfs.h>

#include <algorithm>

#include "core/error.h"
#include "options/render_request.h"

namespace nurbsrt::server {
namespace {

// EXR: RGBA and the AOVs (z, face, normal 3, uv 2, iterations) as 32-bit floats.
constexpr int64_t kExrBytesPerPixel = 12 * 4;
constexpr int64_t kRgbaBytesPerPixel = 4;
// A converted file against its input: STEP <-> IGES text grows by up to ~2x,
// a fine STL or glb mesh of a small B-rep part by a few times its text.
constexpr int64_t kConversionGrowth = 4;
// When the file system cannot be asked: 10 GiB.
constexpr size_t kFallbackQuota = size_t(10) << 30;

std::string mib(int64_t bytes) { return std::to_string((bytes + (1 << 20) - 1) >> 20) + " MiB"; }

}  // namespace

int64_t estimated_artifact_bytes(const JobOutput& out, int64_t input_bytes) {
    if (out.kind != OutputKind::render) return kConversionGrowth * input_bytes;
    const RenderRequest r = parse_render_options(out.options_json);
    // Several views: a frame each (a contact sheet of them, or a file each).
    const int64_t pixels = int64_t(r.width) * r.height * std::max<int64_t>(1, static_cast<int64_t>(r.views.size()));
    return pixels * (r.format.kind == ImageFormat::exr ? kExrBytesPerPixel : kRgbaBytesPerPixel);
}

size_t default_artifact_quota(const std::string& data_dir) {
    struct statvfs fs {};
    if (::statvfs(data_dir.c_str(), &fs) != 0 || fs.f_blocks == 0) return kFallbackQuota;
    return static_cast<size_t>(fs.f_blocks) * fs.f_frsize / 2;
}

void check_artifact_quota(int64_t used, int64_t more, size_t quota, const std::string& what) {
    if (used + more <= static_cast<int64_t>(quota)) return;
    throw Error(ErrorCode::limit_exceeded, what + " (" + mib(more) + ") would exceed the artifact quota of " +
                                               mib(static_cast<int64_t>(quota)) + " (" + mib(used) +
                                               " in use by kept jobs): delete finished jobs (DELETE /v1/jobs/{id}) "
                                               "or wait for them to expire");
}

}  // namespace nurbsrt::server
