// Stage timings that add up: one steady clock, stages marked end to end from a
// start, so the stages of a request (or a frame) sum to its total by
// construction. A stage runs from the previous mark to its own mark; the small
// set-up between two pieces of named work therefore belongs to the stage that
// follows it, and no time is left unnamed.
//
// Work measured elsewhere inside a running stage (a child process's own
// stages, a frame's passes measured by the renderer) is recorded with add():
// it is taken out of the stage that encloses it, so the total is still the sum.
#pragma once

#include <chrono>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace nurbsrt {

class StageClock {
public:
    using Clock = std::chrono::steady_clock;
    struct Stage {
        std::string name;
        double ms = 0;
    };

    explicit StageClock(Clock::time_point start = Clock::now()) : start_(start), last_(start) {}

    // Ends the running stage at `at`: the time since the previous mark, less
    // what add() recorded meanwhile, is added to `stage` (a stage may be marked
    // several times; its parts add). Returns that time. A mark before the
    // previous one counts as none (the clock never runs backwards).
    double mark(std::string_view stage, Clock::time_point at = Clock::now());
    // `ms` of `stage` spent inside the running stage, measured by someone else
    // (negative or non-finite values count as 0).
    void add(std::string_view stage, double ms);

    // The time of `stage` so far; 0 when it was never marked or added.
    double ms(std::string_view stage) const;
    // From the start to the last mark. Equal to the sum of the stages unless
    // add() recorded more than its enclosing stage's time (then that stage is
    // 0 and the sum exceeds the total by the excess; never with nested
    // intervals measured on this clock).
    double total_ms() const;
    double sum_ms() const;
    Clock::time_point start() const { return start_; }
    const std::vector<Stage>& stages() const { return stages_; }  // in order of first mark

private:
    double& slot(std::string_view stage);

    Clock::time_point start_, last_;
    double nested_ms_ = 0;  // add()ed since the last mark
    std::vector<Stage> stages_;
};

}  // namespace nurbsrt
