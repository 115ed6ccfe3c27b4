// Several views of a scene as one image (render.h compose_sheet).
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/check.h"
#include "renderer/render.h"

namespace nurbsrt {

namespace {

// A label is this fraction of a cell's height (and at least kMinLabelPixels):
// readable on a thumbnail, small beside the part.
constexpr double kLabelHeight = 1.0 / 16;
constexpr int kMinLabelPixels = 10;
// Dark grey: reads on the light backgrounds of product shots and on transparency.
constexpr Color kLabelColor{0.08f, 0.08f, 0.08f};

// Copies `n` values per pixel of frame f's buffer into cell (col, row) of the sheet's.
template <class T>
void place(const std::vector<T>& from, std::vector<T>& to, int n, int w, int h, int sheet_w, int col, int row) {
    if (from.empty()) return;
    for (int j = 0; j < h; ++j) {
        const size_t src = static_cast<size_t>(j) * w * n;
        const size_t dst = (static_cast<size_t>(row * h + j) * sheet_w + static_cast<size_t>(col) * w) * n;
        std::copy(from.begin() + static_cast<std::ptrdiff_t>(src),
                  from.begin() + static_cast<std::ptrdiff_t>(src + static_cast<size_t>(w) * n),
                  to.begin() + static_cast<std::ptrdiff_t>(dst));
    }
}

}  // namespace

RenderImage compose_sheet(const std::vector<RenderResult>& frames, const std::vector<std::string>& labels,
                          const RenderOptions& options) {
    NURBSRT_CHECK(!frames.empty() && labels.size() == frames.size());
    const int columns = std::max(1, static_cast<int>(std::ceil(std::sqrt(static_cast<double>(frames.size())))));
    const float empty[4] = {options.background.r, options.background.g, options.background.b, options.background_alpha};
    const int w = frames[0].image.width, h = frames[0].image.height;
    const int rows = static_cast<int>((frames.size() + columns - 1) / columns);
    RenderImage sheet;
    sheet.width = w * columns;
    sheet.height = h * rows;
    const size_t npx = static_cast<size_t>(sheet.width) * sheet.height;
    sheet.rgba.resize(4 * npx);
    for (size_t k = 0; k < npx; ++k) std::copy(empty, empty + 4, &sheet.rgba[4 * k]);
    sheet.z.assign(npx, std::numeric_limits<float>::infinity());
    sheet.normal.assign(3 * npx, 0.0f);
    sheet.face.assign(npx, 0);
    sheet.u.assign(npx, 0.0f);
    sheet.v.assign(npx, 0.0f);
    sheet.iterations.assign(npx, 0);
    if (!frames[0].image.shadow.empty()) sheet.shadow.assign(npx, 0);
    for (size_t f = 0; f < frames.size(); ++f) {
        const RenderImage& im = frames[f].image;
        NURBSRT_CHECK(im.width == w && im.height == h);
        const int col = static_cast<int>(f % columns), row = static_cast<int>(f / columns);
        place(im.rgba, sheet.rgba, 4, w, h, sheet.width, col, row);
        place(im.z, sheet.z, 1, w, h, sheet.width, col, row);
        place(im.normal, sheet.normal, 3, w, h, sheet.width, col, row);
        place(im.face, sheet.face, 1, w, h, sheet.width, col, row);
        place(im.u, sheet.u, 1, w, h, sheet.width, col, row);
        place(im.v, sheet.v, 1, w, h, sheet.width, col, row);
        place(im.iterations, sheet.iterations, 1, w, h, sheet.width, col, row);
        place(im.shadow, sheet.shadow, 1, w, h, sheet.width, col, row);
    }
    const int size = std::max(kMinLabelPixels, static_cast<int>(std::lround(h * kLabelHeight)));
    for (size_t f = 0; f < frames.size(); ++f) {
        if (labels[f].empty()) continue;
        const int col = static_cast<int>(f % columns), row = static_cast<int>(f / columns);
        draw_label(sheet, col * w + size / 2, row * h + size / 2, size, labels[f], kLabelColor);
    }
    return sheet;
}

}  // namespace nurbsrt
