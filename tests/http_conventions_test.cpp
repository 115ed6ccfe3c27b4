// The pure parts of the service's HTTP conventions: the route table behind 405
// and Allow, the CORS policy, and entity tags with If-None-Match matching.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "core/error.h"
#include "server/render/context.h"
#include "server/common/cors.h"
#include "server/http/etag.h"
#include "server/http/problem.h"
#include "server/routes/route_table.h"
#include "server/common/service_error.h"

using namespace nurbsrt::server;

TEST(RouteTable, TemplatesAndAllowedMethods) {
    const std::pair<const char*, const char*> kRoutes[] = {
        {"/v1/renders", "/v1/renders"},
        {"/v1/jobs/abc", "/v1/jobs/{id}"},
        {"/v1/jobs/abc/artifacts/0-render-0.png", "/v1/jobs/{id}/artifacts/{name}"},
        {"/web/app.js", "/web/{name}"},
        {"/v1/files", "/v1/files"},
        {"/v1/files/abc", "/v1/files/{id}"},
        {"/v1/files/abc/content", "/v1/files/{id}/content"},
        {"/v1/files/abc/other", "other"},
        {"/web/a/b.js", "other"},
        {"/v1/renders/", "other"},
    };
    for (const auto& [path, route] : kRoutes) EXPECT_EQ(route_of(path), route) << path;
    EXPECT_TRUE(allows_method("/v1/files/{id}", "PATCH"));
    EXPECT_TRUE(allows_method("/v1/files/{id}", "DELETE"));
    EXPECT_FALSE(allows_method("/v1/files/{id}/content", "DELETE"));
    EXPECT_STREQ(allowed_methods("other"), "");
    EXPECT_STREQ(allowed_methods("/v1/renders"), "POST, OPTIONS");
    EXPECT_TRUE(allows_method("/v1/renders", "POST"));
    EXPECT_TRUE(allows_method("/v1/renders", "OPTIONS"));
    EXPECT_FALSE(allows_method("/v1/renders", "GET"));
    EXPECT_FALSE(allows_method("/v1/renders", "POS"));  // whole names only
    EXPECT_FALSE(allows_method("/v1/renders", "POST, OPTIONS"));
    EXPECT_FALSE(allows_method("/v1/renders", ""));
    EXPECT_TRUE(allows_method("/v1/jobs/{id}", "DELETE"));
    EXPECT_TRUE(allows_method("/healthz", "HEAD"));
    EXPECT_FALSE(allows_method("/healthz", "DELETE"));
    EXPECT_FALSE(allows_method("other", "GET"));
}

// The route table and the API document describe the same routes and methods:
// a handler added to one and not the other fails here.
TEST(RouteTable, IsTheApiDocumentsPaths) {
    const nlohmann::json doc = nlohmann::json::parse(openapi_document());
    std::set<std::string> documented, served;
    for (const auto& [path, item] : doc.at("paths").items())
        for (const auto& [method, op] : item.items())
            if (method != "options" && method != "parameters" && method != "summary" && method != "description")
                documented.insert(method + " " + path);
    for (const Route& route : route_table()) {
        const std::string name = route.name;
        if (name.find('{') == std::string::npos) {
            EXPECT_EQ(route_of(name), name);  // a fixed path is its own template
        }
        for (const RouteMethod& m : route.methods) {
            static const char* const names[] = {"get", "post", "patch", "delete"};
            served.insert(std::string(names[static_cast<int>(m.method)]) + " " + route.name);
            ASSERT_NE(m.handler, nullptr) << route.name;
        }
    }
    EXPECT_EQ(served, documented);
    // The Allow headers the table makes, method by method in RFC 9110's order.
    EXPECT_STREQ(allowed_methods("/v1/jobs"), "GET, HEAD, POST, OPTIONS");
    EXPECT_STREQ(allowed_methods("/v1/files/{id}"), "GET, HEAD, PATCH, DELETE, OPTIONS");
    EXPECT_STREQ(allowed_methods("/v1/jobs/{id}"), "GET, HEAD, DELETE, OPTIONS");
    EXPECT_STREQ(allowed_methods("/v1/openapi.json"), "GET, HEAD, OPTIONS");
    EXPECT_EQ(route_of("/v1/openapiXjson"), "other");  // the dot is not a wildcard
}

TEST(Cors, OriginsAreCheckedAndNormalized) {
    EXPECT_EQ(normalized_origin("HTTPS://App.Example.com:8443"), "https://app.example.com:8443");
    EXPECT_EQ(normalized_origin("http://[::1]:3000"), "http://[::1]:3000");
    for (const char* bad : {"*", "https://app.example.com/", "https://app.example.com/x", "app.example.com",
                            "ftp://x.org", "https://", "https://a b.org", "null", "https://x.org:123456"})
        EXPECT_THROW((void)normalized_origin(bad), nurbsrt::Error) << bad;
}

TEST(Cors, OnlyConfiguredOriginsGetHeaders) {
    const CorsPolicy off;
    EXPECT_FALSE(off.enabled());
    EXPECT_TRUE(off.response_headers("https://a.org").empty()) << "CORS off: not even Vary";

    const CorsPolicy cors({"https://a.org", "http://localhost:3000"});
    EXPECT_TRUE(cors.allows("https://a.org"));
    EXPECT_TRUE(cors.allows("HTTPS://A.ORG"));
    EXPECT_FALSE(cors.allows("https://a.org.evil.net"));
    EXPECT_FALSE(cors.allows("https://a.org:443"));
    EXPECT_FALSE(cors.allows(""));

    const HeaderList other = cors.response_headers("https://b.org");
    ASSERT_EQ(other.size(), 1u);
    EXPECT_EQ(other[0], (std::pair<std::string, std::string>{"Vary", "Origin"}));
    EXPECT_TRUE(cors.preflight_headers("https://b.org", "POST, OPTIONS").empty());

    const HeaderList mine = cors.response_headers("HTTPS://A.ORG");
    ASSERT_EQ(mine.size(), 3u);
    EXPECT_EQ(mine[1].first, "Access-Control-Allow-Origin");
    EXPECT_EQ(mine[1].second, "HTTPS://A.ORG") << "echoed as sent";
    const HeaderList pre = cors.preflight_headers("https://a.org", "POST, OPTIONS");
    ASSERT_EQ(pre.size(), 3u);
    EXPECT_EQ(pre[0].second, "POST, OPTIONS");
    EXPECT_NE(pre[1].second.find("X-Api-Key"), std::string::npos);
    EXPECT_NE(pre[1].second.find("Authorization"), std::string::npos);
    EXPECT_EQ(pre[2].second, std::to_string(kCorsPreflightMaxAgeS));
}

TEST(Etag, Sha256OfTheFile) {
    const std::string path = (std::filesystem::temp_directory_path() / "nurbsrt-etag-test.bin").string();
    {
        std::ofstream out(path, std::ios::binary);
        out << "abc";
    }
    // SHA-256("abc"), FIPS 180-2 appendix B.1.
    EXPECT_EQ(file_etag(path), "\"ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad\"");
    std::filesystem::remove(path);
    EXPECT_THROW((void)file_etag(path), nurbsrt::Error);
}

TEST(Etag, IfNoneMatchUsesTheWeakComparison) {
    const std::string tag = "\"abc\"";
    EXPECT_TRUE(if_none_match_matches("\"abc\"", tag));
    EXPECT_TRUE(if_none_match_matches(" W/\"abc\" ", tag));
    EXPECT_TRUE(if_none_match_matches("\"x\", \"abc\"", tag));
    EXPECT_TRUE(if_none_match_matches("*", tag));
    EXPECT_FALSE(if_none_match_matches("\"abcd\"", tag));
    EXPECT_FALSE(if_none_match_matches("abc", tag)) << "unquoted is no entity tag";
    EXPECT_FALSE(if_none_match_matches("", tag));
    EXPECT_FALSE(if_none_match_matches("\"x\", W/\"y\"", tag));
}

// A problem's `code` is either a library ErrorCode or a ServiceCode: one name
// space, documented as one enum (components.schemas.ErrorCode of the embedded
// OpenAPI document). Every name is distinct and documented, and the document
// names no code the service cannot send.
TEST(ProblemCodes, OneDocumentedNameSpace) {
    std::set<std::string> names;
    size_t count = 0;
    for (int c = 0; c <= static_cast<int>(nurbsrt::ErrorCode::internal); ++c, ++count)
        names.insert(ProblemCode(static_cast<nurbsrt::ErrorCode>(c)).name());
    for (int c = 0; c <= static_cast<int>(ServiceCode::strict_refused); ++c, ++count)  // the last one
        names.insert(ProblemCode(static_cast<ServiceCode>(c)).name());
    EXPECT_EQ(names.size(), count);
    const nlohmann::json spec = nlohmann::json::parse(openapi_document());
    std::set<std::string> documented;
    for (const auto& n : spec.at("components").at("schemas").at("ErrorCode").at("enum"))
        documented.insert(n.get<std::string>());
    EXPECT_EQ(documented, names);
}

TEST(ProblemCodes, StatusesAndBodies) {
    EXPECT_EQ(http_status(ServiceCode::not_found), 404);
    EXPECT_EQ(http_status(ServiceCode::method_not_allowed), 405);
    EXPECT_EQ(http_status(ServiceCode::unauthorized), 401);
    EXPECT_EQ(http_status(ServiceCode::request_timeout), 408);
    EXPECT_EQ(http_status(ServiceCode::overloaded), 503);
    EXPECT_EQ(http_status(ServiceCode::render_timeout), 504);
    EXPECT_EQ(http_status(nurbsrt::ErrorCode::invalid_argument), 400);
    EXPECT_EQ(http_status(nurbsrt::ErrorCode::invalid_json), 400);
    EXPECT_EQ(http_status(ServiceCode::malformed_request), 400);
    EXPECT_EQ(http_status(ServiceCode::not_implemented), 501);
    EXPECT_EQ(http_status(ServiceCode::strict_refused), 422);
    EXPECT_EQ(http_status(nurbsrt::ErrorCode::unreadable_file), 422);
    EXPECT_EQ(http_status(nurbsrt::ErrorCode::internal), 500);
    EXPECT_TRUE(ProblemCode(ServiceCode::not_found) == ServiceCode::not_found);
    EXPECT_FALSE(ProblemCode(ServiceCode::not_found) == nurbsrt::ErrorCode::io);

    const Problem p = make_problem(ServiceCode::method_not_allowed, "use POST", "req-1");
    EXPECT_EQ(p.status, 405);
    const nlohmann::json j = nlohmann::json::parse(p.body);
    EXPECT_EQ(j.at("code"), "method_not_allowed");
    EXPECT_EQ(j.at("type"), "urn:nurbsrt:error:method_not_allowed");
    EXPECT_EQ(j.at("title"), "Method not allowed");
    EXPECT_EQ(j.at("status"), 405);
    // A status given instead of the code's own: the body says that status and its reason phrase.
    const Problem big = make_problem(nurbsrt::ErrorCode::limit_exceeded, "too big", "req-2", 413);
    const nlohmann::json b = nlohmann::json::parse(big.body);
    EXPECT_EQ(big.status, 413);
    EXPECT_EQ(b.at("status"), 413);
    EXPECT_EQ(b.at("title"), "Content too large");
    EXPECT_EQ(b.at("code"), "limit_exceeded");
}
