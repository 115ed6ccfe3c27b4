// The admission gate (server/render/admission.h) as batch jobs use it: a waiter with
// a give-up condition keeps its place in the order, leaves the queue soon
// after the condition becomes true, and the waiters behind it go on.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <future>
#include <thread>

#include "server/render/admission.h"

using nurbsrt::server::AdmissionGate;
using namespace std::chrono_literals;

namespace {

// Waits until the gate reports `n` queued waiters (they enter on other threads).
void wait_queued(const AdmissionGate& gate, int n) {
    const auto deadline = std::chrono::steady_clock::now() + 10s;
    while (gate.queued() != n) {
        ASSERT_LT(std::chrono::steady_clock::now(), deadline) << "never " << n << " queued";
        std::this_thread::sleep_for(1ms);
    }
}

TEST(AdmissionGate, WaiterThatGivesUpLeavesAndOthersGoOn) {
    AdmissionGate gate(1, 4);
    AdmissionGate::Refusal why;
    auto held = gate.enter(1s, why);
    ASSERT_TRUE(held);

    std::atomic<bool> give_up{false};
    auto job = std::async(std::launch::async, [&] {
        AdmissionGate::Refusal w;
        auto t = gate.enter(std::chrono::hours(1), w, [&] { return give_up.load(); });
        return std::make_pair(t != nullptr, w);
    });
    wait_queued(gate, 1);
    auto request = std::async(std::launch::async, [&] {
        AdmissionGate::Refusal w;
        return gate.enter(10s, w) != nullptr;
    });
    wait_queued(gate, 2);

    const auto t0 = std::chrono::steady_clock::now();
    give_up = true;
    const auto [admitted, reason] = job.get();
    EXPECT_FALSE(admitted);
    EXPECT_EQ(reason, AdmissionGate::Refusal::gave_up);
    EXPECT_LT(std::chrono::steady_clock::now() - t0, 2s);
    EXPECT_EQ(gate.queued(), 1);

    held.reset();  // the request behind the job that left is served
    EXPECT_TRUE(request.get());
}

TEST(AdmissionGate, WaiterWithGiveUpKeepsItsPlace) {
    AdmissionGate gate(1, 4);
    AdmissionGate::Refusal why;
    auto held = gate.enter(1s, why);
    ASSERT_TRUE(held);
    std::atomic<int> order{0};
    int job_turn = -1, request_turn = -1;
    std::thread job([&] {
        AdmissionGate::Refusal w;
        auto t = gate.enter(std::chrono::hours(1), w, [] { return false; });
        job_turn = order++;
        std::this_thread::sleep_for(20ms);
    });
    wait_queued(gate, 1);
    std::thread request([&] {
        AdmissionGate::Refusal w;
        auto t = gate.enter(10s, w);
        request_turn = order++;
    });
    wait_queued(gate, 2);
    held.reset();
    job.join();
    request.join();
    EXPECT_EQ(job_turn, 0);  // first come, first served
    EXPECT_EQ(request_turn, 1);
}

}  // namespace

namespace {

constexpr size_t kMiB = size_t(1) << 20;

TEST(AdmissionGate, MemoryCapacityBoundsWhatIsHeldTogether) {
    AdmissionGate gate(8, 4, 100 * kMiB);
    AdmissionGate::Refusal why;
    EXPECT_FALSE(gate.enter(0ms, why, {}, 101 * kMiB));  // never fits: refused without waiting
    EXPECT_EQ(why, AdmissionGate::Refusal::too_large);
    auto a = gate.enter(0ms, why, {}, 60 * kMiB);
    ASSERT_TRUE(a);
    EXPECT_EQ(gate.used_bytes(), 60 * kMiB);
    auto small = gate.enter(0ms, why, {}, 40 * kMiB);  // exactly fills the capacity
    ASSERT_TRUE(small);
    EXPECT_FALSE(gate.enter(50ms, why, {}, 1));  // full: waits, then times out
    EXPECT_EQ(why, AdmissionGate::Refusal::queue_timeout);
    small.reset();
    EXPECT_EQ(gate.used_bytes(), 60 * kMiB);
    EXPECT_TRUE(gate.enter(0ms, why, {}, 40 * kMiB));
}

// gate.enter for `bytes`, waiting up to 10 s, on a thread of its own.
auto enter_waiting(AdmissionGate& gate, size_t bytes) {
    return std::async(std::launch::async, [&gate, bytes] {
        AdmissionGate::Refusal w;
        return gate.enter(10s, w, {}, bytes);
    });
}

TEST(AdmissionGate, LargeWaiterIsNotOvertakenBySmallOnes) {
    AdmissionGate gate(8, 4, 100 * kMiB);
    AdmissionGate::Refusal why;
    auto held = gate.enter(0ms, why, {}, 50 * kMiB);
    ASSERT_TRUE(held);
    // 80 MiB does not fit beside 50: it waits at the head of the queue ...
    auto large = enter_waiting(gate, 80 * kMiB);
    wait_queued(gate, 1);
    // ... and a small request that would fit waits behind it, in order.
    auto small = enter_waiting(gate, 10 * kMiB);
    wait_queued(gate, 2);
    EXPECT_EQ(small.wait_for(100ms), std::future_status::timeout);
    held.reset();
    auto large_ticket = large.get();
    ASSERT_TRUE(large_ticket);
    auto small_ticket = small.get();  // 80 + 10 fit together
    ASSERT_TRUE(small_ticket);
    EXPECT_EQ(gate.used_bytes(), 90 * kMiB);
    EXPECT_EQ(gate.active(), 2);
}

}  // namespace

namespace {

TEST(AdmissionGate, ShortWorkOvertakesLargeWorkWaitingForMemory) {
    AdmissionGate gate(8, 4, 100 * kMiB);
    AdmissionGate::Refusal why;
    auto running = gate.enter(0ms, why, {}, 70 * kMiB);
    ASSERT_TRUE(running);
    auto large = enter_waiting(gate, 60 * kMiB);  // waits for the running work's memory
    wait_queued(gate, 1);
    // The large waiter cannot start before the running work ends anyway: short
    // work that fits beside the running one goes ahead instead of waiting.
    auto small = gate.enter(0ms, why, {}, 20 * kMiB, AdmissionGate::Order::may_overtake);
    ASSERT_TRUE(small) << static_cast<int>(why);
    running.reset();  // 20 held: the large one (60) fits now
    auto large_ticket = large.get();
    ASSERT_TRUE(large_ticket);
    // Now 80 of 100 are held; short work of 30 would not fit and waits for memory.
    EXPECT_FALSE(gate.enter(50ms, why, {}, 30 * kMiB, AdmissionGate::Order::may_overtake));
    EXPECT_EQ(why, AdmissionGate::Refusal::queue_timeout);
}

}  // namespace
