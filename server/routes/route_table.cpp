#include "server/routes/route_table.h"

#include <httplib.h>

#include <algorithm>
#include <regex>
#include <string_view>

#include "server/render/context.h"
#include "server/routes/handler_util.h"
#include "server/routes/routes.h"

namespace nurbsrt::server {

const std::vector<Route>& route_table() {
    using M = HttpMethod;
    static const std::vector<Route> table = {
        {"/v1/renders", "/v1/renders", {{M::post, handle_render}}},
        {"/v1/conversions", "/v1/conversions", {{M::post, handle_conversion}}},
        {"/v1/jobs", "/v1/jobs", {{M::get, handle_job_list}, {M::post, handle_job_submit}}},
        {"/v1/jobs/{id}", R"(/v1/jobs/([^/]+))", {{M::get, handle_job_get}, {M::del, handle_job_delete}}},
        {"/v1/jobs/{id}/events", R"(/v1/jobs/([^/]+)/events)", {{M::get, handle_job_events}}},
        {"/v1/jobs/{id}/artifacts/{name}", R"(/v1/jobs/([^/]+)/artifacts/([^/]+))", {{M::get, handle_job_artifact}}},
        {"/v1/files", "/v1/files", {{M::get, handle_file_list}, {M::post, handle_file_upload}}},
        {"/v1/files/{id}",
         R"(/v1/files/([^/]+))",
         {{M::get, handle_file_get}, {M::patch, handle_file_patch}, {M::del, handle_file_delete}}},
        {"/v1/files/{id}/content", R"(/v1/files/([^/]+)/content)", {{M::get, handle_file_content}}},
        {"/healthz", "/healthz", {{M::get, handle_healthz}}},
        {"/readyz", "/readyz", {{M::get, handle_readyz}}},
        {"/metrics", "/metrics", {{M::get, handle_metrics}}},
        {"/v1/openapi.json", R"(/v1/openapi\.json)", {{M::get, handle_openapi}}},
        {"/", "/", {{M::get, handle_page}}},
        {"/web/{name}", R"(/web/([A-Za-z0-9_.-]+))", {{M::get, handle_web_file}}},
    };
    return table;
}

void register_routes(httplib::Server& svr, ServerContext& ctx) {
    for (const Route& route : route_table()) {
        for (const RouteMethod& m : route.methods) {
            auto handler = guarded(ctx, m.handler);
            switch (m.method) {
                case HttpMethod::get:
                    svr.Get(route.pattern, handler);
                    break;
                case HttpMethod::post:
                    svr.Post(route.pattern, handler);
                    break;
                case HttpMethod::patch:
                    svr.Patch(route.pattern, handler);
                    break;
                case HttpMethod::del:
                    svr.Delete(route.pattern, handler);
                    break;
            }
        }
    }
}

namespace {

// Each route's compiled pattern and Allow header, made once from the table.
struct CompiledRoute {
    const Route* route;
    bool literal;  // a fixed path: compared, not matched (most requests name one)
    std::regex pattern;
    std::string allow;
};

std::string allow_header(const Route& route) {
    auto has = [&](HttpMethod method) {
        return std::any_of(route.methods.begin(), route.methods.end(),
                           [&](const RouteMethod& m) { return m.method == method; });
    };
    std::string allow;
    auto add = [&](const char* name) { allow += allow.empty() ? name : std::string(", ") + name; };
    if (has(HttpMethod::get)) add("GET"), add("HEAD");
    if (has(HttpMethod::post)) add("POST");
    if (has(HttpMethod::patch)) add("PATCH");
    if (has(HttpMethod::del)) add("DELETE");
    add("OPTIONS");
    return allow;
}

const std::vector<CompiledRoute>& compiled_routes() {
    static const std::vector<CompiledRoute> compiled = [] {
        std::vector<CompiledRoute> v;
        for (const Route& r : route_table())
            v.push_back({&r, std::string_view(r.pattern).find_first_of("\\()[]{}*+?.^$|") == std::string_view::npos,
                         std::regex(r.pattern), allow_header(r)});
        return v;
    }();
    return compiled;
}

}  // namespace

std::string route_of(const std::string& path) {
    for (const CompiledRoute& c : compiled_routes())
        if (c.literal ? path == c.route->pattern : std::regex_match(path, c.pattern)) return c.route->name;
    return "other";
}

const char* allowed_methods(const std::string& route) {
    for (const CompiledRoute& c : compiled_routes())
        if (route == c.route->name) return c.allow.c_str();
    return "";
}

bool allows_method(const std::string& route, const std::string& method) {
    if (method.empty()) return false;
    const std::string_view allow = allowed_methods(route);
    for (size_t start = 0; start < allow.size();) {
        const size_t comma = std::min(allow.find(',', start), allow.size());
        if (allow.substr(start, comma - start) == method) return true;
        start = comma + 2;  // ", "
    }
    return false;
}

}  // namespace nurbsrt::server
