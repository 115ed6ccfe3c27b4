// Webhooks (server/jobs/webhooks.h, server/jobs/callback_url.h): which callback URLs a job may name, which
// addresses a callback may reach, the signature (RFC 4231 vectors) and the
// back-off. Delivery itself is tested end to end in tests/api/test_webhooks.py.
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>

#include "core/error.h"
#include "server/common/sha256.h"
#include "server/jobs/callback_url.h"
#include "server/jobs/webhooks.h"
#include "tests/support/error_code_of.h"

using namespace nurbsrt;
using namespace nurbsrt::server;
using nurbsrt::test::code_of;

namespace {

bool public_address(const std::string& text) {
    sockaddr_in v4{};
    if (inet_pton(AF_INET, text.c_str(), &v4.sin_addr) == 1) {
        v4.sin_family = AF_INET;
        return is_public_address(reinterpret_cast<sockaddr*>(&v4));
    }
    sockaddr_in6 v6{};
    EXPECT_EQ(inet_pton(AF_INET6, text.c_str(), &v6.sin6_addr), 1) << text;
    v6.sin6_family = AF_INET6;
    return is_public_address(reinterpret_cast<sockaddr*>(&v6));
}

std::string refusal(const std::string& url, bool allow_private = false) {
    try {
        check_callback_url(url, allow_private);
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::invalid_argument);
        return e.what();
    }
    return "";
}

}  // namespace

TEST(Webhooks, CallbackUrlsAreParsed) {
    CallbackUrl u = check_callback_url("https://hooks.example.com/nurbsrt/done?team=7", false);
    EXPECT_EQ(u.scheme, "https");
    EXPECT_EQ(u.host, "hooks.example.com");
    EXPECT_EQ(u.port, 443);
    EXPECT_EQ(u.target, "/nurbsrt/done?team=7");
    u = check_callback_url("HTTP://example.com:8080", false);
    EXPECT_EQ(u.scheme, "http");
    EXPECT_EQ(u.port, 8080);
    EXPECT_EQ(u.target, "/");
    u = check_callback_url("http://example.com?x=1", false);
    EXPECT_EQ(u.target, "/?x=1");
    u = check_callback_url("http://[2001:4860:4860::8888]:8443/h", false);
    EXPECT_EQ(u.host, "2001:4860:4860::8888");
    EXPECT_EQ(u.port, 8443);
    u = check_callback_url("http://127.0.0.1:9/h", true);  // allowed by the operator
    EXPECT_EQ(u.host, "127.0.0.1");
}

TEST(Webhooks, BadCallbackUrlsAreRefusedWithTheReason) {
    EXPECT_NE(refusal("").find("must not be empty"), std::string::npos);
    EXPECT_NE(refusal("ftp://example.com/x").find("http:// or https://"), std::string::npos);
    EXPECT_NE(refusal("example.com/hook").find("http:// or https://"), std::string::npos);
    EXPECT_NE(refusal("https://user:pw@example.com/").find("user information"), std::string::npos);
    EXPECT_NE(refusal("https://example.com/#frag").find("fragment"), std::string::npos);
    EXPECT_NE(refusal("https://exa mple.com/").find("spaces"), std::string::npos);
    EXPECT_NE(refusal("https:///path").find("host"), std::string::npos);
    EXPECT_NE(refusal("https://example.com:0/").find("port"), std::string::npos);
    EXPECT_NE(refusal("https://example.com:99999/").find("port"), std::string::npos);
    EXPECT_NE(refusal("https://[zz::1]/").find("host"), std::string::npos);
    EXPECT_NE(refusal("https://example.com/" + std::string(3000, 'a')).find("at most 2048"), std::string::npos);
    for (const char* url :
         {"http://127.0.0.1/", "http://10.1.2.3/", "http://169.254.169.254/latest/meta-data",
          "http://192.168.0.10:8080/", "http://[::1]/", "http://[fd00::1]/", "http://[::ffff:127.0.0.1]/",
          "http://localhost:8080/", "http://api.localhost/", "http://0.0.0.0/",
          // Every spelling of an IPv4 address the resolver takes (inet_aton's):
          "http://0x7f000001/", "http://2130706433/", "http://0177.0.0.1/", "http://127.1/", "http://0/",
          "http://127.000.000.001/", "http://0xa.1.2.3/", "http://3232235530/"}) {
        EXPECT_NE(refusal(url).find("loopback, private or link-local"), std::string::npos) << url;
        EXPECT_EQ(refusal(url, true), "") << url;
    }
    EXPECT_NE(refusal("https://example.com:/x").find("empty port"), std::string::npos);
    EXPECT_NE(refusal("https://[2001:db8::1/x").find("host"), std::string::npos);
    EXPECT_NE(refusal("https://exa_mple.com/").find("host"), std::string::npos);
    EXPECT_EQ(refusal("https://" + std::string(2000, 'a') + ".com/"), "");  // long, but a name
    EXPECT_EQ(refusal("https://8.8.8.8/"), "");
}

TEST(Webhooks, PublicAddressRanges) {
    for (const char* a : {"8.8.8.8", "1.1.1.1", "172.32.0.1", "100.128.0.1", "2001:4860:4860::8888", "64:ff9b::808:808",
                          "::ffff:8.8.4.4"})
        EXPECT_TRUE(public_address(a)) << a;
    for (const char* a : {"0.0.0.0",
                          "10.0.0.1",
                          "100.64.0.1",
                          "127.0.0.1",
                          "127.255.255.254",
                          "169.254.169.254",
                          "172.16.0.1",
                          "172.31.255.255",
                          "192.0.0.8",
                          "192.0.2.1",
                          "192.168.1.1",
                          "198.18.0.1",
                          "198.51.100.7",
                          "203.0.113.9",
                          "224.0.0.1",
                          "240.0.0.1",
                          "255.255.255.255",
                          "::",
                          "::1",
                          "fc00::1",
                          "fdff::1",
                          "fe80::1",
                          "ff02::1",
                          "2001:db8::1",
                          "::ffff:10.0.0.1",
                          "64:ff9b::a00:1"})
        EXPECT_FALSE(public_address(a)) << a;
}

TEST(Webhooks, HmacSha256MatchesRfc4231) {
    // RFC 4231, test cases 1 and 2.
    EXPECT_EQ(hmac_sha256_hex(std::string(20, '\x0b'), "Hi There"),
              "b0344c61d8db38535ca8afceaf0bf12b881dc200c9833da726e9376c2e32cff7");
    EXPECT_EQ(hmac_sha256_hex("Jefe", "what do ya want for nothing?"),
              "5bdcc146bf60754e6a042426089575c75a003f089d2739839dec58b964ec3843");
}

TEST(Webhooks, BackoffDoublesUpToAnHourWithUpwardJitter) {
    EXPECT_EQ(webhook_backoff_ms(1, 2.0, 0.0), 2000);
    EXPECT_EQ(webhook_backoff_ms(2, 2.0, 0.0), 4000);
    EXPECT_EQ(webhook_backoff_ms(3, 2.0, 1.0), 10000);  // 8 s + 25 %
    EXPECT_EQ(webhook_backoff_ms(12, 2.0, 0.0), 3600000);
    EXPECT_EQ(webhook_backoff_ms(40, 2.0, 0.5), 4050000);  // an hour + 12.5 %
}

TEST(Webhooks, SecretsMustBeLongEnough) {
    EXPECT_EQ(code_of([] { check_webhook_secret("short"); }), ErrorCode::invalid_argument);
    EXPECT_EQ(code_of([] { check_webhook_secret(std::string("0123456789abcdef\n", 17)); }),
              ErrorCode::invalid_argument);
    EXPECT_NO_THROW(check_webhook_secret("0123456789abcdef"));
}
