#include "detector/candidates.h"

#include "detector/opencv_overrides.h"

#ifdef __SSE2__
#include <emmintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <opencv2/imgproc.hpp>
#include <vector>

namespace mcmt {

// Per tile row: the minimum and maximum of each column over the tile's rows, kept in registers 16
// columns at a time over the rows (SSE2), then over each tile's columns (t = 4: 16 columns, 4 tiles at a
// time; the last tile's columns beyond the image are the image's last column again). The same minima
// and maxima as the row-by-row cv::min / cv::max it replaces (test_detector_unit,
// CandidateSearch.TileRangesAreTheNeighbourhoodsRanges). Their call overhead and a scalar pass over
// every column made QuadFinder's constructor 42.2 M instructions on bench_detector's 10 blurred frames
// (MCMT_BENCH_BLUR=1.2: the broken-border search, bench/results/2026-12-06-blursearch.md); now 17.9 M.
void TileRanges(const cv::Mat& gray, int t, std::vector<uint8_t>* lo, std::vector<uint8_t>* hi) {
  const int cols = gray.cols, rows = gray.rows;
  const int tw = (cols + t - 1) / t, th = (rows + t - 1) / t;
  cv::Mat tlo(th, tw, CV_8U), thi(th, tw, CV_8U);
  thread_local std::vector<uint8_t> col_lo, col_hi;
  col_lo.resize(static_cast<size_t>(tw) * t);
  col_hi.resize(static_cast<size_t>(tw) * t);
  uint8_t* __restrict pl = col_lo.data();
  uint8_t* __restrict ph = col_hi.data();
  for (int ty = 0; ty < th; ++ty) {
    const int y0 = ty * t, y1 = std::min(rows, y0 + t);
    int x = 0;
#ifdef __SSE2__
    for (; x + 16 <= cols; x += 16) {
      __m128i mn = _mm_loadu_si128(reinterpret_cast<const __m128i*>(gray.ptr<uint8_t>(y0) + x)), mx = mn;
      for (int y = y0 + 1; y < y1; ++y) {
        const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(gray.ptr<uint8_t>(y) + x));
        mn = _mm_min_epu8(mn, v), mx = _mm_max_epu8(mx, v);
      }
      _mm_storeu_si128(reinterpret_cast<__m128i*>(pl + x), mn);
      _mm_storeu_si128(reinterpret_cast<__m128i*>(ph + x), mx);
    }
#endif
    for (; x < cols; ++x) {
      uint8_t mn = gray.ptr<uint8_t>(y0)[x], mx = mn;
      for (int y = y0 + 1; y < y1; ++y) {
        const uint8_t v = gray.ptr<uint8_t>(y)[x];
        mn = std::min(mn, v), mx = std::max(mx, v);
      }
      pl[x] = mn, ph[x] = mx;
    }
    for (x = cols; x < tw * t; ++x) pl[x] = pl[cols - 1], ph[x] = ph[cols - 1];
    uint8_t* __restrict out_lo = tlo.ptr<uint8_t>(ty);
    uint8_t* __restrict out_hi = thi.ptr<uint8_t>(ty);
    int tx = 0;
#ifdef __SSE2__
    if (t == 4) {
      // Within each 32-bit lane (one tile's 4 columns) the minimum / maximum into its low byte.
      const __m128i low_byte = _mm_set1_epi32(0xff);
      auto tiles = [&](__m128i v, bool is_min) {
        v = is_min ? _mm_min_epu8(v, _mm_srli_epi32(v, 8)) : _mm_max_epu8(v, _mm_srli_epi32(v, 8));
        v = is_min ? _mm_min_epu8(v, _mm_srli_epi32(v, 16)) : _mm_max_epu8(v, _mm_srli_epi32(v, 16));
        const __m128i words = _mm_packs_epi32(_mm_and_si128(v, low_byte), _mm_setzero_si128());
        return _mm_cvtsi128_si32(_mm_packus_epi16(words, _mm_setzero_si128()));
      };
      for (; tx + 4 <= tw; tx += 4) {
        const int a = tiles(_mm_loadu_si128(reinterpret_cast<const __m128i*>(pl + 4 * tx)), true);
        const int b = tiles(_mm_loadu_si128(reinterpret_cast<const __m128i*>(ph + 4 * tx)), false);
        std::memcpy(out_lo + tx, &a, 4);
        std::memcpy(out_hi + tx, &b, 4);
      }
    }
#endif
    for (; tx < tw; ++tx) {
      uint8_t mn = 255, mx = 0;
      for (x = tx * t; x < tx * t + t; ++x) mn = std::min(mn, pl[x]), mx = std::max(mx, ph[x]);
      out_lo[tx] = mn, out_hi[tx] = mx;
    }
  }
  // 3 x 3 tile neighbourhoods (within the image: erosion and dilation ignore what is outside).
  const cv::Mat square = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(3, 3));
  cv::erode(tlo, tlo, square);
  cv::dilate(thi, thi, square);
  lo->assign(tlo.datastart, tlo.dataend);
  hi->assign(thi.datastart, thi.dataend);
}

namespace {

double Cross(const cv::Point2d& a, const cv::Point2d& b) { return a.x * b.y - a.y * b.x; }

// Distance of p to the segment a-b.
double SegmentDistance(const cv::Point2d& p, const cv::Point2d& a, const cv::Point2d& b) {
  const cv::Point2d ab = b - a, ap = p - a;
  const double len2 = ab.dot(ab);
  const double u = len2 > 0 ? std::clamp(ap.dot(ab) / len2, 0.0, 1.0) : 0.0;
  return cv::norm(ap - u * ab);
}

// A quad from one closed boundary; false if the boundary is not one.
bool QuadFromBoundary(const std::vector<cv::Point>& c, const QuadSearch& s, cv::Size size,
                      std::array<cv::Point2d, 4>* quad) {
  const int n = static_cast<int>(c.size());
  cv::Point2d centre(0, 0);
  for (const cv::Point& p : c) centre += cv::Point2d(p);
  centre *= 1.0 / n;
  auto farthest = [&](const cv::Point2d& from) {
    int best = 0;
    double d = -1;
    for (int i = 0; i < n; ++i) {
      const cv::Point2d q = cv::Point2d(c[i]) - from;
      const double v = q.dot(q);
      if (v > d) d = v, best = i;
    }
    return best;
  };
  const int i0 = farthest(centre);
  const int i2 = farthest(cv::Point2d(c[i0]));
  // The two other corners: farthest from the diagonal on either side.
  const cv::Point2d a(c[i0]), diagonal = cv::Point2d(c[i2]) - a;
  int i1 = -1, i3 = -1;
  double d1 = 0, d3 = 0;
  for (int i = 0; i < n; ++i) {
    const double v = Cross(diagonal, cv::Point2d(c[i]) - a);
    if (v > d1) d1 = v, i1 = i;
    if (-v > d3) d3 = -v, i3 = i;
  }
  if (i1 < 0 || i3 < 0) return false;
  const double perimeter = static_cast<double>(n);
  // Corners in boundary order.
  std::array<int, 4> idx = {i0, i1, i2, i3};
  std::sort(idx.begin(), idx.end());
  if (idx[0] == idx[1] || idx[1] == idx[2] || idx[2] == idx[3]) return false;
  // Every boundary point near its side of the extreme points' polygon.
  const double tolerance = std::max(1.5, s.max_deviation_rate * perimeter);
  std::array<cv::Point2d, 4> extreme;
  for (int k = 0; k < 4; ++k) extreme[k] = cv::Point2d(c[idx[k]]);
  for (int k = 0; k < 4; ++k) {
    const int begin = idx[k], end = k == 3 ? idx[0] + n : idx[k + 1];
    for (int i = begin; i < end; ++i)
      if (SegmentDistance(cv::Point2d(c[i % n]), extreme[k], extreme[(k + 1) % 4]) > tolerance) return false;
  }
  // A line fitted to each side's points, a sixth of the side left out at each end (rounded corners).
  std::array<cv::Vec4f, 4> lines;
  std::vector<cv::Point2f> points;
  for (int k = 0; k < 4; ++k) {
    const int begin = idx[k], end = k == 3 ? idx[0] + n : idx[k + 1];
    const int len = end - begin, skip = len / 6;
    points.clear();
    for (int i = begin + skip; i <= end - skip; ++i) points.emplace_back(cv::Point2f(c[i % n]));
    if (points.size() < 2) return false;
    cv::fitLine(points, lines[k], cv::DIST_L2, 0, 0.01, 0.01);
  }
  for (int k = 0; k < 4; ++k) {
    // Corner k: the intersection of side k-1 (ending at it) and side k (starting at it).
    const cv::Vec4f& l0 = lines[(k + 3) % 4];
    const cv::Vec4f& l1 = lines[k];
    const cv::Point2d p0(l0[2], l0[3]), v0(l0[0], l0[1]), p1(l1[2], l1[3]), v1(l1[0], l1[1]);
    const double det = Cross(v0, v1);
    if (std::abs(det) < 1e-3) return false;
    const double u = Cross(p1 - p0, v1) / det;
    const cv::Point2d corner = p0 + u * v0;
    // Not far from the extreme point (a side fit gone wrong).
    if (cv::norm(corner - extreme[k]) > 2.0 * tolerance + 2.0) return false;
    const double b = s.min_distance_to_border;
    if (corner.x < b || corner.y < b || corner.x > size.width - 1 - b || corner.y > size.height - 1 - b)
      return false;
    (*quad)[k] = corner;
  }
  // Convex, sides long enough; OpenCV's order.
  for (int k = 0; k < 4; ++k) {
    const cv::Point2d e0 = (*quad)[(k + 1) % 4] - (*quad)[k],
                      e1 = (*quad)[(k + 2) % 4] - (*quad)[(k + 1) % 4];
    if (cv::norm(e0) < s.min_side_rate * perimeter) return false;
    if (Cross(e0, e1) * Cross((*quad)[1] - (*quad)[0], (*quad)[2] - (*quad)[1]) <= 0) return false;
  }
  MakeClockwise(quad);
  return true;
}

}  // namespace

QuadFinder::QuadFinder(const cv::Mat& gray, const QuadSearch& search) : gray_(gray), search_(search) {
  CV_Assert(gray.type() == CV_8UC1);
  search_.tile_px = std::max(1, search.tile_px);
  const int t = search_.tile_px;
  tiles_wide_ = (gray.cols + t - 1) / t, tiles_high_ = (gray.rows + t - 1) / t;
  TileRanges(gray, t, &lo_, &hi_);
  // Regions: the bounding boxes (in tiles) of the 8-connected components of tiles with contrast, merged
  // where they overlap, so that each holds whole components: a dark component lies in tiles with
  // contrast, hence in one region, and no region cuts one.
  cv::Mat contrast(tiles_high_, tiles_wide_, CV_8U);
  for (int i = 0; i < tiles_high_ * tiles_wide_; ++i) contrast.data[i] = HasContrast(i) ? 255 : 0;
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(contrast, labels, stats, centroids, 8, CV_32S);
  for (int i = 1; i < n; ++i)
    regions_.emplace_back(stats.at<int>(i, cv::CC_STAT_LEFT), stats.at<int>(i, cv::CC_STAT_TOP),
                          stats.at<int>(i, cv::CC_STAT_WIDTH), stats.at<int>(i, cv::CC_STAT_HEIGHT));
  for (bool merged = true; merged;) {
    merged = false;
    for (size_t i = 0; i < regions_.size(); ++i)
      for (size_t j = i + 1; j < regions_.size(); ++j)
        if ((regions_[i] & regions_[j]).area() > 0) {
          regions_[i] |= regions_[j];
          regions_.erase(regions_.begin() + static_cast<long>(j));
          merged = true, --j;
        }
  }
  binary_.create(gray.size(), CV_8U);
}

std::vector<std::array<cv::Point2d, 4>> QuadFinder::Find(double level) { return Quads(level, 0, 0); }

std::vector<std::array<cv::Point2d, 4>> QuadFinder::FindBelowMean(int window_px, double offset) {
  return Quads(0, window_px, offset);
}

std::vector<std::array<cv::Point2d, 4>> QuadFinder::Quads(double level, int window_px, double offset) {
  const int t = search_.tile_px;
  std::vector<std::array<cv::Point2d, 4>> quads;
  for (const cv::Rect& region : regions_) {
    const cv::Rect tiles = Uncovered(region);
    const cv::Rect px(tiles.x * t, tiles.y * t, std::min(tiles.br().x * t, gray_.cols) - tiles.x * t,
                      std::min(tiles.br().y * t, gray_.rows) - tiles.y * t);
    // Too small to hold a quad's boundary (at most twice the box's width and height).
    if (tiles.empty() || 4.0 * std::max(px.width, px.height) < search_.min_perimeter) continue;
    Threshold(tiles, px, level, window_px, offset);
    // Two levels: components' outer boundaries (no parent) and their holes' boundaries.
    cv::findContours(binary_(px), contours_, hierarchy_, cv::RETR_CCOMP, cv::CHAIN_APPROX_NONE, px.tl());
    for (size_t i = 0; i < contours_.size(); ++i) {
      if (hierarchy_[i][3] >= 0) continue;
      const double length = static_cast<double>(contours_[i].size());
      if (length < search_.min_perimeter || length > search_.max_perimeter) continue;
      std::array<cv::Point2d, 4> quad;
      if (QuadFromBoundary(contours_[i], search_, gray_.size(), &quad)) quads.push_back(quad);
    }
  }
  return quads;
}

void QuadFinder::Threshold(const cv::Rect& tiles, const cv::Rect& px, double level, int window_px,
                           double offset) {
  const int t = search_.tile_px;
  // OpenCV's adaptive threshold: dark where v - mean <= -floor(offset), the mean rounded to 8 bits.
  const int delta = static_cast<int>(std::floor(offset));
  // The mean's threshold from window sums, the mean image not formed (ThresholdBelowBlur: the same binary
  // image as cv::blur's mean and the comparison below, test_detector_unit
  // CandidateSearch.ThresholdBelowBlurIsBlursComparison), then tiles without contrast cleared. This
  // function took 26.4 M instructions on bench_detector's 10 blurred frames (the broken-border search),
  // 16.4 M of them cv::blur; now 13.8 M.
  if (window_px > 0) {
    cv::Mat binary = binary_(px);
    if (ThresholdBelowBlur(gray_(px), window_px, -delta, 255, 0, &binary)) {
      std::vector<uint8_t> keep(static_cast<size_t>(tiles.width) * t);
      for (int ty = tiles.y; ty < tiles.br().y; ++ty) {
        bool all = true;
        for (int tx = tiles.x; tx < tiles.br().x; ++tx) {
          const bool on = HasContrast(ty * tiles_wide_ + tx);
          std::fill_n(keep.begin() + (tx - tiles.x) * t, t, static_cast<uint8_t>(on ? 255 : 0));
          all = all && on;
        }
        if (all) continue;
        const uint8_t* __restrict k = keep.data();
        for (int y = ty * t; y < std::min(gray_.rows, ty * t + t); ++y) {
          uint8_t* __restrict out = binary_.ptr<uint8_t>(y) + px.x;
          for (int x = 0; x < px.width; ++x) out[x] &= k[x];
        }
      }
      return;
    }
    mean_.create(gray_.size(), CV_8U);
    cv::Mat mean = mean_(px);
    cv::blur(gray_(px), mean, cv::Size(window_px, window_px), cv::Point(-1, -1), cv::BORDER_REPLICATE);
  }
  const int width = px.width, x0 = px.x, y_end = gray_.rows;  // locals: uint8_t pointers alias all
  std::vector<uint8_t> threshold(static_cast<size_t>(tiles.width) * t);
  for (int ty = tiles.y; ty < tiles.br().y; ++ty) {
    // Per tile: dark below this value (the mean's pass: 255 marks the tile searched); 0: no pixel.
    for (int tx = tiles.x; tx < tiles.br().x; ++tx) {
      const int mn = lo_[ty * tiles_wide_ + tx], mx = hi_[ty * tiles_wide_ + tx];
      const int value = !HasContrast(ty * tiles_wide_ + tx) ? 0
                        : window_px > 0                     ? 255
                                        : static_cast<int>(std::ceil(mn + level * (mx - mn) - 1e-9));
      std::fill_n(threshold.begin() + (tx - tiles.x) * t, t, static_cast<uint8_t>(std::min(value, 255)));
    }
    const uint8_t* __restrict thr = threshold.data();
    for (int y = ty * t; y < std::min(y_end, ty * t + t); ++y) {
      const uint8_t* __restrict in = gray_.ptr<uint8_t>(y) + x0;
      uint8_t* __restrict out = binary_.ptr<uint8_t>(y) + x0;
      if (window_px > 0) {
        const uint8_t* __restrict m = mean_.ptr<uint8_t>(y) + x0;
        for (int x = 0; x < width; ++x) out[x] = in[x] + delta <= m[x] ? thr[x] : 0;
      } else {
        for (int x = 0; x < width; ++x) out[x] = in[x] < thr[x] ? 255 : 0;
      }
    }
  }
}

cv::Rect QuadFinder::Uncovered(const cv::Rect& region) const {
  int x0 = region.br().x, y0 = region.br().y, x1 = region.x - 1, y1 = region.y - 1;
  for (int ty = region.y; ty < region.br().y; ++ty)
    for (int tx = region.x; tx < region.br().x; ++tx)
      if (HasContrast(ty * tiles_wide_ + tx))
        x0 = std::min(x0, tx), y0 = std::min(y0, ty), x1 = std::max(x1, tx), y1 = std::max(y1, ty);
  return x1 < x0 ? cv::Rect() : cv::Rect(x0, y0, x1 - x0 + 1, y1 - y0 + 1);
}

void QuadFinder::Cover(const std::array<cv::Point2d, 4>& quad, double grow_px) {
  double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
  for (const cv::Point2d& c : quad)
    x0 = std::min(x0, c.x), y0 = std::min(y0, c.y), x1 = std::max(x1, c.x), y1 = std::max(y1, c.y);
  const int t = search_.tile_px;
  const int tx0 = std::max(0, static_cast<int>(std::floor((x0 - grow_px) / t)));
  const int ty0 = std::max(0, static_cast<int>(std::floor((y0 - grow_px) / t)));
  const int tx1 = std::min(tiles_wide_ - 1, static_cast<int>(std::floor((x1 + grow_px) / t)));
  const int ty1 = std::min(tiles_high_ - 1, static_cast<int>(std::floor((y1 + grow_px) / t)));
  for (int ty = ty0; ty <= ty1; ++ty)
    for (int tx = tx0; tx <= tx1; ++tx) lo_[ty * tiles_wide_ + tx] = 255, hi_[ty * tiles_wide_ + tx] = 0;
}

std::vector<std::array<cv::Point2d, 4>> FindQuads(const cv::Mat& gray, const QuadSearch& search) {
  QuadFinder finder(gray, search);
  std::vector<std::array<cv::Point2d, 4>> quads;
  for (double level : search.levels) {
    const std::vector<std::array<cv::Point2d, 4>> found = finder.Find(level);
    quads.insert(quads.end(), found.begin(), found.end());
  }
  return quads;
}

}  // namespace mcmt
