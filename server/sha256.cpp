#include "server/sha256.h"

#include <openssl/evp.h>

#include "renderer/error.h"

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

std::string Sha256::hex() {
    unsigned char digest[EVP_MAX_MD_SIZE];
    unsigned len = 0;
    if (EVP_DigestFinal_ex(impl_->ctx, digest, &len) != 1) throw Error(ErrorCode::internal, "SHA-256 failed");
    static const char* digits = "0123456789abcdef";
    std::string out;
    out.reserve(2 * len);
    for (unsigned i = 0; i < len; ++i) {
        out += digits[digest[i] >> 4];
        out += digits[digest[i] & 15];
    }
    return out;
}

std::string sha256_hex(const std::string& bytes) {
    Sha256 h;
    h.update(bytes);
    return h.hex();
}

}  // namespace nurbsrt::server
