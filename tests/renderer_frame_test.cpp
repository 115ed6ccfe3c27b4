// for_each_neighbour: the neighbourhood walk every pass of a frame uses.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <utility>
#include <vector>

#include "renderer/frame/frame.h"
#include "core/process/heap_tuning.h"

namespace nurbsrt {
namespace {

using Px = std::pair<int, int>;

std::vector<Px> walk(int w, int h, int i, int j, int radius) {
    std::vector<Px> out;
    for_each_neighbour(w, h, i, j, radius, [&](int a, int b) { out.push_back({a, b}); });
    return out;
}

TEST(ForEachNeighbour, InteriorSquareInScanOrderWithTheCentre) {
    const std::vector<Px> expected = {{1, 1}, {2, 1}, {3, 1}, {1, 2}, {2, 2}, {3, 2}, {1, 3}, {2, 3}, {3, 3}};
    EXPECT_EQ(walk(5, 5, 2, 2, 1), expected);
    EXPECT_EQ(walk(9, 9, 4, 4, 2).size(), 25u);
}

TEST(ForEachNeighbour, ClippedAtTheFrame) {
    const std::vector<Px> corner = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
    EXPECT_EQ(walk(5, 4, 0, 0, 1), corner);
    const std::vector<Px> far_corner = {{3, 2}, {4, 2}, {3, 3}, {4, 3}};
    EXPECT_EQ(walk(5, 4, 4, 3, 1), far_corner);
    const std::vector<Px> single = {{0, 0}};
    EXPECT_EQ(walk(1, 1, 0, 0, 2), single);
}

TEST(ForEachNeighbour, StopsWhenTheCallbackReturnsFalse) {
    std::vector<Px> seen;
    for_each_neighbour(5, 5, 2, 2, 1, [&](int a, int b) {
        seen.push_back({a, b});
        return !(a == 3 && b == 1);
    });
    const std::vector<Px> expected = {{1, 1}, {2, 1}, {3, 1}};
    EXPECT_EQ(seen, expected);
}

}  // namespace
}  // namespace nurbsrt

// Faulting in a buffer's pages leaves what it holds as it was (populate_pages
// only maps pages; fresh ones read as zero either way), for a buffer of fresh
// pages above glibc's mmap threshold and for one already written, unaligned
// ends included.
TEST(PopulatePages, KeepsTheContents) {
    constexpr size_t kBytes = (size_t(40) << 20) + 12345;  // over kPopulateMinBytes, not whole pages
    std::vector<uint8_t> fresh;
    fresh.reserve(kBytes);
    const bool supported = nurbsrt::populate_pages(fresh.data(), kBytes);
    fresh.resize(kBytes);  // value-initialized after the populate
    EXPECT_TRUE(std::all_of(fresh.begin(), fresh.end(), [](uint8_t b) { return b == 0; }));
    std::vector<uint8_t> written(kBytes);
    for (size_t k = 0; k < kBytes; ++k) written[k] = static_cast<uint8_t>(k * 2654435761u >> 24);
    EXPECT_EQ(nurbsrt::populate_pages(written.data() + 7, kBytes - 7), supported);
    for (size_t k = 0; k < kBytes; ++k)
        ASSERT_EQ(written[k], static_cast<uint8_t>(k * 2654435761u >> 24)) << "byte " << k;
    if (!supported)
        std::printf("[ populate ] madvise(MADV_POPULATE_WRITE) is not supported here: buffers fill on one thread\n");
}
