// The content-addressed scene cache of the service: LRU bound, and single-flight
// loading (simultaneous first renders of one file import it once).
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

#include "core/error.h"
#include "server/common/sha256.h"
#include "renderer/solve/prepared_data.h"
#include "server/render/scene_cache.h"

using namespace nurbsrt;
using namespace nurbsrt::server;

namespace {

// A prepared scene of n faces without surfaces (an empty parameter box: nothing
// is evaluated), each trimmed by a square loop, so the prepared data includes trim grids.
std::shared_ptr<const PreparedScene> scene_with_faces(size_t n) {
    auto s = std::make_shared<Scene>();
    s->faces.resize(n);
    for (size_t k = 0; k < n; ++k) {
        Face& f = s->faces[k];
        f.index = static_cast<uint32_t>(k + 1);
        f.loops.push_back(TrimLoop{{{0.1, 0.1}, {0.9, 0.1}, {0.9, 0.9}, {0.1, 0.9}}, true});
    }
    return std::make_shared<const PreparedScene>(prepare(std::shared_ptr<const Scene>(std::move(s)), 1));
}

}  // namespace

TEST(SceneCache, KeyDependsOnBytesAndOptions) {
    ImportOptions a, b;
    b.mesh_relative_deflection *= 2;
    const std::string abc = sha256_hex("abc"), abd = sha256_hex("abd");
    EXPECT_EQ(scene_cache_key(abc, a), scene_cache_key(abc, a));
    EXPECT_NE(scene_cache_key(abc, a), scene_cache_key(abd, a));
    EXPECT_NE(scene_cache_key(abc, a), scene_cache_key(abc, b));
    EXPECT_EQ(scene_cache_key(abc, a).size(), 64u);  // SHA-256 hex
}

TEST(SceneCache, EvictsLeastRecentlyUsedBeyondCapacity) {
    const size_t one = prepared_scene_memory_bytes(*scene_with_faces(10));
    SceneCache cache(2 * one + one / 2);  // room for two
    cache.put("a", scene_with_faces(10));
    cache.put("b", scene_with_faces(10));
    ASSERT_NE(cache.get("a"), nullptr);  // a is now more recent than b
    cache.put("c", scene_with_faces(10));
    EXPECT_EQ(cache.entries(), 2u);
    EXPECT_NE(cache.get("a"), nullptr);
    EXPECT_EQ(cache.get("b"), nullptr);
    EXPECT_NE(cache.get("c"), nullptr);
    EXPECT_LE(cache.bytes(), cache.capacity());
    cache.put("huge", scene_with_faces(1000));  // larger than the whole cache: not kept
    EXPECT_EQ(cache.get("huge"), nullptr);
}

TEST(SceneCache, SimultaneousMissesLoadOnce) {
    SceneCache cache(size_t(64) << 20);
    std::atomic<int> loads{0};
    const int n = 8;
    std::vector<std::shared_ptr<const PreparedScene>> got(n);
    std::vector<SceneCache::Source> sources(n);
    std::vector<std::thread> threads;
    for (int k = 0; k < n; ++k)
        threads.emplace_back([&, k] {
            got[k] = cache.get_or_load(
                "key",
                [&] {
                    ++loads;
                    std::this_thread::sleep_for(std::chrono::milliseconds(300));
                    return scene_with_faces(3);
                },
                sources[k]);
        });
    for (auto& t : threads) t.join();
    EXPECT_EQ(loads.load(), 1);
    int loaded = 0;
    for (int k = 0; k < n; ++k) {
        ASSERT_NE(got[k], nullptr);
        EXPECT_EQ(got[k], got[0]);  // one scene, shared
        loaded += sources[k] == SceneCache::Source::loaded;
    }
    EXPECT_EQ(loaded, 1);
    SceneCache::Source s;
    cache.get_or_load(
        "key",
        [&] {
            ++loads;
            return scene_with_faces(1);
        },
        s);
    EXPECT_EQ(s, SceneCache::Source::hit);
    EXPECT_EQ(loads.load(), 1);
}

TEST(SceneCache, FailedLoadReachesEveryWaiterAndIsNotCached) {
    SceneCache cache(size_t(64) << 20);
    std::atomic<int> loads{0}, errors{0};
    std::vector<std::thread> threads;
    for (int k = 0; k < 4; ++k)
        threads.emplace_back([&] {
            SceneCache::Source s;
            try {
                cache.get_or_load(
                    "bad",
                    [&]() -> std::shared_ptr<const PreparedScene> {
                        ++loads;
                        std::this_thread::sleep_for(std::chrono::milliseconds(200));
                        throw Error(ErrorCode::unreadable_file, "truncated");
                    },
                    s);
            } catch (const Error& e) {
                if (e.code() == ErrorCode::unreadable_file) ++errors;
            }
        });
    for (auto& t : threads) t.join();
    EXPECT_EQ(errors.load(), 4);
    EXPECT_GE(loads.load(), 1);
    EXPECT_EQ(cache.get("bad"), nullptr);
    SceneCache::Source s;
    const int before = loads.load();
    EXPECT_NE(cache.get_or_load(
                  "bad",
                  [&] {
                      ++loads;
                      return scene_with_faces(1);
                  },
                  s),
              nullptr);
    EXPECT_EQ(s, SceneCache::Source::loaded);  // tried again, not a cached failure
    EXPECT_EQ(loads.load(), before + 1);
}

TEST(SceneCache, AWaiterLoadsItselfWhenTheLoaderGaveUp) {
    // The first caller's load ends canceled (its client left); the caller that
    // waited for it must not inherit that: it loads the scene itself.
    SceneCache cache(size_t(64) << 20);
    std::atomic<bool> first_started{false};
    std::atomic<int> loads{0};
    SceneCache::Source first_source{}, second_source{};
    bool first_canceled = false;
    std::thread first([&] {
        try {
            cache.get_or_load(
                "k",
                [&]() -> std::shared_ptr<const PreparedScene> {
                    ++loads;
                    first_started = true;
                    std::this_thread::sleep_for(std::chrono::milliseconds(300));
                    throw Error(ErrorCode::canceled, "the client left");
                },
                first_source);
        } catch (const Error& e) {
            first_canceled = e.code() == ErrorCode::canceled;
        }
    });
    while (!first_started) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    const auto got = cache.get_or_load(
        "k",
        [&] {
            ++loads;
            return scene_with_faces(2);
        },
        second_source);
    first.join();
    EXPECT_TRUE(first_canceled);
    ASSERT_NE(got, nullptr);
    EXPECT_EQ(got->scene().faces.size(), 2u);
    EXPECT_EQ(second_source, SceneCache::Source::loaded);
    EXPECT_EQ(loads.load(), 2);
    EXPECT_EQ(cache.get("k"), got);
}

TEST(SceneCache, CountsThePreparedDataInItsBytes) {
    const std::shared_ptr<const PreparedScene> p = scene_with_faces(4);
    EXPECT_GT(p->memory_bytes(), 4 * sizeof(PreparedFace));  // the trim grids are counted
    EXPECT_EQ(prepared_scene_memory_bytes(*p), scene_memory_bytes(p->scene()) + p->memory_bytes());
    SceneCache cache(size_t(64) << 20);
    cache.put("a", p);
    EXPECT_EQ(cache.bytes(), prepared_scene_memory_bytes(*p));
    EXPECT_EQ(cache.get("a"), p);
}
