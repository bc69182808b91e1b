#include "detector/candidates.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <opencv2/imgproc.hpp>

namespace mcmt {
namespace {

// Each tile's minimum and maximum over it and its 8 neighbours (tw x th tiles of t x t pixels).
void TileRanges(const cv::Mat& gray, int t, std::vector<uint8_t>* lo, std::vector<uint8_t>* hi) {
  const int cols = gray.cols, rows = gray.rows;
  const int tw = (cols + t - 1) / t, th = (rows + t - 1) / t;
  std::vector<uint8_t> tlo(static_cast<size_t>(tw) * th), thi(static_cast<size_t>(tw) * th);
  std::vector<uint8_t> col_lo(static_cast<size_t>(tw) * t), col_hi(static_cast<size_t>(tw) * t);
  for (int ty = 0; ty < th; ++ty) {
    // Per column over the tile's rows (vectorised), then over the tile's columns.
    std::fill(col_lo.begin(), col_lo.end(), 255);
    std::fill(col_hi.begin(), col_hi.end(), 0);
    uint8_t* __restrict l = col_lo.data();
    uint8_t* __restrict h = col_hi.data();
    for (int y = ty * t; y < std::min(rows, ty * t + t); ++y) {
      const uint8_t* __restrict row = gray.ptr<uint8_t>(y);
      for (int x = 0; x < cols; ++x) {
        l[x] = std::min(l[x], row[x]);
        h[x] = std::max(h[x], row[x]);
      }
    }
    for (int tx = 0; tx < tw; ++tx) {
      uint8_t mn = 255, mx = 0;
      for (int x = tx * t; x < tx * t + t; ++x) mn = std::min(mn, l[x]), mx = std::max(mx, h[x]);
      tlo[ty * tw + tx] = mn, thi[ty * tw + tx] = mx;
    }
  }
  // 3 x 3 tile neighbourhoods: separable, rows then columns.
  std::vector<uint8_t> rlo(tlo.size()), rhi(thi.size());
  for (int ty = 0; ty < th; ++ty)
    for (int tx = 0; tx < tw; ++tx) {
      uint8_t mn = 255, mx = 0;
      for (int dx = std::max(0, tx - 1); dx <= std::min(tw - 1, tx + 1); ++dx) {
        mn = std::min(mn, tlo[ty * tw + dx]);
        mx = std::max(mx, thi[ty * tw + dx]);
      }
      rlo[ty * tw + tx] = mn, rhi[ty * tw + tx] = mx;
    }
  lo->assign(tlo.size(), 255);
  hi->assign(thi.size(), 0);
  for (int ty = 0; ty < th; ++ty)
    for (int tx = 0; tx < tw; ++tx)
      for (int dy = std::max(0, ty - 1); dy <= std::min(th - 1, ty + 1); ++dy) {
        (*lo)[ty * tw + tx] = std::min((*lo)[ty * tw + tx], rlo[dy * tw + tx]);
        (*hi)[ty * tw + tx] = std::max((*hi)[ty * tw + tx], rhi[dy * tw + tx]);
      }
}

// Dark pixels (255): below min + level * (max - min) of their tile's range; none in tiles whose range is
// below min_contrast.
void LevelBinary(const cv::Mat& gray, int t, const std::vector<uint8_t>& lo, const std::vector<uint8_t>& hi,
                 double level, int min_contrast, cv::Mat* binary) {
  const int cols = gray.cols, rows = gray.rows;
  const int tw = (cols + t - 1) / t, th = (rows + t - 1) / t;
  binary->create(rows, cols, CV_8U);
  std::vector<uint8_t> threshold(static_cast<size_t>(tw) * t);
  for (int ty = 0; ty < th; ++ty) {
    for (int tx = 0; tx < tw; ++tx) {
      const int mn = lo[ty * tw + tx], mx = hi[ty * tw + tx];
      // Dark: v < value (v integer), i.e. v < min + level * (max - min); 0: no pixel.
      const int value =
          mx - mn < min_contrast ? 0 : static_cast<int>(std::ceil(mn + level * (mx - mn) - 1e-9));
      std::fill(threshold.begin() + tx * t, threshold.begin() + tx * t + t,
                static_cast<uint8_t>(std::min(value, 255)));
    }
    const uint8_t* __restrict thr = threshold.data();
    for (int y = ty * t; y < std::min(rows, ty * t + t); ++y) {
      const uint8_t* __restrict in = gray.ptr<uint8_t>(y);
      uint8_t* __restrict out = binary->ptr<uint8_t>(y);
      for (int x = 0; x < cols; ++x) out[x] = in[x] < thr[x] ? 255 : 0;
    }
  }
}

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
  if (Cross((*quad)[1] - (*quad)[0], (*quad)[2] - (*quad)[0]) < 0) std::swap((*quad)[1], (*quad)[3]);
  return true;
}

}  // namespace

QuadFinder::QuadFinder(const cv::Mat& gray, const QuadSearch& search) : gray_(gray), search_(search) {
  CV_Assert(gray.type() == CV_8UC1);
  search_.tile_px = std::max(1, search.tile_px);
  const int t = search_.tile_px;
  tiles_wide_ = (gray.cols + t - 1) / t, tiles_high_ = (gray.rows + t - 1) / t;
  TileRanges(gray, t, &lo_, &hi_);
}

std::vector<std::array<cv::Point2d, 4>> QuadFinder::Find(double level) {
  LevelBinary(gray_, search_.tile_px, lo_, hi_, level, search_.min_contrast, &binary_);
  return Quads();
}

std::vector<std::array<cv::Point2d, 4>> QuadFinder::FindBelowMean(int window_px, double offset) {
  cv::adaptiveThreshold(gray_, binary_, 255, cv::ADAPTIVE_THRESH_MEAN_C, cv::THRESH_BINARY_INV, window_px,
                        offset);
  // Only tiles with contrast, not covered (a row of tile masks per row of tiles).
  const int t = search_.tile_px;
  std::vector<uint8_t> mask(static_cast<size_t>(tiles_wide_) * t);
  for (int ty = 0; ty < tiles_high_; ++ty) {
    for (int tx = 0; tx < tiles_wide_; ++tx) {
      const bool on = hi_[ty * tiles_wide_ + tx] - lo_[ty * tiles_wide_ + tx] >= search_.min_contrast;
      std::fill(mask.begin() + tx * t, mask.begin() + tx * t + t, on ? 255 : 0);
    }
    const uint8_t* __restrict m = mask.data();
    for (int y = ty * t; y < std::min(binary_.rows, ty * t + t); ++y) {
      uint8_t* __restrict out = binary_.ptr<uint8_t>(y);
      for (int x = 0; x < binary_.cols; ++x) out[x] &= m[x];
    }
  }
  return Quads();
}

std::vector<std::array<cv::Point2d, 4>> QuadFinder::Quads() {
  std::vector<std::array<cv::Point2d, 4>> quads;
  // Two levels: components' outer boundaries (no parent) and their holes' boundaries.
  cv::findContours(binary_, contours_, hierarchy_, cv::RETR_CCOMP, cv::CHAIN_APPROX_NONE);
  for (size_t i = 0; i < contours_.size(); ++i) {
    if (hierarchy_[i][3] >= 0) continue;
    const double length = static_cast<double>(contours_[i].size());
    if (length < search_.min_perimeter || length > search_.max_perimeter) continue;
    std::array<cv::Point2d, 4> quad;
    if (QuadFromBoundary(contours_[i], search_, gray_.size(), &quad)) quads.push_back(quad);
  }
  return quads;
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
