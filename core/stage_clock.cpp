#include "core/stage_clock.h"

#include <algorithm>
#include <cmath>

namespace nurbsrt {

double& StageClock::slot(std::string_view stage) {
    for (Stage& s : stages_)
        if (s.name == stage) return s.ms;
    stages_.push_back({std::string(stage), 0.0});
    return stages_.back().ms;
}

double StageClock::mark(std::string_view stage, Clock::time_point at) {
    at = std::max(at, last_);
    const double elapsed = std::chrono::duration<double, std::milli>(at - last_).count();
    const double own = std::max(0.0, elapsed - nested_ms_);
    slot(stage) += own;
    last_ = at;
    nested_ms_ = 0;
    return own;
}

void StageClock::add(std::string_view stage, double ms) {
    if (!(ms > 0) || !std::isfinite(ms)) ms = 0;
    slot(stage) += ms;
    nested_ms_ += ms;
}

double StageClock::ms(std::string_view stage) const {
    for (const Stage& s : stages_)
        if (s.name == stage) return s.ms;
    return 0.0;
}

double StageClock::total_ms() const { return std::chrono::duration<double, std::milli>(last_ - start_).count(); }

double StageClock::sum_ms() const {
    double sum = 0;
    for (const Stage& s : stages_) sum += s.ms;
    return sum;
}

}  // namespace nurbsrt
