// The files of the web page (web/*.html, *.js, *.css), compiled into the
// binary by cmake/embed_web.cmake.
#pragma once

#include <span>
#include <string_view>

namespace nurbsrt::server {

struct WebAsset {
    std::string_view name;          // file name under web/, e.g. "app.js"
    std::string_view content_type;  // text/html, text/javascript or text/css, UTF-8
    std::string_view body;
};

std::span<const WebAsset> web_assets();

}  // namespace nurbsrt::server
