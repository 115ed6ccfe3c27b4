// server/http/http_framing.h: the RFC 9112 framing rules a request head must keep
// before cpp-httplib reads on (request smuggling: one request hiding another).
// The service's own answers to these heads are tested over sockets in
// tests/api/test_hostile.py.
#include <gtest/gtest.h>

#include <string>

#include "server/http/http_framing.h"

using nurbsrt::server::BodyFraming;
using nurbsrt::server::check_request_head;
using nurbsrt::server::ServiceCode;

namespace {

std::string head(const std::string& request_line, const std::string& fields) {
    return request_line + "\r\n" + fields + "\r\n";
}

}  // namespace

TEST(HttpFraming, WellFramedRequestsPass) {
    const auto get = check_request_head(head("GET /healthz HTTP/1.1", "Host: x\r\n"));
    EXPECT_TRUE(get.ok()) << get.detail;
    EXPECT_EQ(get.body, BodyFraming::none);
    EXPECT_TRUE(check_request_head(head("GET /healthz HTTP/1.1", "Host: x\r\nContent-Length: 0\r\n")).ok());
    const auto post = check_request_head(head("POST /v1/renders HTTP/1.1", "Host: x\r\ncontent-length: 42\r\n"));
    EXPECT_TRUE(post.ok()) << post.detail;
    EXPECT_EQ(post.body, BodyFraming::content_length);
    const auto chunked =
        check_request_head(head("POST /v1/renders HTTP/1.1", "Host: x\r\nTransfer-Encoding: Chunked\r\n"));
    EXPECT_TRUE(chunked.ok()) << chunked.detail;
    EXPECT_EQ(chunked.body, BodyFraming::chunked);
    EXPECT_TRUE(check_request_head(head("GET / HTTP/1.0", "")).ok());  // HTTP/1.0 needs no Host
    EXPECT_TRUE(check_request_head(head("GET / HTTP/1.1", "Host:x\r\nX-Empty:\r\nX-Tab:\tv\t\r\n")).ok());
}

TEST(HttpFraming, BodiesThatWouldBeParsedAsTheNextRequestAreRefused) {
    for (const char* method : {"GET", "HEAD", "TRACE"}) {
        const auto v =
            check_request_head(head(std::string(method) + " /healthz HTTP/1.1", "Host: x\r\nContent-Length: 42\r\n"));
        EXPECT_EQ(v.status, 400) << method;
        EXPECT_EQ(v.code, ServiceCode::malformed_request);
    }
    EXPECT_EQ(check_request_head(head("GET / HTTP/1.1", "Host: x\r\nTransfer-Encoding: chunked\r\n")).status, 400);
}

TEST(HttpFraming, ContentLengthMustBeOneDecimalNumber) {
    for (const char* fields :
         {"Content-Length: +10\r\n", "Content-Length: -1\r\n", "Content-Length: 1, 1\r\n", "Content-Length: 0x10\r\n",
          "Content-Length:\r\n", "Content-Length: 1 0\r\n", "Content-Length: 99999999999999999999\r\n",
          "Content-Length: 10\r\nContent-Length: 11\r\n", "Content-Length: 10\r\nContent-Length: 10\r\n"}) {
        const auto v = check_request_head(head("POST /v1/renders HTTP/1.1", std::string("Host: x\r\n") + fields));
        EXPECT_EQ(v.status, 400) << fields;
        EXPECT_EQ(v.code, ServiceCode::malformed_request) << fields;
    }
}

TEST(HttpFraming, OnlyChunkedAloneIsATransferCoding) {
    for (const char* te : {"xchunked", "gzip, chunked", "chunked, identity", "identity", "chunked, chunked"}) {
        const auto v = check_request_head(
            head("POST /v1/renders HTTP/1.1", std::string("Host: x\r\nTransfer-Encoding: ") + te + "\r\n"));
        EXPECT_EQ(v.status, 501) << te;
        EXPECT_EQ(v.code, ServiceCode::not_implemented) << te;
    }
    // Two field lines are one list: chunked twice.
    EXPECT_EQ(check_request_head(
                  head("POST / HTTP/1.1", "Host: x\r\nTransfer-Encoding: chunked\r\nTransfer-Encoding: chunked\r\n"))
                  .status,
              501);
    EXPECT_EQ(
        check_request_head(head("POST / HTTP/1.1", "Host: x\r\nTransfer-Encoding: chunked\r\nContent-Length: 10\r\n"))
            .status,
        400);
    EXPECT_EQ(check_request_head(head("POST / HTTP/1.0", "Transfer-Encoding: chunked\r\n")).status, 400);
}

TEST(HttpFraming, MalformedHeaderLinesAreRefused) {
    for (const char* fields : {"X-Bad-Line\r\n", "Host : x\r\n", "Host: x\r\nX-A: 1\r\n folded\r\n",
                               "Host: x\r\n: novalue\r\n", "Host: x\r\nX-\"q\": 1\r\n"}) {
        const auto v = check_request_head(head("GET / HTTP/1.1", fields));
        EXPECT_EQ(v.status, 400) << fields;
    }
    EXPECT_EQ(check_request_head("GET / HTTP/1.1\r\nHost: x\nX-A: 1\r\n\r\n").status, 400);  // bare LF
    EXPECT_EQ(check_request_head("GET / HTTP/1.1\r\nHost: x\rX-A: 1\r\n\r\n").status, 400);  // bare CR
    EXPECT_EQ(check_request_head(std::string("GET / HTTP/1.1\r\nHost: x\r\nX-A: a\0b\r\n\r\n", 36)).status, 400);
    EXPECT_EQ(check_request_head(head("GET / HTTP/1.1", "")).status, 400);  // no Host
    EXPECT_EQ(check_request_head(head("GET / HTTP/1.1", "Host: x\r\nHost: y\r\n")).status, 400);
    // A refusal's detail never echoes control bytes or unbounded text.
    const auto v = check_request_head(head("GET / HTTP/1.1", "Host: x\r\n" + std::string(5000, 'a') + "\x01\r\n"));
    EXPECT_EQ(v.status, 400);
    EXPECT_LT(v.detail.size(), 200u);
}
