#include "server/render/admission.h"

#include <algorithm>

namespace nurbsrt::server {

bool AdmissionGate::wait_for(std::unique_lock<std::mutex>& lock, std::chrono::steady_clock::time_point deadline,
                             const std::function<bool()>& ready, const std::function<bool()>& give_up, bool& gave_up) {
    gave_up = false;
    if (!give_up) return cv_.wait_until(lock, deadline, ready);
    // Polled a few times a second: the give-up condition has no way to wake us.
    constexpr auto kGiveUpPoll = std::chrono::milliseconds(100);
    while (!ready()) {
        if (give_up()) {
            gave_up = true;
            return false;
        }
        const auto next = std::min(deadline, std::chrono::steady_clock::now() + kGiveUpPoll);
        if (!cv_.wait_until(lock, next, ready) && std::chrono::steady_clock::now() >= deadline) return false;
    }
    return true;
}

std::shared_ptr<AdmissionGate::Ticket> AdmissionGate::enter(std::chrono::milliseconds max_wait, Refusal& why,
                                                            const std::function<bool()>& give_up, size_t bytes,
                                                            Order order) {
    std::unique_lock<std::mutex> lock(m_);
    why = Refusal::none;
    if (bytes > capacity_bytes_) {
        why = Refusal::too_large;
        return nullptr;
    }
    if (order == Order::may_overtake) return overtake(lock, max_wait, why, give_up, bytes);
    const auto fits = [&] { return active_ < max_active_ && used_bytes_ + bytes <= capacity_bytes_; };
    if (queued_ == 0 && fits()) {
        ++active_;
        used_bytes_ += bytes;
        return std::make_shared<Ticket>(*this, bytes);
    }
    if (queued_ >= max_queued_) {
        why = Refusal::queue_full;
        return nullptr;
    }
    ++queued_;
    const uint64_t my_number = next_number_++;
    fifo_waiting_.emplace_back(my_number, bytes);
    const auto deadline = std::chrono::steady_clock::now() + max_wait;
    bool gave_up = false;
    const bool admitted = wait_for(
        lock, deadline, [&] { return serving_ == my_number && fits(); }, give_up, gave_up);
    --queued_;
    fifo_waiting_.erase(std::find(fifo_waiting_.begin(), fifo_waiting_.end(), std::make_pair(my_number, bytes)));
    if (!admitted) {
        // Give up our place: waiters behind us must not wait for a number that never comes.
        // Numbers are served in order, so skip ours when it comes up (see release()).
        abandoned_.push_back(my_number);
        skip_abandoned();
        cv_.notify_all();
        why = gave_up ? Refusal::gave_up : Refusal::queue_timeout;
        return nullptr;
    }
    ++serving_;
    skip_abandoned();
    ++active_;
    used_bytes_ += bytes;
    cv_.notify_all();
    return std::make_shared<Ticket>(*this, bytes);
}

std::shared_ptr<AdmissionGate::Ticket> AdmissionGate::overtake(std::unique_lock<std::mutex>& lock,
                                                               std::chrono::milliseconds max_wait, Refusal& why,
                                                               const std::function<bool()>& give_up, size_t bytes) {
    // Fits now, and leaves the first FIFO waiter what it could take now (if
    // it cannot start anyway, until running work ends, taking free memory
    // meanwhile delays it by this short work at most).
    const auto ready = [&] {
        if (active_ >= max_active_ || used_bytes_ + bytes > capacity_bytes_) return false;
        for (const auto& [number, need] : fifo_waiting_) {
            if (number != serving_) continue;
            const bool head_fits_now = active_ < max_active_ && used_bytes_ + need <= capacity_bytes_;
            return !head_fits_now || (active_ + 1 < max_active_ && used_bytes_ + need + bytes <= capacity_bytes_);
        }
        return true;
    };
    if (!ready()) {
        if (queued_ >= max_queued_) {
            why = Refusal::queue_full;
            return nullptr;
        }
        ++queued_;
        bool gave_up = false;
        const bool admitted = wait_for(lock, std::chrono::steady_clock::now() + max_wait, ready, give_up, gave_up);
        --queued_;
        if (!admitted) {
            why = gave_up ? Refusal::gave_up : Refusal::queue_timeout;
            return nullptr;
        }
    }
    ++active_;
    used_bytes_ += bytes;
    cv_.notify_all();
    return std::make_shared<Ticket>(*this, bytes);
}

void AdmissionGate::skip_abandoned() {
    for (bool again = true; again;) {
        again = false;
        for (auto it = abandoned_.begin(); it != abandoned_.end(); ++it) {
            if (*it == serving_) {
                abandoned_.erase(it);
                ++serving_;
                again = true;
                break;
            }
        }
    }
}

void AdmissionGate::release(size_t bytes) {
    {
        std::lock_guard<std::mutex> lock(m_);
        --active_;
        used_bytes_ -= bytes;
    }
    cv_.notify_all();
}

int AdmissionGate::active() const {
    std::lock_guard<std::mutex> lock(m_);
    return active_;
}

size_t AdmissionGate::used_bytes() const {
    std::lock_guard<std::mutex> lock(m_);
    return used_bytes_;
}

int AdmissionGate::queued() const {
    std::lock_guard<std::mutex> lock(m_);
    return queued_;
}

}  // namespace nurbsrt::server
