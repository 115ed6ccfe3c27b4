// The render options of POST /v1/renders and of job outputs (a JSON object, or
// query parameters as strings), then the camera the service would build from
// them for a scene, and the conversion options of POST /v1/conversions.
#include <cstddef>
#include <cstdint>

#include "fuzz/fuzz_common.h"
#include "renderer/camera.h"
#include "server/common/config.h"
#include "options/render_request.h"
#include "server/render/render_limits.h"

using namespace nurbsrt;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string text = fuzz::as_string(data, size);
    fuzz::expect_only_errors([&] {
        const nurbsrt::RenderRequest r = nurbsrt::parse_render_options(text);
        server::check_render_limits(server::ServerConfig{}, r);
        // A small part away from the origin: the camera is fitted to its box.
        Scene scene;
        scene.bbox.extend(Vec3{10, 20, 30});
        scene.bbox.extend(Vec3{15, 22, 40});
        const Camera camera(nurbsrt::camera_spec_for(r, scene));
        (void)camera.pixel_ray(0, 0);
        (void)camera.pixel_ray(r.width - 1, r.height - 1);
    });
    fuzz::expect_only_errors([&] { (void)nurbsrt::parse_conversion_format(text); });
    return 0;
}
