#include "detector/candidates.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <opencv2/imgproc.hpp>

namespace mcmt {
namespace {

// Tile minima and maxima over each tile and its 8 neighbours; per pixel, dark if below the mid level.
void MidLevelBinary(const cv::Mat& gray, const QuadSearch& s, cv::Mat* binary) {
  const int t = std::max(1, s.tile_px);
  const int cols = gray.cols, rows = gray.rows;
  const int tw = (cols + t - 1) / t, th = (rows + t - 1) / t;
  std::vector<uint8_t> lo(static_cast<size_t>(tw) * th, 255), hi(static_cast<size_t>(tw) * th, 0);
  for (int y = 0; y < rows; ++y) {
    const uint8_t* row = gray.ptr<uint8_t>(y);
    uint8_t* l = &lo[static_cast<size_t>(y / t) * tw];
    uint8_t* h = &hi[static_cast<size_t>(y / t) * tw];
    for (int tx = 0; tx < tw; ++tx) {
      const int x0 = tx * t, x1 = std::min(cols, x0 + t);
      uint8_t mn = l[tx], mx = h[tx];
      for (int x = x0; x < x1; ++x) mn = std::min(mn, row[x]), mx = std::max(mx, row[x]);
      l[tx] = mn, h[tx] = mx;
    }
  }
  // 3 x 3 tile neighbourhoods: separable, rows then columns.
  std::vector<uint8_t> lo2(lo.size()), hi2(hi.size());
  for (int ty = 0; ty < th; ++ty)
    for (int tx = 0; tx < tw; ++tx) {
      uint8_t mn = 255, mx = 0;
      for (int dx = std::max(0, tx - 1); dx <= std::min(tw - 1, tx + 1); ++dx) {
        mn = std::min(mn, lo[ty * tw + dx]);
        mx = std::max(mx, hi[ty * tw + dx]);
      }
      lo2[ty * tw + tx] = mn, hi2[ty * tw + tx] = mx;
    }
  binary->create(rows, cols, CV_8U);
  std::vector<int16_t> threshold(static_cast<size_t>(cols));
  for (int ty = 0; ty < th; ++ty) {
    // Per pixel column of this tile row: 2 x the mid level, or a value no pixel passes.
    for (int tx = 0; tx < tw; ++tx) {
      uint8_t mn = 255, mx = 0;
      for (int dy = std::max(0, ty - 1); dy <= std::min(th - 1, ty + 1); ++dy) {
        mn = std::min(mn, lo2[dy * tw + tx]);
        mx = std::max(mx, hi2[dy * tw + tx]);
      }
      int16_t value = static_cast<int16_t>(mn + mx);
      if (mx - mn < s.min_contrast) value = s.bright ? 1024 : -1;
      for (int x = tx * t; x < std::min(cols, tx * t + t); ++x) threshold[x] = value;
    }
    for (int y = ty * t; y < std::min(rows, ty * t + t); ++y) {
      const uint8_t* in = gray.ptr<uint8_t>(y);
      uint8_t* out = binary->ptr<uint8_t>(y);
      const int16_t* thr = threshold.data();
      if (s.bright) {
        for (int x = 0; x < cols; ++x) out[x] = 2 * in[x] > thr[x] ? 255 : 0;
      } else {
        for (int x = 0; x < cols; ++x) out[x] = 2 * in[x] < thr[x] ? 255 : 0;
      }
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
  const double diag = cv::norm(diagonal);
  if (d1 / diag < s.min_side_rate * perimeter || d3 / diag < s.min_side_rate * perimeter) return false;
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

std::vector<std::array<cv::Point2d, 4>> FindQuads(const cv::Mat& gray, const QuadSearch& search,
                                                  cv::Mat* binary) {
  CV_Assert(gray.type() == CV_8UC1);
  cv::Mat local;
  cv::Mat& bin = binary ? *binary : local;
  MidLevelBinary(gray, search, &bin);
  std::vector<std::vector<cv::Point>> contours;
  std::vector<cv::Vec4i> hierarchy;
  // Two levels: components' outer boundaries (no parent) and their holes' boundaries.
  cv::findContours(bin, contours, hierarchy, cv::RETR_CCOMP, cv::CHAIN_APPROX_NONE);
  std::vector<std::array<cv::Point2d, 4>> quads;
  for (size_t i = 0; i < contours.size(); ++i) {
    if (hierarchy[i][3] >= 0) continue;
    const double length = static_cast<double>(contours[i].size());
    if (length < search.min_perimeter || length > search.max_perimeter) continue;
    std::array<cv::Point2d, 4> quad;
    if (QuadFromBoundary(contours[i], search, gray.size(), &quad)) quads.push_back(quad);
  }
  return quads;
}

}  // namespace mcmt
