// core/json_limits.h: client JSON is measured before it is parsed, so that no
// nesting depth, size or number of values can reach the recursive parts of
// nlohmann::json (dump, copies, merge_patch) or allocate without bound.
#include <gtest/gtest.h>

#include <string>

#include "core/error.h"
#include "core/json_limits.h"

using nurbsrt::JsonLimits;
using nurbsrt::JsonProblem;
using nurbsrt::kRequestJsonLimits;
using nurbsrt::parse_json_bounded;

namespace {

std::string nested_arrays(int depth) { return std::string(depth, '[') + std::string(depth, ']'); }

}  // namespace

TEST(JsonLimits, DepthUpToTheLimitParsesAndOneMoreIsRefused) {
    const auto at = parse_json_bounded(nested_arrays(64), kRequestJsonLimits);
    EXPECT_TRUE(at.ok()) << at.detail;
    EXPECT_TRUE(at.value.is_array());
    const auto over = parse_json_bounded(nested_arrays(65), kRequestJsonLimits);
    EXPECT_EQ(over.problem, JsonProblem::too_deep);
    EXPECT_NE(over.detail.find("64"), std::string::npos) << over.detail;
    EXPECT_TRUE(over.value.is_discarded());
}

TEST(JsonLimits, VeryDeepTextIsRefusedWithoutRecursing) {
    // A million levels: once parsed, dump() or a copy of it would overflow the stack.
    for (const int depth : {10'000, 60'000, 1'000'000}) {
        const std::string text = "{\"x\":" + nested_arrays(depth) + "}";
        const auto r = parse_json_bounded(text, nurbsrt::kDocumentJsonLimits);
        EXPECT_EQ(r.problem, JsonProblem::too_deep) << depth;
    }
    // Objects count as levels too, and brackets inside strings do not.
    std::string objects;
    for (int i = 0; i < 100; ++i) objects += "{\"a\":";
    objects += "0" + std::string(100, '}');
    EXPECT_EQ(parse_json_bounded(objects, kRequestJsonLimits).problem, JsonProblem::too_deep);
    // (Appended piecewise: "..." + std::string + "..." trips GCC 12's -Wrestrict false positive, GCC bug 105329.)
    std::string quoted = "{\"s\":\"";
    quoted.append(1000, '[');
    quoted += "\\\"]\"}";
    const auto in_string = parse_json_bounded(quoted, kRequestJsonLimits);
    EXPECT_TRUE(in_string.ok()) << in_string.detail;
}

TEST(JsonLimits, SizeAndValueCountAreBounded) {
    const std::string big = "{\"x\":\"" + std::string(300'000, 'a') + "\"}";
    const auto large = parse_json_bounded(big, kRequestJsonLimits);
    EXPECT_EQ(large.problem, JsonProblem::too_large);
    EXPECT_NE(large.detail.find("262144"), std::string::npos) << large.detail;

    std::string many = "[0";
    for (int i = 0; i < 30'000; ++i) many += ",0";
    many += "]";
    ASSERT_LT(many.size(), kRequestJsonLimits.max_bytes);
    const auto values = parse_json_bounded(many, kRequestJsonLimits);
    EXPECT_EQ(values.problem, JsonProblem::too_many_values);
    EXPECT_NE(values.detail.find("20000"), std::string::npos) << values.detail;

    // Without bounds (scene files) the same text parses.
    EXPECT_TRUE(parse_json_bounded(many, nurbsrt::kDocumentJsonLimits).ok());
}

TEST(JsonLimits, TextThatIsNotJsonIsRefusedWithItsPosition) {
    for (const char* text : {"", "{\"file_id\":\"ab", "{\"a\": NaN}", "{\"w\":1e400}", "{\"a\":1} xyz", "]]][[["}) {
        const auto r = parse_json_bounded(text, kRequestJsonLimits);
        EXPECT_EQ(r.problem, JsonProblem::not_json) << text;
        EXPECT_EQ(r.detail.rfind("not JSON", 0), 0u) << r.detail;
    }
    // Invalid UTF-8 is not JSON; the message never echoes the bytes.
    const auto bad_utf8 = parse_json_bounded("{\"a\":\"\xff\xfe\"}", kRequestJsonLimits);
    EXPECT_EQ(bad_utf8.problem, JsonProblem::not_json);
    EXPECT_EQ(bad_utf8.detail.find('\xff'), std::string::npos);
}

TEST(JsonLimits, ThrowingFormNamesWhatAndTheLimit) {
    try {
        (void)nurbsrt::parse_json_or_throw(nested_arrays(100), kRequestJsonLimits, "the 'job' part");
        FAIL() << "no exception";
    } catch (const nurbsrt::Error& e) {
        EXPECT_EQ(e.code(), nurbsrt::ErrorCode::invalid_json);
        EXPECT_EQ(std::string(e.what()), "the 'job' part: the JSON text is nested deeper than 64 levels");
    }
    EXPECT_EQ(nurbsrt::parse_json_or_throw("{\"a\":[1,2]}", kRequestJsonLimits, "x")["a"][1], 2);
}
