// SHA-256 (FIPS 180-4) through OpenSSL's EVP interface, as lowercase hex: the
// content address of stored files, the scene cache's key, and strong ETags;
// and HMAC-SHA256 (RFC 2104), the signature of webhook bodies.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <string_view>

namespace nurbsrt::server {

// Incremental: update() any number of times, then hex() once. Throws
// Error(internal) if OpenSSL fails (it does not for SHA-256 in practice).
class Sha256 {
public:
    Sha256();
    ~Sha256();
    Sha256(const Sha256&) = delete;
    Sha256& operator=(const Sha256&) = delete;
    void update(const void* data, size_t n);
    void update(const std::string& s) { update(s.data(), s.size()); }
    std::string hex();

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// SHA-256 of `bytes` in lowercase hex.
std::string sha256_hex(const std::string& bytes);
// HMAC-SHA256 of `data` under `key`, lowercase hex.
std::string hmac_sha256_hex(std::string_view key, std::string_view data);

}  // namespace nurbsrt::server
