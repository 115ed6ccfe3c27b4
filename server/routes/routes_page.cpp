// The web page: GET / (web/index.html) and GET /web/{name} (its modules and
// style sheet), served from the bytes compiled into the binary
// (server/routes/web_assets.h). The page talks to the service only through the
// public REST API, like any other client.
#include <httplib.h>

#include <string>
#include <string_view>

#include "server/render/context.h"
#include "server/routes/handler_util.h"
#include "server/routes/routes.h"
#include "server/routes/web_assets.h"
#include "server/common/service_error.h"

namespace nurbsrt::server {
namespace {

// Scripts and styles only from this origin and never inline (no
// 'unsafe-inline', no eval), images also from blob: URLs (the rendered frames
// and the AOV views the page draws), requests only to this origin, and the page
// may not be framed (clickjacking) or post forms anywhere (W3C CSP Level 3).
constexpr const char* kContentSecurityPolicy =
    "default-src 'self'; script-src 'self'; style-src 'self'; img-src 'self' blob: data:; "
    "connect-src 'self'; font-src 'self'; object-src 'none'; base-uri 'none'; form-action 'none'; "
    "frame-ancestors 'none'";

const WebAsset* find_asset(std::string_view name) {
    for (const WebAsset& a : web_assets())
        if (a.name == name) return &a;
    return nullptr;
}

void send_asset(const WebAsset& a, httplib::Response& res) {
    res.set_header("Content-Security-Policy", kContentSecurityPolicy);
    res.set_header("X-Content-Type-Options", "nosniff");
    res.set_header("Referrer-Policy", "no-referrer");
    res.set_header("X-Frame-Options", "DENY");
    res.set_header("Cross-Origin-Opener-Policy", "same-origin");
    res.set_header("Permissions-Policy", "camera=(), microphone=(), geolocation=()");
    // The page changes with the binary: revalidate rather than keep a stale copy.
    res.set_header("Cache-Control", "no-cache");
    res.set_content(a.body.data(), a.body.size(), std::string(a.content_type).c_str());
}

}  // namespace

void handle_page(ServerContext&, const httplib::Request&, httplib::Response& res) {
    const WebAsset* page = find_asset("index.html");
    if (!page) {
        send_problem(res, ServiceCode::not_found, "this build has no web page");
        return;
    }
    send_asset(*page, res);
}

void handle_web_file(ServerContext&, const httplib::Request& req, httplib::Response& res) {
    const WebAsset* a = find_asset(req.matches[1].str());
    if (!a) {
        send_problem(res, ServiceCode::not_found, "no such file of the web page");
        return;
    }
    send_asset(*a, res);
}

}  // namespace nurbsrt::server
