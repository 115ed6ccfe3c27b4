// Inputs the libFuzzer harnesses of fuzz/ found to break our parsers, reduced
// to what broke them (the exact inputs are in fuzz/regressions/). Each must be
// refused with nurbsrt::Error like any other bad input, never escape as
// another exception or crash.
#include <gtest/gtest.h>
#include <httplib.h>

#include <functional>
#include <string>

#include "renderer/error.h"
#include "server/upload.h"

using nurbsrt::Error;
using nurbsrt::ErrorCode;

namespace {

ErrorCode code_of(const std::function<void()>& f) {
    try {
        f();
    } catch (const Error& e) {
        return e.code();
    }
    ADD_FAILURE() << "no nurbsrt::Error thrown";
    return ErrorCode::internal;
}

// A query string is bytes: "?heig\xFB\xFB...ht=10" reached the options as a
// JSON key, and writing that JSON threw nlohmann's invalid UTF-8 type_error,
// which became a 500 instead of a 400.
TEST(FuzzRegressions, QueryParameterThatIsNotUtf8IsInvalidArgument) {
    for (const bool in_name : {true, false}) {
        httplib::Request req;
        req.method = "POST";
        req.set_header("Content-Type", "model/step");
        req.body = "ISO-10303-21;";
        req.params.emplace("width", "20");
        if (in_name)
            req.params.emplace("heig\xFB\xFBht", "10");
        else
            req.params.emplace("view", "to\xFFp");
        EXPECT_EQ(code_of([&] { (void)nurbsrt::server::read_upload(req); }), ErrorCode::invalid_argument)
            << (in_name ? "in a name" : "in a value");
    }
}

}  // namespace
