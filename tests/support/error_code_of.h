// The ErrorCode of the nurbsrt::Error a call throws (a test failure when it
// throws none), for tests that check which typed error a bad input gets.
#pragma once

#include <gtest/gtest.h>

#include <functional>

#include "core/error.h"

namespace nurbsrt::test {

inline ErrorCode code_of(const std::function<void()>& f) {
    try {
        f();
    } catch (const Error& e) {
        return e.code();
    }
    ADD_FAILURE() << "no nurbsrt::Error thrown";
    return ErrorCode::internal;
}

}  // namespace nurbsrt::test
