#include "server/common/service_error.h"

#include "core/enum_names.h"

namespace nurbsrt::server {

namespace {

constexpr EnumName<ServiceCode> kServiceCodeNames[] = {
    {ServiceCode::not_found, "not_found"},           {ServiceCode::method_not_allowed, "method_not_allowed"},
    {ServiceCode::overloaded, "overloaded"},         {ServiceCode::render_timeout, "render_timeout"},
    {ServiceCode::unauthorized, "unauthorized"},     {ServiceCode::request_timeout, "request_timeout"},
    {ServiceCode::interrupted, "interrupted"},       {ServiceCode::malformed_request, "malformed_request"},
    {ServiceCode::not_acceptable, "not_acceptable"}, {ServiceCode::not_implemented, "not_implemented"},
    {ServiceCode::strict_refused, "strict_refused"}};
static_assert(names_every_value(kServiceCodeNames, ServiceCode::strict_refused));

}  // namespace

const char* service_code_name(ServiceCode code) {
    return enum_name(kServiceCodeNames, code, "internal");  // "internal": an out-of-range value cast to ServiceCode
}

const char* ProblemCode::name() const {
    struct Name {
        const char* operator()(ErrorCode c) const { return error_code_name(c); }
        const char* operator()(ServiceCode c) const { return service_code_name(c); }
    };
    return visit(Name{});
}

}  // namespace nurbsrt::server

namespace nurbsrt::server {

ServiceError strict_refusal(const std::vector<std::string>& warnings) {
    std::string detail = std::to_string(warnings.size()) + " warning(s), refused by strict:";
    for (const std::string& w : warnings) detail += " " + w + ";";
    return ServiceError(ServiceCode::strict_refused, detail);
}

}  // namespace nurbsrt::server
