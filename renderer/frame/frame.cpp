// Progress reporting and cancellation of a frame's passes (see frame.h).
#include "renderer/frame/frame.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace nurbsrt {

void Progress::add(int64_t n) {
    if (!fn_) return;
    const int64_t d = done_.fetch_add(n, std::memory_order_relaxed) + n;
    if (d < next_.load(std::memory_order_relaxed)) return;
    std::unique_lock<std::mutex> lock(m_, std::try_to_lock);
    if (!lock.owns_lock()) return;
    const int64_t now = done_.load(std::memory_order_relaxed);
    if (now < next_.load(std::memory_order_relaxed)) return;
    next_.store(now + step_, std::memory_order_relaxed);
    report(std::min(0.999, double(now) / double(total_)));
}

void Progress::finish() {
    if (!fn_) return;
    std::lock_guard<std::mutex> lock(m_);
    report(1.0);
}

void Progress::report(double f) {
    if (f <= last_) return;
    last_ = f;
    fn_(f);
}

void throw_if_canceled(const RenderOptions& o) {
    if (canceled(o)) throw Error(ErrorCode::canceled, "the render was canceled");
}

}  // namespace nurbsrt
