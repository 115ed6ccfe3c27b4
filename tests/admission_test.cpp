// The admission gate (server/admission.h) as batch jobs use it: a waiter with
// a give-up condition keeps its place in the order, leaves the queue soon
// after the condition becomes true, and the waiters behind it go on.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <future>
#include <thread>

#include "server/admission.h"

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
