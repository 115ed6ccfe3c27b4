#include "server/common/service_error.h"

namespace nurbsrt::server {

const char* service_code_name(ServiceCode code) {
    switch (code) {
        case ServiceCode::not_found:
            return "not_found";
        case ServiceCode::method_not_allowed:
            return "method_not_allowed";
        case ServiceCode::overloaded:
            return "overloaded";
        case ServiceCode::render_timeout:
            return "render_timeout";
        case ServiceCode::unauthorized:
            return "unauthorized";
        case ServiceCode::request_timeout:
            return "request_timeout";
        case ServiceCode::interrupted:
            return "interrupted";
        case ServiceCode::malformed_request:
            return "malformed_request";
        case ServiceCode::not_implemented:
            return "not_implemented";
    }
    return "internal";  // out-of-range value cast to ServiceCode
}

const char* ProblemCode::name() const {
    struct Name {
        const char* operator()(ErrorCode c) const { return error_code_name(c); }
        const char* operator()(ServiceCode c) const { return service_code_name(c); }
    };
    return visit(Name{});
}

}  // namespace nurbsrt::server
