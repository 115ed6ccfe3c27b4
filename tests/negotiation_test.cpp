// Proactive negotiation (RFC 9110 §12.5.1) and download names (RFC 6266, RFC 8187).
#include <gtest/gtest.h>

#include "server/http/negotiation.h"

using nurbsrt::server::attachment_disposition;
using nurbsrt::server::negotiate_media_type;

namespace {

const std::vector<std::string> kRenderOffers = {"image/png", "image/jpeg", "image/tiff", "image/x-exr",
                                                "application/json"};

std::string chosen(std::string_view accept, const std::vector<std::string>& offers = kRenderOffers) {
    return negotiate_media_type(accept, offers).value_or("406");
}

}  // namespace

// Accept field -> the answer's media type among the render's offers ("406": none).
struct Case {
    const char* accept;
    const char* answer;
};

TEST(Negotiation, ChoosesAsRfc9110Says) {
    const Case cases[] = {
        // No Accept, or anything: the first offer.
        {"", "image/png"},
        {"*/*", "image/png"},
        {"image/*", "image/png"},
        {"  ", "image/png"},
        // Named types are served; media types are case-insensitive (RFC 9110 §8.3.1).
        {"image/jpeg", "image/jpeg"},
        {"IMAGE/TIFF", "image/tiff"},
        {"image/x-exr;q=0.5", "image/x-exr"},
        {"application/json", "application/json"},
        // A type named exactly beats a wildcard of the same weight: a browser's fetch of JSON.
        {"application/json, */*", "application/json"},
        {"application/json, text/plain, */*", "application/json"},
        // Weights decide; the most specific range sets an offer's weight; a tie keeps the server's order.
        {"image/png;q=0.4, image/jpeg;q=0.9", "image/jpeg"},
        {"application/json;q=0.1, image/*;q=0.2", "image/png"},
        {"image/*, image/png;q=0", "image/jpeg"},
        {"image/png ; q=0.3 , application/json ; q=0.30", "image/png"},
        // Parameters other than q are ignored.
        {"application/json;charset=utf-8", "application/json"},
        {"text/plain;format=flowed, image/tiff;level=1;q=0.7", "image/tiff"},
        // Nothing acceptable: 406. A weight that is no number in [0, 1] refuses, never prefers.
        {"application/xml", "406"},
        {"text/html, application/xhtml+xml", "406"},
        {"image/png;q=0, application/json;q=0", "406"},
        {"image/png;q=abc", "406"},
        {"image/png;q=2", "406"}};
    for (const Case& c : cases) EXPECT_EQ(chosen(c.accept), c.answer) << "Accept: " << c.accept;
    EXPECT_EQ(chosen("image/gif", {"image/png"}), "406");
    EXPECT_EQ(chosen("*/*", {}), "406");
}

TEST(Disposition, KeepsTheNameByteForByte) {
    EXPECT_EQ(attachment_disposition("bearing.iges"),
              "attachment; filename=\"bearing.iges\"; filename*=UTF-8''bearing.iges");
    EXPECT_EQ(attachment_disposition("My Part (v2).STEP"),
              "attachment; filename=\"My Part (v2).STEP\"; filename*=UTF-8''My%20Part%20%28v2%29.STEP");
    // UTF-8 exactly in the RFC 8187 form; the quoted form of a client that cannot read it stays ASCII.
    EXPECT_EQ(attachment_disposition("Gehäuse.stp"),
              "attachment; filename=\"Geh__use.stp\"; filename*=UTF-8''Geh%C3%A4use.stp");
    // Quotes and backslashes cannot end or escape the quoted form; no path survives.
    EXPECT_EQ(attachment_disposition("a\"b\\c.igs"), "attachment; filename=\"c.igs\"; filename*=UTF-8''c.igs");
    EXPECT_EQ(attachment_disposition("x\"y.igs"), "attachment; filename=\"x_y.igs\"; filename*=UTF-8''x%22y.igs");
    EXPECT_EQ(attachment_disposition("../../etc/passwd"), "attachment; filename=\"passwd\"; filename*=UTF-8''passwd");
    EXPECT_EQ(attachment_disposition("a\r\nSet-Cookie: x"),
              "attachment; filename=\"a__Set-Cookie: x\"; filename*=UTF-8''a%0D%0ASet-Cookie%3A%20x");
}
