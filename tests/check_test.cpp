// The invariant checks (core/check.h): a broken invariant becomes Error(internal)
// naming the condition and the file, never a crash or a silent corruption.
#include <gtest/gtest.h>

#include <string>

#include "core/check.h"
#include "core/error.h"

using nurbsrt::Error;
using nurbsrt::ErrorCode;

TEST(Check, HoldsQuietlyAndThrowsInternalWhenBroken) {
    EXPECT_NO_THROW(NURBSRT_CHECK(1 + 1 == 2));
    try {
        const int faces = 3;
        NURBSRT_CHECK(faces == 4);
        FAIL() << "no throw";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::internal);
        const std::string what = e.what();
        EXPECT_NE(what.find("invariant broken: faces == 4 (check_test.cpp:"), std::string::npos) << what;
        EXPECT_EQ(what.find('/'), std::string::npos) << "no build directory in the message: " << what;
    }
}

TEST(Check, DebugOnlyChecksVanishInReleaseBuilds) {
    int evaluated = 0;
    auto broken = [&] { return ++evaluated < 0; };
#ifdef NDEBUG
    (void)broken;
    EXPECT_NO_THROW(NURBSRT_DCHECK(broken()));
    EXPECT_EQ(evaluated, 0);  // not even evaluated: free in the per-pixel loops
#else
    EXPECT_THROW(NURBSRT_DCHECK(broken()), Error);
    EXPECT_EQ(evaluated, 1);
#endif
}
