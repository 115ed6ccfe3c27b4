#include "server/jobs/callback_url.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <algorithm>
#include <cctype>

#include "core/error.h"
#include "core/ascii.h"

namespace nurbsrt::server {
namespace {

// A URL longer than this is no receiver's address but an attempt to store data.
constexpr size_t kMaxCallbackUrlLength = 2048;
[[noreturn]] void bad_callback_url(const std::string& what) {
    throw Error(ErrorCode::invalid_argument, "callback_url " + what);
}

bool public_v4(uint32_t a) {  // host byte order
    auto in = [a](uint32_t net, int bits) { return (a >> (32 - bits)) == (net >> (32 - bits)); };
    return !(in(0x00000000, 8) || in(0x0A000000, 8) || in(0x64400000, 10) || in(0x7F000000, 8) || in(0xA9FE0000, 16) ||
             in(0xAC100000, 12) || in(0xC0000000, 24) || in(0xC0000200, 24) || in(0xC0A80000, 16) ||
             in(0xC6120000, 15) || in(0xC6336400, 24) || in(0xCB007100, 24) || in(0xE0000000, 4) || in(0xF0000000, 4));
}

bool public_v6(const unsigned char* b) {
    static const unsigned char mapped[12] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0xff, 0xff};
    static const unsigned char nat64[12] = {0, 0x64, 0xff, 0x9b, 0, 0, 0, 0, 0, 0, 0, 0};
    if (std::equal(mapped, mapped + 12, b) || std::equal(nat64, nat64 + 12, b))
        return public_v4(uint32_t(b[12]) << 24 | uint32_t(b[13]) << 16 | uint32_t(b[14]) << 8 | b[15]);
    if (std::all_of(b, b + 15, [](unsigned char c) { return c == 0; })) return false;  // :: and ::1
    if ((b[0] & 0xfe) == 0xfc) return false;                                           // fc00::/7 unique local
    if (b[0] == 0xfe && (b[1] & 0xc0) == 0x80) return false;                           // fe80::/10 link-local
    if (b[0] == 0xff) return false;                                                    // multicast
    if (b[0] == 0x20 && b[1] == 0x01 && b[2] == 0x0d && b[3] == 0xb8) return false;    // 2001:db8::/32 documentation
    return true;
}

// The literal address of `host`, when it is one. IPv4 in every spelling the
// resolver (getaddrinfo, so the HTTP client at delivery) takes as an address,
// which is inet_aton's: 0x7f000001, 2130706433, 0177.0.0.1, 127.1 and 0 are
// all addresses, not names, and must be judged as such at submission.
bool literal_address(const std::string& host, sockaddr_storage& out) {
    out = {};
    auto* v4 = reinterpret_cast<sockaddr_in*>(&out);
    if (inet_aton(host.c_str(), &v4->sin_addr) != 0) {
        v4->sin_family = AF_INET;
        return true;
    }
    auto* v6 = reinterpret_cast<sockaddr_in6*>(&out);
    if (inet_pton(AF_INET6, host.c_str(), &v6->sin6_addr) == 1) {
        v6->sin6_family = AF_INET6;
        return true;
    }
    return false;
}

bool is_localhost_name(std::string host) {
    host = ascii_lower(host);
    if (!host.empty() && host.back() == '.') host.pop_back();
    return host == "localhost" || (host.size() > 10 && host.compare(host.size() - 10, 10, ".localhost") == 0);
}

}  // namespace

CallbackUrl check_callback_url(const std::string& url, bool allow_private) {
    if (url.empty()) bad_callback_url("must not be empty");
    if (url.size() > kMaxCallbackUrlLength)
        bad_callback_url("is " + std::to_string(url.size()) + " characters; at most " +
                         std::to_string(kMaxCallbackUrlLength));
    for (unsigned char c : url)
        if (c <= 0x20 || c >= 0x7f)
            bad_callback_url("must be an ASCII URL without spaces or control characters (percent-encode)");
    const size_t colon = url.find("://");
    const std::string scheme = colon == std::string::npos ? "" : ascii_lower(std::string_view(url).substr(0, colon));
    if (scheme != "http" && scheme != "https") bad_callback_url("must be an http:// or https:// URL");
    const size_t authority_end = url.find_first_of("/?#", colon + 3);
    const std::string authority =
        url.substr(colon + 3, authority_end == std::string::npos ? std::string::npos : authority_end - colon - 3);
    if (authority.find('@') != std::string::npos)
        bad_callback_url("must not carry user information (user:password@): receivers check the signature instead");
    if (url.find('#') != std::string::npos) bad_callback_url("must not have a fragment (#...)");
    // host[:port], the host a name, an IPv4 address or a bracketed IPv6 one
    // (parsed by hand: std::regex recurses per character and a long hostile
    // authority could exhaust the stack).
    CallbackUrl u;
    u.scheme = scheme;
    std::string port;
    if (!authority.empty() && authority.front() == '[') {
        const size_t close = authority.find(']');
        if (close == std::string::npos) bad_callback_url("has no valid host[:port]");
        u.host = authority.substr(1, close - 1);
        const std::string rest = authority.substr(close + 1);
        if (!rest.empty() && rest.front() != ':') bad_callback_url("has no valid host[:port]");
        if (!rest.empty()) port = rest.substr(1);
        if (u.host.empty() || u.host.find_first_not_of("0123456789abcdefABCDEF:.") != std::string::npos)
            bad_callback_url("has an invalid IPv6 host address");
    } else {
        const size_t c = authority.find(':');
        u.host = authority.substr(0, c);
        if (c != std::string::npos) port = authority.substr(c + 1);
        if (u.host.empty() ||
            u.host.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789.-") !=
                std::string::npos)
            bad_callback_url("has no valid host[:port]");
    }
    if (authority.find(':') != std::string::npos && authority.back() == ':') bad_callback_url("has an empty port");
    if (!port.empty() && (port.size() > 5 || port.find_first_not_of("0123456789") != std::string::npos))
        bad_callback_url("has a port outside 1..65535");
    u.port = !port.empty() ? std::stoi(port) : (scheme == "https" ? 443 : 80);
    if (u.port < 1 || u.port > 65535) bad_callback_url("has a port outside 1..65535");
    u.target = authority_end == std::string::npos ? "/" : url.substr(authority_end);
    if (u.target.front() == '?') u.target = "/" + u.target;
    sockaddr_storage address;
    const bool literal = literal_address(u.host, address);
    if (!literal && u.host.find(':') != std::string::npos) bad_callback_url("has an invalid IPv6 host address");
    if (!allow_private &&
        (is_localhost_name(u.host) || (literal && !is_public_address(reinterpret_cast<sockaddr*>(&address)))))
        bad_callback_url(
            "points at a loopback, private or link-local address; this service sends callbacks only to public "
            "addresses (it is started with --webhook-allow-private to allow others)");
    return u;
}

bool is_public_address(const sockaddr* address) {
    if (address->sa_family == AF_INET)
        return public_v4(ntohl(reinterpret_cast<const sockaddr_in*>(address)->sin_addr.s_addr));
    if (address->sa_family == AF_INET6)
        return public_v6(reinterpret_cast<const sockaddr_in6*>(address)->sin6_addr.s6_addr);
    return false;
}

}  // namespace nurbsrt::server
