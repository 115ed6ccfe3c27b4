#include "server/common/sha256.h"

#include <openssl/evp.h>

#include "core/error.h"

namespace nurbsrt::server {

struct Sha256::Impl {
    EVP_MD_CTX* ctx = nullptr;
};

Sha256::Sha256() : impl_(new Impl) {
    impl_->ctx = EVP_MD_CTX_new();
    if (!impl_->ctx || EVP_DigestInit_ex(impl_->ctx, EVP_sha256(), nullptr) != 1)
        throw Error(ErrorCode::internal, "SHA-256 is not available");
}

Sha256::~Sha256() { EVP_MD_CTX_free(impl_->ctx); }

void Sha256::update(const void* data, size_t n) {
    if (n && EVP_DigestUpdate(impl_->ctx, data, n) != 1) throw Error(ErrorCode::internal, "SHA-256 failed");
}

namespace {

std::string to_hex(const unsigned char* digest, size_t len) {
    static const char* digits = "0123456789abcdef";
    std::string out;
    out.reserve(2 * len);
    for (size_t i = 0; i < len; ++i) {
        out += digits[digest[i] >> 4];
        out += digits[digest[i] & 15];
    }
    return out;
}

}  // namespace

std::string Sha256::hex() {
    unsigned char digest[EVP_MAX_MD_SIZE];
    unsigned len = 0;
    if (EVP_DigestFinal_ex(impl_->ctx, digest, &len) != 1) throw Error(ErrorCode::internal, "SHA-256 failed");
    return to_hex(digest, len);
}

std::string hmac_sha256_hex(std::string_view key, std::string_view data) {
    unsigned char mac[EVP_MAX_MD_SIZE];
    size_t len = 0;
    // EVP_Q_mac: OpenSSL 3's one-shot MAC (HMAC() is deprecated there).
    if (!EVP_Q_mac(nullptr, "HMAC", nullptr, "SHA256", nullptr, key.data(), key.size(),
                   reinterpret_cast<const unsigned char*>(data.data()), data.size(), mac, sizeof mac, &len))
        throw Error(ErrorCode::internal, "HMAC-SHA256 failed");
    return to_hex(mac, len);
}

std::string sha256_hex(const std::string& bytes) {
    Sha256 h;
    h.update(bytes);
    return h.hex();
}

}  // namespace nurbsrt::server
