// A bounded admission gate: at most `max_active` holders at once, together
// holding at most `capacity_bytes` of (estimated) memory; at most `max_queued`
// wait (each for at most a timeout); anything beyond is turned away at once (the
// caller answers 503 with Retry-After). Requests are admitted in arrival order,
// so a large request waiting for memory is not overtaken for ever by small ones.
// The service has two: imports and conversions (child processes, by count), and
// renders (by their memory estimate against the process's budget).
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <vector>

namespace nurbsrt::server {

class AdmissionGate {
public:
    AdmissionGate(int max_active, int max_queued, size_t capacity_bytes = SIZE_MAX)
        : max_active_(max_active), max_queued_(max_queued), capacity_bytes_(capacity_bytes) {}

    // Held while the work runs; releasing it (destruction) admits the next waiter.
    // Shared so that work that outlives its request (a render past its time
    // limit, still running) keeps its slot until it really ends.
    class Ticket {
    public:
        Ticket(AdmissionGate& g, size_t bytes) : gate_(g), bytes_(bytes) {}
        ~Ticket() { gate_.release(bytes_); }
        size_t bytes() const { return bytes_; }
        Ticket(const Ticket&) = delete;
        Ticket& operator=(const Ticket&) = delete;

    private:
        AdmissionGate& gate_;
        const size_t bytes_;
    };

    // too_large: `bytes` alone exceed the capacity (refused without waiting).
    enum class Refusal { none, queue_full, queue_timeout, gave_up, too_large };

    // A ticket, or nullptr with `why` set when the queue is full or the wait timed out.
    // `give_up`, when set, is polled while waiting (a few times a second): once it
    // returns true the caller leaves the queue (a batch job that was canceled or a
    // service stopping), without losing its place in the order before that.
    // fifo: admitted in arrival order. may_overtake: short work (an interactive
    // render) is admitted as soon as it fits, ahead of earlier waiters, but never
    // with memory the first waiter could take now: it delays that waiter only by
    // its own short run, and is never stuck behind large work waiting for memory.
    enum class Order { fifo, may_overtake };

    // `bytes`: the memory the holder will use, held against the capacity.
    std::shared_ptr<Ticket> enter(std::chrono::milliseconds max_wait, Refusal& why,
                                  const std::function<bool()>& give_up = {}, size_t bytes = 0,
                                  Order order = Order::fifo);

    int active() const;
    int queued() const;
    size_t used_bytes() const;
    int max_active() const { return max_active_; }
    int max_queued() const { return max_queued_; }
    size_t capacity_bytes() const { return capacity_bytes_; }

private:
    void release(size_t bytes);
    void skip_abandoned();  // with m_ held
    // With m_ held: true while `wait` (false: returned for the deadline) and not given up.
    bool wait_for(std::unique_lock<std::mutex>& lock, std::chrono::steady_clock::time_point deadline,
                  const std::function<bool()>& ready, const std::function<bool()>& give_up, bool& gave_up);
    std::shared_ptr<Ticket> overtake(std::unique_lock<std::mutex>& lock, std::chrono::milliseconds max_wait,
                                     Refusal& why, const std::function<bool()>& give_up, size_t bytes);

    const int max_active_, max_queued_;
    const size_t capacity_bytes_;
    mutable std::mutex m_;
    std::condition_variable cv_;
    int active_ = 0, queued_ = 0;
    size_t used_bytes_ = 0;
    uint64_t next_number_ = 0, serving_ = 0;                 // FIFO among waiters
    std::vector<uint64_t> abandoned_;                        // numbers whose waiters timed out
    std::vector<std::pair<uint64_t, size_t>> fifo_waiting_;  // number and bytes of each FIFO waiter
};

}  // namespace nurbsrt::server
