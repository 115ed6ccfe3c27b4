// The bounded admission gate shared by renders and conversions: at most
// `max_active` run at once, at most `max_queued` wait (each for at most a
// timeout); anything beyond is turned away at once (the caller answers 503
// with Retry-After). Requests are admitted in arrival order.
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
    AdmissionGate(int max_active, int max_queued) : max_active_(max_active), max_queued_(max_queued) {}

    // Held while the work runs; releasing it (destruction) admits the next waiter.
    // Shared so that work that outlives its request (a render past its time
    // limit, still running) keeps its slot until it really ends.
    class Ticket {
    public:
        explicit Ticket(AdmissionGate& g) : gate_(g) {}
        ~Ticket() { gate_.release(); }
        Ticket(const Ticket&) = delete;
        Ticket& operator=(const Ticket&) = delete;

    private:
        AdmissionGate& gate_;
    };

    enum class Refusal { none, queue_full, queue_timeout, gave_up };

    // A ticket, or nullptr with `why` set when the queue is full or the wait timed out.
    // `give_up`, when set, is polled while waiting (a few times a second): once it
    // returns true the caller leaves the queue (a batch job that was canceled or a
    // service stopping), without losing its place in the order before that.
    std::shared_ptr<Ticket> enter(std::chrono::milliseconds max_wait, Refusal& why,
                                  const std::function<bool()>& give_up = {});

    int active() const;
    int queued() const;
    int max_active() const { return max_active_; }
    int max_queued() const { return max_queued_; }

private:
    void release();
    void skip_abandoned();  // with m_ held

    const int max_active_, max_queued_;
    mutable std::mutex m_;
    std::condition_variable cv_;
    int active_ = 0, queued_ = 0;
    uint64_t next_number_ = 0, serving_ = 0;  // FIFO among waiters
    std::vector<uint64_t> abandoned_;           // numbers whose waiters timed out
};

}  // namespace nurbsrt::server
