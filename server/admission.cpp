#include "server/admission.h"

#include <algorithm>

namespace nurbsrt::server {

std::shared_ptr<AdmissionGate::Ticket> AdmissionGate::enter(std::chrono::milliseconds max_wait, Refusal& why,
                                                            const std::function<bool()>& give_up) {
    std::unique_lock<std::mutex> lock(m_);
    why = Refusal::none;
    if (queued_ == 0 && active_ < max_active_) {
        ++active_;
        return std::make_shared<Ticket>(*this);
    }
    if (queued_ >= max_queued_) {
        why = Refusal::queue_full;
        return nullptr;
    }
    ++queued_;
    const uint64_t my_number = next_number_++;
    const auto deadline = std::chrono::steady_clock::now() + max_wait;
    const auto my_turn = [&] { return serving_ == my_number && active_ < max_active_; };
    bool admitted = false, gave_up = false;
    if (!give_up) {
        admitted = cv_.wait_until(lock, deadline, my_turn);
    } else {
        while (!(admitted = my_turn())) {
            if (give_up()) {
                gave_up = true;
                break;
            }
            const auto next = std::min(deadline, std::chrono::steady_clock::now() + std::chrono::milliseconds(100));
            if (!cv_.wait_until(lock, next, my_turn) && std::chrono::steady_clock::now() >= deadline) break;
        }
    }
    --queued_;
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
    cv_.notify_all();
    return std::make_shared<Ticket>(*this);
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

void AdmissionGate::release() {
    {
        std::lock_guard<std::mutex> lock(m_);
        --active_;
    }
    cv_.notify_all();
}

int AdmissionGate::active() const {
    std::lock_guard<std::mutex> lock(m_);
    return active_;
}

int AdmissionGate::queued() const {
    std::lock_guard<std::mutex> lock(m_);
    return queued_;
}

}  // namespace nurbsrt::server
