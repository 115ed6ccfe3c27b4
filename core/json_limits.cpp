#include "core/json_limits.h"

#include "core/error.h"

namespace nurbsrt {
namespace {

struct Measure {
    int depth = 0;
    size_t values = 0;
};

// One pass over the text, outside strings: every '[' and '{' opens a level and
// a value, every ',' separates one more value (or member), so `values` bounds
// the number of values from above. For text that is JSON both are exact enough;
// text that is not is refused by the parser afterwards.
JsonProblem measure(std::string_view text, const JsonLimits& limits, Measure& m) {
    int depth = 0;
    bool in_string = false, escaped = false;
    m.values = text.empty() ? 0 : 1;
    for (const char c : text) {
        if (in_string) {
            if (escaped)
                escaped = false;
            else if (c == '\\')
                escaped = true;
            else if (c == '"')
                in_string = false;
            continue;
        }
        switch (c) {
            case '"':
                in_string = true;
                break;
            case '[':
            case '{':
                ++m.values;
                if (++depth > limits.max_depth) {
                    m.depth = depth;
                    return JsonProblem::too_deep;
                }
                break;
            case ']':
            case '}':
                --depth;
                break;
            case ',':
                ++m.values;
                break;
            default:
                break;
        }
        if (limits.max_values && m.values > limits.max_values) return JsonProblem::too_many_values;
    }
    return JsonProblem::none;
}

}  // namespace

BoundedJson parse_json_bounded(std::string_view text, const JsonLimits& limits) {
    // Depth first: the measure stops at the first level too deep, and that
    // names the cause of a deeply nested text better than its size.
    BoundedJson out;
    out.value = nlohmann::json(nlohmann::json::value_t::discarded);
    Measure m;
    out.problem = measure(text, limits, m);
    if (out.problem == JsonProblem::too_deep) {
        out.detail = "the JSON text is nested deeper than " + std::to_string(limits.max_depth) + " levels";
        return out;
    }
    if (out.problem == JsonProblem::too_many_values) {
        out.detail = "the JSON text holds more than " + std::to_string(limits.max_values) + " values";
        return out;
    }
    if (limits.max_bytes && text.size() > limits.max_bytes) {
        out.problem = JsonProblem::too_large;
        out.detail = "the JSON text is " + std::to_string(text.size()) + " bytes, over the limit of " +
                     std::to_string(limits.max_bytes);
        return out;
    }
    try {
        out.value = nlohmann::json::parse(text);
    } catch (const nlohmann::json::parse_error& e) {
        // The position only: nlohmann's message quotes the input, which may not be UTF-8.
        out.problem = JsonProblem::not_json;
        out.detail = text.empty() ? "not JSON (empty)"
                                  : "not JSON (a syntax error at byte " + std::to_string(e.byte) + " of " +
                                        std::to_string(text.size()) + ")";
        out.value = nlohmann::json(nlohmann::json::value_t::discarded);
    } catch (const nlohmann::json::out_of_range&) {
        // 1e400: RFC 8259 §6 leaves numbers beyond a double to the parser.
        out.problem = JsonProblem::not_json;
        out.detail = "not JSON (a number beyond the range of a double)";
    }
    return out;
}

nlohmann::json parse_json_or_throw(std::string_view text, const JsonLimits& limits, const std::string& what) {
    BoundedJson j = parse_json_bounded(text, limits);
    if (!j.ok()) throw Error(ErrorCode::invalid_json, what + ": " + j.detail);
    return std::move(j.value);
}

}  // namespace nurbsrt
