// Content-addressed cache of imported scenes: key = SHA-256 of the uploaded
// bytes and the import options, value = the immutable Scene together with its
// PreparedScene (renderer/prepared_scene.h, which owns the Scene), shared by
// every render that uses it, so a cached render pays only the frame. Bounded by
// an estimate of the memory of both; least recently used entries go first.
// Thread-safe.
#pragma once

#include <cstddef>
#include <functional>
#include <future>
#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>

#include "importer/importer.h"
#include "renderer/prepared_scene.h"

namespace nurbsrt::server {

// The cache's key of a file's scene: the SHA-256 (hex) of the file's SHA-256
// (hex, content_sha256) followed by the import options' canonical text. From the
// file's digest, not its bytes, so that a stored file (whose id is that digest)
// is looked up without hashing its bytes again.
std::string scene_cache_key(const std::string& content_sha256, const ImportOptions& options);

// Approximate memory held by a scene (its vectors' payloads), for the bound.
size_t scene_memory_bytes(const Scene& scene);
// The same for a cache entry: its scene plus the prepared data.
size_t prepared_scene_memory_bytes(const PreparedScene& prepared);

class SceneCache {
public:
    explicit SceneCache(size_t capacity_bytes) : capacity_(capacity_bytes) {}

    std::shared_ptr<const PreparedScene> get(const std::string& key);  // nullptr on a miss
    // Inserts (or refreshes) the entry and evicts LRU entries beyond the bound;
    // a scene larger than the whole capacity is not kept. `scene` must own its
    // Scene (prepare(std::shared_ptr<const Scene>)).
    void put(const std::string& key, std::shared_ptr<const PreparedScene> scene);

    // How the scene of get_or_load came: from the cache, by waiting for another
    // request's import of the same key, or by running `load` itself.
    enum class Source { hit, shared, loaded };
    // The cached scene, or else `load()` run once for all concurrent callers of
    // the same key ("single flight": N simultaneous first renders of one file
    // import it once); the result is put in the cache. When `load` throws, every
    // caller waiting for it gets the same exception and nothing is cached, except
    // Error(canceled) (the loading caller gave up): a waiter then looks again.
    std::shared_ptr<const PreparedScene> get_or_load(const std::string& key,
                                                     const std::function<std::shared_ptr<const PreparedScene>()>& load,
                                                     Source& source);

    size_t bytes() const;
    size_t entries() const;
    size_t capacity() const { return capacity_; }

private:
    struct Entry {
        std::string key;
        std::shared_ptr<const PreparedScene> scene;
        size_t bytes = 0;
    };
    const size_t capacity_;
    mutable std::mutex m_;
    std::list<Entry> lru_;  // front = most recently used
    std::unordered_map<std::string, std::list<Entry>::iterator> index_;
    size_t bytes_ = 0;
    std::unordered_map<std::string, std::shared_future<std::shared_ptr<const PreparedScene>>> loading_;
};

}  // namespace nurbsrt::server
