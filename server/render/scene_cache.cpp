#include "server/render/scene_cache.h"

#include "importer/isolated.h"
#include "core/error.h"
#include "server/common/sha256.h"

namespace nurbsrt::server {

std::string scene_cache_key(const std::string& content_sha256, const ImportOptions& options) {
    std::string opts;
    for (const std::string& a : import_options_to_args(options)) opts += a + '\n';
    Sha256 h;
    h.update(content_sha256);
    h.update("\0options\n", 9);
    h.update(opts);
    return h.hex();
}

size_t scene_memory_bytes(const Scene& s) {
    size_t n = sizeof(Scene) + s.source_name.size() + s.format.size() + s.units.size();
    for (const Face& f : s.faces) {
        n += sizeof(Face) + f.name.size();
        n += f.surface.knots_u.size() * sizeof(double) + f.surface.knots_v.size() * sizeof(double);
        n += f.surface.cp.size() * sizeof(Vec4);
        for (const TrimLoop& l : f.loops) n += sizeof(TrimLoop) + l.points.size() * sizeof(Vec2);
        n += f.mesh.uv.size() * sizeof(Vec2) + f.mesh.xyz.size() * sizeof(Vec3) +
             f.mesh.triangles.size() * sizeof(uint32_t);
    }
    for (const Body& b : s.bodies) n += sizeof(Body) + b.name.size();
    for (const Part& p : s.parts) n += sizeof(Part) + p.id.size() + p.name.size();
    for (const std::string& w : s.warnings) n += sizeof(std::string) + w.size();
    return n;
}

size_t prepared_scene_memory_bytes(const PreparedScene& prepared) {
    return scene_memory_bytes(prepared.scene()) + prepared.memory_bytes();
}

std::shared_ptr<const PreparedScene> SceneCache::get(const std::string& key) {
    std::lock_guard<std::mutex> lock(m_);
    const auto it = index_.find(key);
    if (it == index_.end()) return nullptr;
    lru_.splice(lru_.begin(), lru_, it->second);
    return it->second->scene;
}

void SceneCache::put(const std::string& key, std::shared_ptr<const PreparedScene> scene) {
    const size_t size = prepared_scene_memory_bytes(*scene);
    std::lock_guard<std::mutex> lock(m_);
    if (const auto it = index_.find(key); it != index_.end()) {
        bytes_ -= it->second->bytes;
        lru_.erase(it->second);
        index_.erase(it);
    }
    if (size > capacity_) return;
    lru_.push_front(Entry{key, std::move(scene), size});
    index_[key] = lru_.begin();
    bytes_ += size;
    while (bytes_ > capacity_ && !lru_.empty()) {
        bytes_ -= lru_.back().bytes;
        index_.erase(lru_.back().key);
        lru_.pop_back();
    }
}

std::shared_ptr<const PreparedScene> SceneCache::get_or_load(
    const std::string& key, const std::function<std::shared_ptr<const PreparedScene>()>& load, Source& source) {
    std::promise<std::shared_ptr<const PreparedScene>> promise;
    for (bool loading = false; !loading;) {
        std::unique_lock<std::mutex> lock(m_);
        if (const auto it = index_.find(key); it != index_.end()) {
            lru_.splice(lru_.begin(), lru_, it->second);
            source = Source::hit;
            return it->second->scene;
        }
        if (const auto it = loading_.find(key); it != loading_.end()) {
            std::shared_future<std::shared_ptr<const PreparedScene>> pending = it->second;
            lock.unlock();
            source = Source::shared;
            try {
                return pending.get();  // rethrows the loader's error
            } catch (const Error& e) {
                // The loader's own caller gave up (a client gone, a job deleted),
                // which says nothing of the file: look again, and load it if need be.
                if (e.code() != ErrorCode::canceled) throw;
                continue;
            }
        }
        loading_.emplace(key, promise.get_future().share());
        loading = true;
    }
    source = Source::loaded;
    std::shared_ptr<const PreparedScene> scene;
    try {
        scene = load();
    } catch (...) {
        {
            // Gone before the waiters wake: one that looks again (canceled) loads it anew.
            std::lock_guard<std::mutex> lock(m_);
            loading_.erase(key);
        }
        promise.set_exception(std::current_exception());
        throw;
    }
    put(key, scene);  // before the waiters wake, so a later caller finds it cached
    promise.set_value(scene);
    std::lock_guard<std::mutex> lock(m_);
    loading_.erase(key);
    return scene;
}

size_t SceneCache::bytes() const {
    std::lock_guard<std::mutex> lock(m_);
    return bytes_;
}

size_t SceneCache::entries() const {
    std::lock_guard<std::mutex> lock(m_);
    return lru_.size();
}

}  // namespace nurbsrt::server
