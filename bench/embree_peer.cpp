// Embree ray casting of a triangle mesh (see embree_peer.h).
#include "bench/embree_peer.h"

#include "bench/bench_context.h"
#include "core/error.h"

#ifdef NURBSRT_WITH_EMBREE
#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <limits>
#include <string>
#endif

namespace nurbsrt::bench {

#ifdef NURBSRT_WITH_EMBREE

bool embree_available() { return true; }

EmbreeFrame embree_render(const TriangleMesh& mesh, const Camera& camera, int threads) {
    EmbreeFrame out;
    const auto t0 = Clock::now();
    const std::string config = "threads=" + std::to_string(std::max(1, threads));
    RTCDevice dev = rtcNewDevice(config.c_str());
    if (!dev) throw Error(ErrorCode::internal, "embree: rtcNewDevice failed");
    RTCScene scene = rtcNewScene(dev);
    RTCGeometry geom = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    // Vertices relative to the eye, subtracted in double: float keeps its
    // precision near the camera whatever the model's coordinates.
    const Vec3 eye = camera.spec().eye;
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                          3 * sizeof(float), mesh.xyz.size()));
    for (size_t k = 0; k < mesh.xyz.size(); ++k) {
        const Vec3 d = mesh.xyz[k] - eye;
        v[3 * k] = static_cast<float>(d.x);
        v[3 * k + 1] = static_cast<float>(d.y);
        v[3 * k + 2] = static_cast<float>(d.z);
    }
    auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                               3 * sizeof(unsigned), mesh.triangle_count()));
    std::copy(mesh.triangles.begin(), mesh.triangles.end(), idx);
    rtcCommitGeometry(geom);
    rtcAttachGeometry(scene, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(scene);
    out.build_ms = ms_since(t0);

    const int W = camera.width(), H = camera.height();
    out.t.assign(static_cast<size_t>(W) * H, std::numeric_limits<float>::infinity());
    const auto t1 = Clock::now();
    tbb::task_arena arena(std::max(1, threads));
    arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<int>(0, H, 8), [&](const tbb::blocked_range<int>& rows) {
            RTCIntersectContext ictx;
            rtcInitIntersectContext(&ictx);
            for (int j = rows.begin(); j < rows.end(); ++j)
                for (int i = 0; i < W; ++i) {
                    const Ray r = camera.pixel_ray(i, j);
                    const Vec3 o = r.origin - eye;
                    RTCRayHit rh{};
                    rh.ray.org_x = static_cast<float>(o.x);
                    rh.ray.org_y = static_cast<float>(o.y);
                    rh.ray.org_z = static_cast<float>(o.z);
                    rh.ray.dir_x = static_cast<float>(r.dir.x);
                    rh.ray.dir_y = static_cast<float>(r.dir.y);
                    rh.ray.dir_z = static_cast<float>(r.dir.z);
                    rh.ray.tnear = 0;
                    rh.ray.tfar = std::numeric_limits<float>::infinity();
                    rh.ray.mask = 0xFFFFFFFFu;
                    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
                    rtcIntersect1(scene, &ictx, &rh);
                    if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) out.t[static_cast<size_t>(j) * W + i] = rh.ray.tfar;
                }
        });
    });
    out.render_ms = ms_since(t1);
    rtcReleaseScene(scene);
    rtcReleaseDevice(dev);
    return out;
}

#else

bool embree_available() { return false; }

EmbreeFrame embree_render(const TriangleMesh&, const Camera&, int) {
    throw Error(ErrorCode::internal, "embree: nurbsrt was built without Embree (NURBSRT_WITH_EMBREE)");
}

#endif

}  // namespace nurbsrt::bench
