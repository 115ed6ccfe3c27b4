#include "server/render/render_limits.h"

#include <string>
#include <utility>

#include "core/error.h"

namespace nurbsrt::server {

void check_render_limits(const ServerConfig& c, const RenderRequest& r) {
    for (const auto& [name, value] : {std::pair{"width", r.width}, std::pair{"height", r.height}})
        if (value > c.max_dimension)
            throw Error(ErrorCode::limit_exceeded, std::string("option '") + name + "' is " + std::to_string(value) +
                                                       ", over the limit of " + std::to_string(c.max_dimension) +
                                                       " pixels per side");
    const long long pixels = static_cast<long long>(r.width) * r.height;
    if (pixels > c.max_pixels)
        throw Error(ErrorCode::limit_exceeded, "options 'width' x 'height' give " + std::to_string(r.width) + "x" +
                                                   std::to_string(r.height) + " = " + std::to_string(pixels) +
                                                   " pixels, over the limit of " + std::to_string(c.max_pixels));
}

}  // namespace nurbsrt::server
