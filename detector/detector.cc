#include "detector/detector.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <opencv2/core/hal/hal.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <stdexcept>

#include "core/dictionary.h"
#include "core/math.h"
#include "detector/aruco_search.h"
#include "detector/candidates.h"
#include "detector/opencv_overrides.h"
#include "detector/side_model.h"

#ifdef __SSE2__
#include <emmintrin.h>
#endif

namespace mcmt {
namespace {

// The largest coordinate Sample interpolates at across `pixels` pixels (the last pixel centre, less 0.001).
inline double LastSampled(int pixels) { return pixels - 1.001; }

// Is (x, y) within 0..max_x, 0..max_y (LastSampled's limits)?
inline bool InsideLimits(double x, double y, double max_x, double max_y) {
  return x >= 0.0 && y >= 0.0 && x <= max_x && y <= max_y;
}

// Is (x, y) inside the area Sample interpolates in?
inline bool Inside(const cv::Mat& gray, double x, double y) {
  return InsideLimits(x, y, LastSampled(gray.cols), LastSampled(gray.rows));
}

// Sample at a point known to be Inside.
inline float SampleInside(const cv::Mat& gray, double x, double y) {
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const float fx = static_cast<float>(x - x0), fy = static_cast<float>(y - y0);
  const uint8_t* r0 = gray.ptr<uint8_t>(y0) + x0;
  const uint8_t* r1 = r0 + gray.step[0];
  const float top = r0[0] + fx * (r0[1] - r0[0]);
  const float bottom = r1[0] + fx * (r1[1] - r1[0]);
  return top + fy * (bottom - top);
}

// Bilinear interpolation of an 8-bit image at (x, y), pixel centres at integer coordinates. Returns
// false outside the image.
inline bool Sample(const cv::Mat& gray, double x, double y, float* value) {
  if (!Inside(gray, x, y)) return false;
  *value = SampleInside(gray, x, y);
  return true;
}

#ifdef __SSE2__
// The 2 x 2 blocks of the pixels at p0 and p1 (rows `step` bytes apart) in the low 8 bytes: p0's top left,
// top right, bottom left, bottom right, then p1's. Each row's two bytes are one 16-bit load inserted into
// its word (pinsrw from memory): the same bytes in the same places as two blocks built in scalar registers
// (top | bottom << 16) and interleaved (_mm_unpacklo_epi32), with 4 instructions less per pair of samples.
inline __m128i PixelBlocks(const uint8_t* p0, const uint8_t* p1, size_t step) {
  uint16_t word[4];
  std::memcpy(&word[0], p0, 2);
  std::memcpy(&word[1], p0 + step, 2);
  std::memcpy(&word[2], p1, 2);
  std::memcpy(&word[3], p1 + step, 2);
  __m128i v = _mm_cvtsi32_si128(word[0]);
  v = _mm_insert_epi16(v, word[1], 1);
  v = _mm_insert_epi16(v, word[2], 2);
  return _mm_insert_epi16(v, word[3], 3);
}

// The SampleInside values at (x[0], y[0]) and (x[1], y[1]) of the image at `data` (rows `step` bytes
// apart) in the two low lanes, by the same operations.
inline __m128 SampleTwoInside(const uint8_t* data, size_t step, __m128d x, __m128d y) {
  const __m128i xi = _mm_cvttpd_epi32(x), yi = _mm_cvttpd_epi32(y), zero = _mm_setzero_si128();
  const __m128 fx = _mm_cvtpd_ps(_mm_sub_pd(x, _mm_cvtepi32_pd(xi)));
  const __m128 fy = _mm_cvtpd_ps(_mm_sub_pd(y, _mm_cvtepi32_pd(yi)));
  const uint8_t* p0 = data + _mm_cvtsi128_si32(yi) * step + _mm_cvtsi128_si32(xi);
  const uint8_t* p1 =
      data + _mm_cvtsi128_si32(_mm_srli_si128(yi, 4)) * step + _mm_cvtsi128_si32(_mm_srli_si128(xi, 4));
  const __m128i blocks = _mm_unpacklo_epi8(PixelBlocks(p0, p1, step), zero);
  const __m128 v0 = _mm_cvtepi32_ps(_mm_unpacklo_epi16(blocks, zero));
  const __m128 v1 = _mm_cvtepi32_ps(_mm_unpackhi_epi16(blocks, zero));
  const __m128 left = _mm_shuffle_ps(v0, v1, _MM_SHUFFLE(2, 0, 2, 0));  // top 0, bottom 0, top 1, bottom 1
  const __m128 right = _mm_shuffle_ps(v0, v1, _MM_SHUFFLE(3, 1, 3, 1));
  const __m128 rows = _mm_add_ps(left, _mm_mul_ps(_mm_unpacklo_ps(fx, fx), _mm_sub_ps(right, left)));
  const __m128 top = _mm_shuffle_ps(rows, rows, _MM_SHUFFLE(2, 0, 2, 0));
  const __m128 bottom = _mm_shuffle_ps(rows, rows, _MM_SHUFFLE(3, 1, 3, 1));
  return _mm_add_ps(top, _mm_mul_ps(fy, _mm_sub_ps(bottom, top)));
}

// The SampleInside values at the four points (x01, y01) (lanes 0, 1) and (x23, y23) (lanes 2, 3) of the
// image at `data`, by the same operations lane by lane (so the same values as SampleTwoInside and
// SampleInside). One sample per float lane: the eight 16-bit rows of the four 2x2 blocks inserted as
// the tops then the bottoms, widened to 32-bit lanes (left pixel | right pixel << 16) and split by a
// mask and a shift, so that each bilinear step is one operation for four samples (SampleTwoInside's
// interleave and its two shuffles per step are gone), and the four pixel offsets y step + x come from one
// pmaddwd instead of four scalar multiplications. bench_detector's 10 accurate frames: SampleRayInside
// 28.26 -> 24.99 M instructions, accurate 288.29 -> 285.02 M (fastfit).
inline __m128 SampleFourInside(const uint8_t* data, size_t step, __m128i offset_weights, __m128d x01,
                               __m128d y01, __m128d x23, __m128d y23) {
  const __m128i xi01 = _mm_cvttpd_epi32(x01), yi01 = _mm_cvttpd_epi32(y01);
  const __m128i xi23 = _mm_cvttpd_epi32(x23), yi23 = _mm_cvttpd_epi32(y23);
  const __m128 fx = _mm_movelh_ps(_mm_cvtpd_ps(_mm_sub_pd(x01, _mm_cvtepi32_pd(xi01))),
                                  _mm_cvtpd_ps(_mm_sub_pd(x23, _mm_cvtepi32_pd(xi23))));
  const __m128 fy = _mm_movelh_ps(_mm_cvtpd_ps(_mm_sub_pd(y01, _mm_cvtepi32_pd(yi01))),
                                  _mm_cvtpd_ps(_mm_sub_pd(y23, _mm_cvtepi32_pd(yi23))));
  // The pixels' offsets y step + x, 32-bit lanes: (x | y << 16) times (1 | step << 16), each pair of
  // 16-bit products added (pmaddwd). Exact where x, y and step are below 2^15 (the caller's check).
  const __m128i xy =
      _mm_or_si128(_mm_unpacklo_epi64(xi01, xi23), _mm_slli_epi32(_mm_unpacklo_epi64(yi01, yi23), 16));
  const __m128i offsets = _mm_madd_epi16(xy, offset_weights);
#ifdef __x86_64__
  // The offsets (non-negative, below 2^31) two at a time through 64-bit registers (sampcost).
  const uint64_t offsets01 = static_cast<uint64_t>(_mm_cvtsi128_si64(offsets));
  const uint64_t offsets23 = static_cast<uint64_t>(_mm_cvtsi128_si64(_mm_unpackhi_epi64(offsets, offsets)));
  const uint8_t* p[4] = {data + static_cast<uint32_t>(offsets01), data + (offsets01 >> 32),
                         data + static_cast<uint32_t>(offsets23), data + (offsets23 >> 32)};
#else
  const uint8_t* p[4] = {data + _mm_cvtsi128_si32(offsets),
                         data + _mm_cvtsi128_si32(_mm_srli_si128(offsets, 4)),
                         data + _mm_cvtsi128_si32(_mm_srli_si128(offsets, 8)),
                         data + _mm_cvtsi128_si32(_mm_srli_si128(offsets, 12))};
#endif
  uint16_t top[4], bottom[4];
  for (int i = 0; i < 4; ++i) {
    std::memcpy(&top[i], p[i], 2);
    std::memcpy(&bottom[i], p[i] + step, 2);
  }
  __m128i v = _mm_cvtsi32_si128(top[0]);
  v = _mm_insert_epi16(v, top[1], 1);
  v = _mm_insert_epi16(v, top[2], 2);
  v = _mm_insert_epi16(v, top[3], 3);
  v = _mm_insert_epi16(v, bottom[0], 4);
  v = _mm_insert_epi16(v, bottom[1], 5);
  v = _mm_insert_epi16(v, bottom[2], 6);
  v = _mm_insert_epi16(v, bottom[3], 7);
  const __m128i zero = _mm_setzero_si128(), low = _mm_set1_epi32(0xffff);
  const __m128i tops = _mm_unpacklo_epi8(v, zero), bottoms = _mm_unpackhi_epi8(v, zero);
  const __m128 top_left = _mm_cvtepi32_ps(_mm_and_si128(tops, low));
  const __m128 top_right = _mm_cvtepi32_ps(_mm_srli_epi32(tops, 16));
  const __m128 bottom_left = _mm_cvtepi32_ps(_mm_and_si128(bottoms, low));
  const __m128 bottom_right = _mm_cvtepi32_ps(_mm_srli_epi32(bottoms, 16));
  const __m128 upper = _mm_add_ps(top_left, _mm_mul_ps(fx, _mm_sub_ps(top_right, top_left)));
  const __m128 lower = _mm_add_ps(bottom_left, _mm_mul_ps(fx, _mm_sub_ps(bottom_right, bottom_left)));
  return _mm_add_ps(upper, _mm_mul_ps(fy, _mm_sub_ps(lower, upper)));
}
#endif

// The image the rays sample, with what SampleRayInside and Inside derive from it, once per side rather
// than once per ray (raycache: 52,000 rays in bench_detector's 10 accurate frames).
struct RayImage {
  explicit RayImage(const cv::Mat& gray)
      : gray(gray),
        data(gray.data),
        step(gray.step[0]),
        max_x(LastSampled(gray.cols)),
        max_y(LastSampled(gray.rows)),
        small(step < 32768 && gray.cols < 32768 && gray.rows < 32768) {
#ifdef __SSE2__
    offset_weights = _mm_set1_epi32(static_cast<int>(1 | (step << 16)));
#endif
  }
  // Inside's test, with its limits computed once.
  bool Inside(double x, double y) const { return InsideLimits(x, y, max_x, max_y); }
  const cv::Mat& gray;
  const uint8_t* data;
  size_t step;
  double max_x, max_y;
  bool small;  // SampleFourInside's offsets are exact
#ifdef __SSE2__
  __m128i offset_weights;  // SampleFourInside's
#endif
};

// Samples at the points origin + (s0 + j ds) direction, begin <= j < end, all Inside, into out[j - begin]
// (SampleInside's values; with SSE2 four at a time by the same operations, two at a time for fewer than four
// samples or an image of 2^15 or more pixels or bytes across).
__attribute__((always_inline)) inline void SampleRayInside(const RayImage& image,
                                                           const Eigen::Vector2d& origin,
                                                           const Eigen::Vector2d& direction, double s0,
                                                           double ds, int begin, int end, float* out) {
#ifdef __SSE2__
  const uint8_t* data = image.data;
  const size_t step = image.step;
  const __m128d first = _mm_set1_pd(s0), width = _mm_set1_pd(ds), two = _mm_set1_pd(2.0);
  const __m128d ox = _mm_set1_pd(origin.x()), oy = _mm_set1_pd(origin.y());
  const __m128d dx = _mm_set1_pd(direction.x()), dy = _mm_set1_pd(direction.y());
  auto at = [&](__m128d js) {  // the two points j = js
    const __m128d s = _mm_add_pd(first, _mm_mul_pd(js, width));
    return SampleTwoInside(data, step, _mm_add_pd(ox, _mm_mul_pd(s, dx)), _mm_add_pd(oy, _mm_mul_pd(s, dy)));
  };
  if (image.small && end - begin >= 4) {
    // Four at a time; the last four end at `end` (overlapping the ones before where the count is not a
    // multiple of four: those samples are written again with the same values).
    const __m128i offset_weights = image.offset_weights;
    auto four_at = [&](int j, __m128d js) {  // js: (j, j + 1)
      const __m128d s01 = _mm_add_pd(first, _mm_mul_pd(js, width));
      const __m128d s23 = _mm_add_pd(first, _mm_mul_pd(_mm_add_pd(js, two), width));
      _mm_storeu_ps(out + j - begin,
                    SampleFourInside(data, step, offset_weights, _mm_add_pd(ox, _mm_mul_pd(s01, dx)),
                                     _mm_add_pd(oy, _mm_mul_pd(s01, dy)), _mm_add_pd(ox, _mm_mul_pd(s23, dx)),
                                     _mm_add_pd(oy, _mm_mul_pd(s23, dy))));
    };
    // (j, j + 1) carried from four to four: whole numbers, the same values as converted from j.
    const __m128d four = _mm_set1_pd(4.0);
    int j = begin;
    __m128d js = _mm_set_pd(j + 1.0, j);
    for (; j + 4 <= end; j += 4, js = _mm_add_pd(js, four)) four_at(j, js);
    if (j < end) four_at(end - 4, _mm_set_pd(end - 3.0, end - 4.0));
    return;
  }
  int j = begin;
  for (__m128d js = _mm_set_pd(j + 1.0, j); j + 1 < end; j += 2, js = _mm_add_pd(js, two))
    _mm_storel_pi(reinterpret_cast<__m64*>(out + j - begin), at(js));
  if (j < end) _mm_store_ss(out + j - begin, at(_mm_set1_pd(j)));
#else
  for (int j = begin; j < end; ++j) {
    const double s = s0 + j * ds;
    out[j - begin] = SampleInside(image.gray, origin.x() + s * direction.x(), origin.y() + s * direction.y());
  }
#endif
}

// Samples at the n points origin + (s0 + j ds) direction, j < n, handed to visit(j, values, count) (the
// values of samples j .. j + count - 1) where inside the image; returns how many were. The points move
// monotonically: both ends inside, all inside, with no check per sample, in runs of up to 64 samples;
// otherwise sample by sample (count 1).
template <class Visit>
int SampleLine(const cv::Mat& gray, int n, const Eigen::Vector2d& origin, const Eigen::Vector2d& direction,
               double s0, double ds, const Visit& visit) {
  auto point = [&](int j) {
    const double s = s0 + j * ds;
    return Eigen::Vector2d(origin.x() + s * direction.x(), origin.y() + s * direction.y());
  };
  const Eigen::Vector2d first = point(0), last = point(n - 1);
  if (Inside(gray, first.x(), first.y()) && Inside(gray, last.x(), last.y())) {
    constexpr int kChunk = 64;
    float values[kChunk];
    for (int j0 = 0; j0 < n; j0 += kChunk) {
      const int count = std::min(kChunk, n - j0);
      SampleRayInside(RayImage(gray), origin, direction, s0, ds, j0, j0 + count, values);
      visit(j0, values, count);
    }
    return n;
  }
  int sampled = 0;
  for (int j = 0; j < n; ++j) {
    const Eigen::Vector2d x = point(j);
    float v;
    if (Sample(gray, x.x(), x.y(), &v)) visit(j, &v, 1), ++sampled;
  }
  return sampled;
}

// Whether SampleLine's n points origin + (s0 + j ds) direction are all inside the image (its first and
// last are: the points move monotonically), by SampleLine's test.
inline bool RayInside(const RayImage& image, int n, const Eigen::Vector2d& origin,
                      const Eigen::Vector2d& direction, double s0, double ds) {
  const double s1 = s0 + (n - 1) * ds;
  return image.Inside(origin.x() + s0 * direction.x(), origin.y() + s0 * direction.y()) &&
         image.Inside(origin.x() + s1 * direction.x(), origin.y() + s1 * direction.y());
}

// The n samples of SampleLine into out[0..n): SampleLine's values where it samples (into `out` directly
// where both ends are inside: no copy), the others left as they were; returns how many were sampled.
inline int SampleLineInto(const RayImage& image, int n, const Eigen::Vector2d& origin,
                          const Eigen::Vector2d& direction, double s0, double ds, float* out) {
  if (RayInside(image, n, origin, direction, s0, ds)) {
    SampleRayInside(image, origin, direction, s0, ds, 0, n, out);
    return n;
  }
  return SampleLine(image.gray, n, origin, direction, s0, ds,
                    [&](int j, const float* v, int count) { std::copy(v, v + count, out + j); });
}

// sum[j] += values[j] for j < n (SSE2: two at a time, each the same addition).
inline void AddToSums(const float* values, int n, double* sum) {
  int j = 0;
#ifdef __SSE2__
  for (; j + 1 < n; j += 2) {
    const __m128d v =
        _mm_cvtps_pd(_mm_castsi128_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(values + j))));
    _mm_storeu_pd(sum + j, _mm_add_pd(_mm_loadu_pd(sum + j), v));
  }
#endif
  for (; j < n; ++j) sum[j] += values[j];
}

// sum[j] += values[j], count[j] += 1 for j < n.
inline void AddSamples(const float* values, int n, double* sum, double* count) {
  AddToSums(values, n, sum);
  for (int j = 0; j < n; ++j) count[j] += 1.0;
}

// Raw image pixels <-> ideal (undistorted) pixels of the same camera; identity without a camera.
struct PixelMap {
  const CameraModel* camera = nullptr;
  Eigen::Vector2d ToImage(const Eigen::Vector2d& u) const {
    if (!camera) return u;
    const double x = (u.x() - camera->cx) / camera->fx, y = (u.y() - camera->cy) / camera->fy;
    double xd, yd;
    camera->Distort(x, y, &xd, &yd);
    return {camera->fx * xd + camera->cx, camera->fy * yd + camera->cy};
  }
  Eigen::Vector2d ToIdeal(const Eigen::Vector2d& p) const { return camera ? camera->Undistort(p) : p; }
};

// The map of `camera` (none: identity; so is a camera without distortion).
PixelMap MapOf(const CameraModel* camera) {
  PixelMap map;
  if (camera && camera->model != DistortionModel::kNone && !camera->distortion.empty()) map.camera = camera;
  return map;
}

// A line n . x = c with |n| = 1, fitted by total least squares with outlier rejection.
struct Line {
  Eigen::Vector2d n;
  double c;
};

bool FitLine(const std::vector<Eigen::Vector2d>& line_points, Line* line) {
  // Working copies held by the thread (FitLine took the points by value and allocated three vectors per
  // round: four allocations per CrossingLine).
  thread_local std::vector<Eigen::Vector2d> points, kept;
  thread_local std::vector<float> abs_res, res_copy;
  points.assign(line_points.begin(), line_points.end());
  for (int round = 0; round < 3; ++round) {
    if (points.size() < 3) return false;
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    for (const auto& p : points) mean += p;
    mean /= static_cast<double>(points.size());
    double sxx = 0, sxy = 0, syy = 0;
    for (const auto& p : points) {
      const Eigen::Vector2d d = p - mean;
      sxx += d.x() * d.x(), sxy += d.x() * d.y(), syy += d.y() * d.y();
    }
    // The normal is perpendicular to the direction of the largest spread.
    const Eigen::Vector2d direction = PrincipalDirection2d(sxx, sxy, syy);
    line->n = Eigen::Vector2d(-direction.y(), direction.x());
    line->c = line->n.dot(mean);
    if (round == 2) break;
    // Residuals; drop those beyond 3 robust sigmas (at least 0.25 px).
    abs_res.resize(points.size());
    for (size_t i = 0; i < points.size(); ++i)
      abs_res[i] = static_cast<float>(std::abs(line->n.dot(points[i]) - line->c));
    res_copy.assign(abs_res.begin(), abs_res.end());
    const double threshold = std::max(0.25, 3.0 * 1.4826 * MedianInPlace(&res_copy));
    kept.clear();
    for (size_t i = 0; i < points.size(); ++i)
      if (abs_res[i] <= threshold) kept.push_back(points[i]);
    if (kept.size() == points.size()) break;
    points.swap(kept);
  }
  return true;
}

bool Intersect(const Line& a, const Line& b, Eigen::Vector2d* p) {
  const double det = a.n.x() * b.n.y() - a.n.y() * b.n.x();
  if (std::abs(det) < 1e-6) return false;
  *p = Eigen::Vector2d((a.c * b.n.y() - b.c * a.n.y()) / det, (a.n.x() * b.c - b.n.x() * a.c) / det);
  return true;
}

// Value of the grid cell (row, col) of the full marker (border included): 1 = differs from the border.
inline int GridCell(const cv::Mat& bits, int cells, int row, int col) {
  if (row <= 0 || col <= 0 || row >= cells - 1 || col >= cells - 1) return 0;
  return bits.at<uint8_t>(row - 1, col - 1) ? 1 : 0;
}

// The homography from the unit square (0,0)-(1,0)-(1,1)-(0,1) to a marker's corners (ArUco order): marker
// coordinates (cells / cells-per-side) to image pixels. It is cv::getPerspectiveTransform(square, quad)
// (OpenCV 4.6, the corners as floats) to the bit: the same 8 x 8 system, entries computed as it computes
// them (products of floats), solved by the LU decomposition cv::solve(DECOMP_LU) calls; a singular
// system gives h[0..7] = 0 as there. Without cv::solve's matrix copies, output allocation and the
// vectors of points: 0.2 M of 33.5 M instructions per 640x480 image (bench/results/2026-12-05-speed7.md).
// The system, for each corner i (x, y: the square's; u, v: the quad's):
//   [x y 1 0 0 0 -x u -y u] h = u,   [0 0 0 x y 1 -x v -y v] h = v,   h[8] = 1.
cv::Matx33d QuadFromUnitSquare(const std::array<cv::Point2d, 4>& corners) {
  static constexpr float kSquare[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  double a[8][8], h[9];
  for (int i = 0; i < 4; ++i) {
    const float x = kSquare[i][0], y = kSquare[i][1];
    const float u = static_cast<float>(corners[i].x), v = static_cast<float>(corners[i].y);
    a[i][0] = a[i + 4][3] = x;
    a[i][1] = a[i + 4][4] = y;
    a[i][2] = a[i + 4][5] = 1;
    a[i][3] = a[i][4] = a[i][5] = a[i + 4][0] = a[i + 4][1] = a[i + 4][2] = 0;
    a[i][6] = -x * u;
    a[i][7] = -y * u;
    a[i + 4][6] = -x * v;
    a[i + 4][7] = -y * v;
    h[i] = u;
    h[i + 4] = v;
  }
  if (!cv::hal::LU64f(&a[0][0], sizeof a[0], 8, h, sizeof h[0], 1)) std::fill(h, h + 8, 0.0);
  h[8] = 1.0;
  return cv::Matx33d(h);
}

// The grey level at every cell centre of the quad `corners` (cells x cells, row-major, border included),
// bilinear through the quad's homography; false where one leaves the image.
bool SampleCellCentres(const cv::Mat& gray, const std::array<cv::Point2d, 4>& corners, int cells,
                       std::vector<float>* values) {
  const cv::Matx33d h = QuadFromUnitSquare(corners);
  values->resize(static_cast<size_t>(cells) * cells);
  for (int row = 0; row < cells; ++row)
    for (int col = 0; col < cells; ++col) {
      const cv::Vec3d p = h * cv::Vec3d((col + 0.5) / cells, (row + 0.5) / cells, 1.0);
      if (!Sample(gray, p[0] / p[2], p[1] / p[2], &(*values)[row * cells + col])) return false;
    }
  return true;
}

// How many of the cells' levels `values` (cells x cells, row-major) read wrong, as CodeMismatches counts.
int LevelMismatches(const std::vector<float>& values, const cv::Mat& bits, int cells) {
  double sum[2] = {0, 0};
  int count[2] = {0, 0};
  for (int row = 0; row < cells; ++row)
    for (int col = 0; col < cells; ++col) {
      const int expected = GridCell(bits, cells, row, col);
      sum[expected] += values[row * cells + col];
      ++count[expected];
    }
  if (count[0] == 0 || count[1] == 0) return cells * cells;
  const double m0 = sum[0] / count[0], m1 = sum[1] / count[1];
  if (std::abs(m1 - m0) < 10.0) return cells * cells;
  int mismatches = 0;
  for (int row = 0; row < cells; ++row)
    for (int col = 0; col < cells; ++col) {
      const float v = values[row * cells + col];
      const int nearer = std::abs(v - m1) < std::abs(v - m0) ? 1 : 0;
      mismatches += nearer != GridCell(bits, cells, row, col);
    }
  return mismatches;
}

// How many cells of the marker's code (border included) read wrong in the quad `corners`: every cell
// centre is sampled through the quad's homography and put with the nearer of the two colour means
// (polarity-free: inverted prints read the same). cells * cells when it cannot be read (a corner outside
// the image, no contrast). A refinement that slid onto another edge (a cell off: the quiet zone's outer
// edge, an inner cell's edge) reads a shifted code: a whole border side and half the inner cells wrong.
int CodeMismatches(const cv::Mat& gray, const std::array<cv::Point2d, 4>& corners, const cv::Mat& bits,
                   int cells) {
  if (bits.empty()) return 0;
  std::vector<float> values;
  if (!SampleCellCentres(gray, corners, cells, &values)) return cells * cells;
  return LevelMismatches(values, bits, cells);
}

// Cells this small or smaller (mean area, px^2) are read unmixed where their centres do not read.
constexpr double kDeconvolvedCellPx2 = 9.0;
// The optics' blur DeconvolvedCells assumes, px: at their true corners, the 11 markers main lost under
// 1.2 px blur read 0-1 inner bits wrong on 10 with 1.0 (0.6: 5, 0.8: 7, 1.2 with ridge 0.3: 4 of 11).
constexpr double kDeconvolutionSigmaPx = 1.0;

// DeconvolvedCells' linear model of the pixels about the quad `corners` (those within half a cell of it):
// their grey levels `observed`, and per pixel (row of `a`) the weight of every cell's level (cells x cells,
// row-major, border included) and last of one level for all outside, each cell's area under a Gaussian of
// `sigma_px` (with the pixel's box) about the pixel (each cell as 3 x 3 points through the quad's
// homography). False where the region leaves the image or has fewer pixels than levels.
using CellMixingRows = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
bool CellMixing(const cv::Mat& gray, const std::array<cv::Point2d, 4>& corners, int cells, double sigma_px,
                CellMixingRows* a, std::vector<double>* observed) {
  constexpr int kSub = 3;  // points per cell and axis
  const double s2 = sigma_px * sigma_px + 1.0 / 12.0, reach = 3.0 * std::sqrt(s2);
  const cv::Matx33d h = QuadFromUnitSquare(corners), unit_from_image = h.inv();
  auto at = [&](double u, double v) {
    const cv::Vec3d p = h * cv::Vec3d(u, v, 1.0);
    return cv::Point2d(p[0] / p[2], p[1] / p[2]);
  };
  const double grow = 0.5 / cells;
  double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
  for (double u : {-grow, 1 + grow})
    for (double v : {-grow, 1 + grow}) {
      const cv::Point2d p = at(u, v);
      x0 = std::min(x0, p.x), x1 = std::max(x1, p.x), y0 = std::min(y0, p.y), y1 = std::max(y1, p.y);
    }
  const int bx = static_cast<int>(std::floor(x0)), by = static_cast<int>(std::floor(y0));
  const int bw = static_cast<int>(std::ceil(x1)) - bx + 1, bh = static_cast<int>(std::ceil(y1)) - by + 1;
  if (bx < 0 || by < 0 || bx + bw > gray.cols || by + bh > gray.rows) return false;
  // The pixels modelled (rows of the system), by their place in the box.
  std::vector<int> row_of(static_cast<size_t>(bw) * bh, -1);
  for (int y = 0; y < bh; ++y)
    for (int x = 0; x < bw; ++x) {
      const cv::Vec3d m = unit_from_image * cv::Vec3d(bx + x, by + y, 1.0);
      const double u = m[0] / m[2], v = m[1] / m[2];
      if (u < -grow || v < -grow || u > 1 + grow || v > 1 + grow) continue;
      row_of[y * bw + x] = static_cast<int>(observed->size());
      observed->push_back(gray.at<uint8_t>(by + y, bx + x));
    }
  const int n = cells * cells + 1, rows = static_cast<int>(observed->size());
  if (rows < n) return false;
  *a = CellMixingRows::Zero(rows, n);
  // scale * exp(-d^2 / (2 s2)) at d = d0, d0 + 1, ...: a product recurrence (the ratio of neighbours
  // falls by exp(-1 / s2) a step).
  const double fall = std::exp(-1.0 / s2);
  auto gaussian = [&](double d0, int count, double scale, std::vector<double>* w) {
    w->resize(std::max(0, count));
    double g = scale * std::exp(-0.5 * d0 * d0 / s2), ratio = std::exp(-(2.0 * d0 + 1.0) / (2.0 * s2));
    for (int i = 0; i < count; ++i) (*w)[i] = g, g *= ratio, ratio *= fall;
  };
  std::vector<double> wx, wy;
  const double step = 1.0 / (cells * kSub);
  for (int cell = 0; cell < cells * cells; ++cell)
    for (int i = 0; i < kSub * kSub; ++i) {
      const double u = ((cell % cells) * kSub + i % kSub + 0.5) * step,
                   v = ((cell / cells) * kSub + i / kSub + 0.5) * step;
      const cv::Point2d p = at(u, v), du = at(u + step, v) - p, dv = at(u, v + step) - p;
      const double area = std::abs(du.x * dv.y - du.y * dv.x) / (2.0 * M_PI * s2);
      const int xa = std::max(0, static_cast<int>(std::ceil(p.x - reach)) - bx),
                xb = std::min(bw - 1, static_cast<int>(std::floor(p.x + reach)) - bx);
      const int ya = std::max(0, static_cast<int>(std::ceil(p.y - reach)) - by),
                yb = std::min(bh - 1, static_cast<int>(std::floor(p.y + reach)) - by);
      gaussian(bx + xa - p.x, xb - xa + 1, 1.0, &wx);
      gaussian(by + ya - p.y, yb - ya + 1, area, &wy);
      for (int y = ya; y <= yb; ++y)
        for (int x = xa; x <= xb; ++x) {
          const int row = row_of[y * bw + x];
          if (row >= 0) (*a)(row, cell) += wy[y - ya] * wx[x - xa];
        }
    }
  for (int row = 0; row < rows; ++row) {
    double covered = 0;  // summed in order: Eigen's sum depends on the row's alignment in memory
    for (int j = 0; j < n - 1; ++j) covered += (*a)(row, j);
    (*a)(row, n - 1) = 1.0 - covered;
  }
  return true;
}

// The least-squares levels x of a x = observed, with a ridge `ridge` toward the observed levels' mean;
// the normal equations' lower triangle from each row's few nonzero weights.
Eigen::VectorXd RidgeLevels(const CellMixingRows& a, const std::vector<double>& observed, double ridge) {
  const int rows = static_cast<int>(a.rows()), n = static_cast<int>(a.cols());
  double mean = 0;
  for (int row = 0; row < rows; ++row) mean += observed[row] / rows;
  Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n);
  std::vector<int> near;
  for (int row = 0; row < rows; ++row) {
    near.clear();
    for (int j = 0; j < n; ++j)
      if (a(row, j) != 0.0) near.push_back(j);
    for (size_t i = 0; i < near.size(); ++i) {
      const double w = a(row, near[i]);
      rhs(near[i]) += w * observed[row];
      for (size_t k = 0; k <= i; ++k) normal(near[i], near[k]) += w * a(row, near[k]);
    }
  }
  for (int j = 0; j < n; ++j) normal(j, j) += ridge, rhs(j) += ridge * mean;
  return normal.selfadjointView<Eigen::Lower>().ldlt().solve(rhs);
}

// The levels of a marker's cells (cells x cells, row-major, border included) unmixed from the pixels
// about the quad `corners` (CellMixing's model), solved by least squares with a small ridge toward the
// pixels' mean. False where the region leaves the image.
bool DeconvolvedCells(const cv::Mat& gray, const std::array<cv::Point2d, 4>& corners, int cells,
                      double sigma_px, std::vector<float>* values) {
  constexpr double kRidge = 0.1;  // toward the mean, in the normal equations' units (weights <= 1)
  CellMixingRows a;
  std::vector<double> observed;
  if (!CellMixing(gray, corners, cells, sigma_px, &a, &observed)) return false;
  const Eigen::VectorXd levels = RidgeLevels(a, observed, kRidge);
  values->resize(static_cast<size_t>(cells) * cells);
  for (int j = 0; j < cells * cells; ++j) (*values)[j] = static_cast<float>(levels(j));
  return true;
}

// The inner neighbours of side `side` (the cells next to its border cells, cells from the side's start
// corner): flags[j] = 1 where cell j differs from the border's colour, for j < cells. Side 0 runs corner
// 0 -> 1 (top, left to right), 1: right side top to bottom, 2: bottom right to left, 3: left bottom to top.
// Read once per SampleSide (CleanNeighbour read them at every ray, with a floor and a cv::Mat::empty
// call per look-up).
void InnerNeighbours(const cv::Mat& bits, int cells, int side, uint8_t* flags) {
  for (int j = 0; j < cells; ++j) {
    int row = 0, col = 0;
    switch (side) {
      case 0:
        row = 1, col = j;
        break;
      case 1:
        row = j, col = cells - 2;
        break;
      case 2:
        row = cells - 2, col = cells - 1 - j;
        break;
      default:
        row = cells - 1 - j, col = 1;
        break;
    }
    flags[j] = static_cast<uint8_t>(GridCell(bits, cells, row, col));
  }
}

// Is the inner neighbour of the side at position u (cells from the side's start corner, 0 <= u) of the
// border's colour, within half a cell either way? `flags`: the side's InnerNeighbours. The cell index is
// clamp(int(u + du), 0, cells - 1): for u + du >= 0 int() is the floor, and for -1 < u + du < 0 both
// clamp to 0.
inline bool CleanNeighbour(const uint8_t* flags, int cells, double u) {
  for (double du : {-0.5, 0.0, 0.5})
    if (flags[std::clamp(static_cast<int>(u + du), 0, cells - 1)]) return false;
  return true;
}

// The medians of the grey levels at the centres of the quad's border cells and of the ring of cells just
// outside it; false where fewer than 4 of either lie in the image.
bool BorderAndRing(const cv::Mat& gray, const std::array<cv::Point2d, 4>& corners, int cells,
                   double* border_level, double* ring_level) {
  const cv::Matx33d h = QuadFromUnitSquare(corners);
  std::vector<float> border, ring;
  for (int i = 0; i < cells; ++i) {
    const double t = (i + 0.5) / cells;
    const double in = 0.5 / cells, out = -0.5 / cells;
    const double pts[8][2] = {{t, in},  {t, 1 - in},  {in, t},  {1 - in, t},
                              {t, out}, {t, 1 - out}, {out, t}, {1 - out, t}};
    for (int k = 0; k < 8; ++k) {
      const cv::Vec3d p = h * cv::Vec3d(pts[k][0], pts[k][1], 1.0);
      float v;
      if (!Sample(gray, p[0] / p[2], p[1] / p[2], &v)) continue;
      (k < 4 ? border : ring).push_back(v);
    }
  }
  if (border.size() < 4 || ring.size() < 4) return false;
  *border_level = Median(std::move(border)), *ring_level = Median(std::move(ring));
  return true;
}

// +1 when the marker's border is darker than the band just outside it (black-on-white print), -1 when
// brighter (inverted), 0 when unclear (BorderAndRing's medians within 5 grey levels).
int MarkerPolarity(const cv::Mat& gray, const std::array<cv::Point2d, 4>& corners, int cells) {
  double b = 0, r = 0;
  if (!BorderAndRing(gray, corners, cells, &b, &r)) return 0;
  if (std::abs(b - r) < 5.0) return 0;
  return b < r ? 1 : -1;
}

// `camera` for the pixels of its images' region `roi` (their own image: the principal point moved).
CameraModel CameraInRegion(const CameraModel& camera, const cv::Rect& roi) {
  CameraModel in_region = camera;
  in_region.cx -= roi.x, in_region.cy -= roi.y;
  in_region.width = roi.width, in_region.height = roi.height;
  return in_region;
}

// The bounding box of `corners` grown by `rate` of its larger side plus `margin_px` on every side,
// within an image of `size`.
cv::Rect GrownBox(const std::array<cv::Point2d, 4>& corners, double rate, double margin_px, cv::Size size) {
  double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
  for (const cv::Point2d& c : corners) {
    x0 = std::min(x0, c.x), x1 = std::max(x1, c.x);
    y0 = std::min(y0, c.y), y1 = std::max(y1, c.y);
  }
  const double grow = rate * std::max(x1 - x0, y1 - y0) + margin_px;
  return cv::Rect(cv::Point(static_cast<int>(std::floor(x0 - grow)), static_cast<int>(std::floor(y0 - grow))),
                  cv::Point(static_cast<int>(std::ceil(x1 + grow)), static_cast<int>(std::ceil(y1 + grow)))) &
         cv::Rect(cv::Point(0, 0), size);
}

std::vector<cv::Point2f> FloatQuad(const std::array<cv::Point2d, 4>& q) {
  std::vector<cv::Point2f> f;
  for (const cv::Point2d& c : q) f.emplace_back(static_cast<float>(c.x), static_cast<float>(c.y));
  return f;
}

// Whether the centre (the corners' mean) of quad `a` lies strictly inside quad `b`.
bool CentreInside(const std::array<cv::Point2d, 4>& a, const std::array<cv::Point2d, 4>& b) {
  cv::Point2d centre(0, 0);
  for (const cv::Point2d& c : a) centre += 0.25 * c;
  return cv::pointPolygonTest(FloatQuad(b),
                              cv::Point2f(static_cast<float>(centre.x), static_cast<float>(centre.y)),
                              false) > 0;
}

// OpenCV's corner refinement of `corners` in place, in a window of about half a cell (1-5 px).
void SubPixelCorners(const cv::Mat& gray, int cells, std::array<cv::Point2d, 4>* corners) {
  std::vector<cv::Point2f> f = FloatQuad(*corners);
  double side = 0;
  for (int k = 0; k < 4; ++k) side += 0.25 * cv::norm((*corners)[(k + 1) % 4] - (*corners)[k]);
  const int half = std::clamp(static_cast<int>(0.5 * side / cells), 1, 5);
  cv::cornerSubPix(gray, f, cv::Size(half, half), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 30, 0.01));
  for (int k = 0; k < 4; ++k) (*corners)[k] = cv::Point2d(f[k].x, f[k].y);
}
}  // namespace

namespace {
// The cell at depth `row` (0: the border) of column `col` (cells from the side's start corner) of side
// `side` (as in CleanNeighbour): 1 when it differs from the border's colour.
int InnerCell(const cv::Mat& bits, int cells, int side, int col, int row) {
  switch (side) {
    case 0:
      return GridCell(bits, cells, row, col);
    case 1:
      return GridCell(bits, cells, col, cells - 1 - row);
    case 2:
      return GridCell(bits, cells, cells - 1 - row, cells - 1 - col);
    default:
      return GridCell(bits, cells, cells - 1 - col, row);
  }
}

// static_cast<int>(std::floor(x)): the truncation, one less where it rounded up (the compiler expands
// std::floor into about 15 instructions on plain x86-64, without SSE4.1's round). Beyond +-2^30 (and for
// NaN) std::floor itself, so that every value is converted as before (raycache).
inline int FloorToInt(double x) {
  if (!(std::abs(x) < 1073741824.0)) return static_cast<int>(std::floor(x));
  const int i = static_cast<int>(x);
  return i - (x < i ? 1 : 0);
}

// Beyond 8.5 sigmas Phi is 1 to double precision and below 1e-17: no exponential.
inline double Phi(double z) {
  if (std::abs(z) > 8.5) return z > 0 ? 1.0 : 0.0;
  double big, small;
  PhiAndDensity(z, &big, &small);
  return big;
}

// Unit-square coordinates of the point `along` the side `side` (0..1 from its start corner) at depth
// `depth` (inward, in units of the marker's side). Inline, and built by Vec3d's three-value constructor
// (braces took its initializer-list one, a loop): CollectSideRays called it 81,172 times in bench_detector's
// 10 accurate frames, 1.1 M instructions out of line (sideray).
inline cv::Vec3d UnitPoint(int side, double along, double depth) {
  switch (side) {
    case 0:
      return cv::Vec3d(along, depth, 1.0);
    case 1:
      return cv::Vec3d(1.0 - depth, along, 1.0);
    case 2:
      return cv::Vec3d(1.0 - along, 1.0 - depth, 1.0);
    default:
      return cv::Vec3d(depth, 1.0 - along, 1.0);
  }
}

// Where a point (ideal pixels) lies along the side `side` of the marker: the unit-square coordinate
// UnitPoint takes as `along` (0..1 from the side's start corner).
// Only the two rows of unit_from_ideal's product that the side uses, and one division (CollectSideRays
// calls it three times per ray; raycache), each row by cv::Matx's product's operations: the same values.
inline double AlongSide(const cv::Matx33d& unit_from_ideal, int side, const Eigen::Vector2d& ideal) {
  auto row = [&](int i) {
    double s = 0;
    s += unit_from_ideal(i, 0) * ideal.x();
    s += unit_from_ideal(i, 1) * ideal.y();
    s += unit_from_ideal(i, 2) * 1.0;
    return s;
  };
  const double w = row(2);
  switch (side) {
    case 0:
      return row(0) / w;
    case 1:
      return row(1) / w;
    case 2:
      return 1.0 - row(0) / w;
    default:
      return 1.0 - row(1) / w;
  }
}

// A line of the marker's grid in ideal pixels, through the unit-square points a and b: a point on it (a's)
// and a normal (as long as the line's image from a to b).
struct GridLine {
  Eigen::Vector2d point, normal;
};
GridLine GridLineThrough(const cv::Matx33d& ideal_from_unit, const cv::Vec3d& a, const cv::Vec3d& b) {
  const cv::Vec3d p0 = ideal_from_unit * a, p1 = ideal_from_unit * b;
  const Eigen::Vector2d a0(p0[0] / p0[2], p0[1] / p0[2]), a1(p1[0] / p1[2], p1[1] / p1[2]);
  return {a0, Eigen::Vector2d(a1.y() - a0.y(), a0.x() - a1.x())};
}

// One ray of a side's model fit: its index among the pass's rays, where it meets the side (`along`, 0..1
// from the side's start corner), the offset from its origin to the line along its normal (`delta`, px),
// and per code row the row's pattern, the depth of the row's outer boundary (px inward from the origin)
// and the part of its level from cells of the other colour under blur along the side.
struct SideRay {
  int index;
  double along;
  double delta;
  std::array<uint8_t, SideProfiles::kRows> pattern;
  std::array<double, SideProfiles::kRows> depths, other;
  // The steps where the ray crosses a column boundary between cells of different colours inside a code
  // row (SideProfiles::RowStep; AddRowSteps).
  std::array<SideProfiles::RowStep, SideProfiles::kMaxRowSteps> row_steps{};
  int row_step_count = 0;
};

// A side's rays (FitSide) and how their profiles are sampled.
struct SideRays {
  const cv::Mat* gray = nullptr;
  const std::vector<Eigen::Vector2d>* origins = nullptr;  // raw pixels
  const std::vector<Eigen::Vector2d>* normals = nullptr;  // outward, raw pixels
  std::vector<SideRay> rays;
  double cell = 0;        // mean depth of the border cell, px
  double u0 = 0, du = 0;  // the profiles' first bin and bin width, px from the line
  int bins = 0;
  bool fit_gamma = false;
  double gamma_hint = 1.0;
  bool hold_gamma = false;
  int polarity = 0;
  double paper = 0;        // SideProfiles::paper
  bool tie_paper = false;  // SideProfiles::tie_paper
  bool skew_pass = false;  // TurnSkewedSides's: TurnSide always takes its three rounds

  // The profiles about the line moved `shift` px outward (the row boundaries' depths are relative to
  // the edge the model places, so they hold at any shift). `half`: -1 every ray, 0 / 1 those before /
  // after `split` along the side. `tilt`: each ray's profile moved a further tilt * (along - split) px
  // outward.
  void SampleProfiles(SideProfiles* profiles, double shift, int half = -1, double split = 0.5,
                      double tilt = 0.0) const {
    profiles->Reset(u0, du, bins, cell);
    profiles->fit_gamma = fit_gamma;
    profiles->gamma_hint = gamma_hint;
    profiles->hold_gamma = hold_gamma;
    profiles->polarity = polarity;
    profiles->paper = paper;
    profiles->tie_paper = tie_paper;
    thread_local std::vector<float> values;
    thread_local std::vector<int> whole_rays;  // per group: its rays inside the image at every bin
    whole_rays.clear();
    const RayImage image(*gray);
    for (size_t r = 0; r < rays.size(); ++r) {
      if (half >= 0 && (rays[r].along >= split) != (half == 1)) continue;
      const int group = profiles->AddRay(rays[r].pattern, rays[r].depths, rays[r].other,
                                         rays[r].row_steps.data(), rays[r].row_step_count);
      const double ox = (*origins)[rays[r].index].x(), oy = (*origins)[rays[r].index].y();
      const double nx = (*normals)[rays[r].index].x(), ny = (*normals)[rays[r].index].y();
      const double first_s = rays[r].delta + shift + tilt * (rays[r].along - split) + u0;
      // The group's profile sums and counts (SideProfiles::Add). A ray inside the image at every bin adds
      // its samples to the sums here and its count to every bin's below, once per group: the same sums
      // in the same order, and the same counts (whole numbers, exact in any order).
      double* sum = &profiles->sum[static_cast<size_t>(group) * bins];
      double* count = &profiles->count[static_cast<size_t>(group) * bins];
      const Eigen::Vector2d origin(ox, oy), normal(nx, ny);
      if (RayInside(image, bins, origin, normal, first_s, du)) {
        values.resize(bins);
        SampleRayInside(image, origin, normal, first_s, du, 0, bins, values.data());
        AddToSums(values.data(), bins, sum);
        if (whole_rays.size() <= static_cast<size_t>(group)) whole_rays.resize(group + 1, 0);
        ++whole_rays[group];
      } else {
        SampleLine(*gray, bins, origin, normal, first_s, du,
                   [&](int j, const float* v, int n) { AddSamples(v, n, sum + j, count + j); });
      }
    }
    for (size_t g = 0; g < whole_rays.size(); ++g) {
      if (whole_rays[g] == 0) continue;
      const double rays_g = whole_rays[g];
      double* count = &profiles->count[g * bins];
      for (int j = 0; j < bins; ++j) count[j] += rays_g;
    }
  }
};

// The ray's colour sequence along its profile (issue 15, bench/results/2026-12-05-rowsteps.md). A ray along
// the side's normal crosses the code's column boundaries obliquely on a sheared quad; where it crosses one
// inside code row r between cells of different colours, the model has one more blurred step there
// (SideProfiles::RowStep), at the crossing's depth along the ray, with the blur across that boundary seen
// along the ray: sigma / sin(angle between the ray and the boundary) (sigma itself: bench_detector's
// 1280x960 fast vs accurate 0.131 px, bench_accuracy median 0.072). The rows with steps take the colour
// where the ray enters them. Without the steps, a wide-cell side of a sheared quad (camera 1 frame 25 id 7
// of bench_detector 30 2 at 1280x960) fitted 7 grey levels rms off, gamma absorbed it in two valleys and
// the start chose one (fast vs accurate 0.423 px). False where the ray leaves the marker through the next
// side within the profiles' reach (taken as 2 cells deep): its samples there are not the code.
// `t`: the ray's distances (ideal px from q along dir) to the row boundaries 1..kRows + 1.
bool AddRowSteps(const std::vector<uint8_t>& row_cells, int cells, int side, const PixelMap& map,
                 const cv::Matx33d& ideal_from_unit, const cv::Matx33d& unit_from_ideal,
                 const Eigen::Vector2d& origin, const Eigen::Vector2d& normal, const Eigen::Vector2d& q,
                 const Eigen::Vector2d& dir, const double* t, SideRay* ray) {
  auto cell_of = [&](int r, int k) { return k >= 0 && k < cells ? row_cells[r * cells + k] : 0; };
  // The column coordinate (cells along the side) of the ray's point at t.
  auto column_at = [&](double at_t) { return AlongSide(unit_from_ideal, side, q + at_t * dir) * cells; };
  // Gates: a ray any of whose crossings meets its boundary at a sine below kMinSin (0.3: at 0-40 deg the
  // median of bench_accuracy --quick stays 0.039 px, 0.042 without) or whose border cell is shallower
  // than kMinCellPx keeps one colour per row. 4 px: without a gate 19 steep markers of bench_accuracy
  // end a cell off and are dropped (recall at 60-75 deg 0.943 -> 0.901); with 3 px the real caliscope
  // board's corners with tone auto came out 0.091 % small per camera on average (0.082 % without steps,
  // test_detector_realdata's bound 0.09 %), with 4 px 0.081 %. A ray under kMinCellPx is also kept
  // when it leaves the marker: dropping those moved the paper rig's plain map from the reference
  // renderer (17 px markers) +0.040 -> +0.052 % (test_mapper_rendered's bound 0.05 %).
  constexpr double kMinSin = 0.3, kMinCellPx = 4.0;
  if (ray->depths[0] < kMinCellPx) return true;  // one colour per row, and kept (as before the steps)
  // What the steps change, to undo them (the whole ray was copied here; sampcost). The ray comes without
  // steps (CollectSideRays' new ray: no steps, all zero).
  const std::array<uint8_t, SideProfiles::kRows> plain_pattern = ray->pattern;
  const std::array<double, SideProfiles::kRows> plain_other = ray->other;
  const double t_max = 2.0 * t[1];
  const double end_column = column_at(t_max);
  if (!std::isfinite(end_column) || end_column < 0.0 || end_column > cells) return false;
  ray->row_step_count = 0;
  for (int r = 1; r <= SideProfiles::kRows && r < cells; ++r) {
    if (t[r] >= t_max) break;
    const double t_out = std::isfinite(t[r + 1]) ? std::min(t[r + 1], t_max) : t_max;
    const double in = column_at(t[r]), out = column_at(t_out);
    if (!std::isfinite(in) || !std::isfinite(out)) return false;
    const int c_in = FloorToInt(in), c_out = FloorToInt(out);
    const int way = c_out > c_in ? 1 : -1;
    bool stepped = false;
    for (int c = c_in; c != c_out; c += way) {
      const int k = way > 0 ? c + 1 : c;  // the column boundary crossed, from column c to c + way
      const double delta = static_cast<double>(cell_of(r, c + way)) - cell_of(r, c);
      if (delta == 0.0 || ray->row_step_count == SideProfiles::kMaxRowSteps) continue;
      // The boundary as a line in ideal pixels, and the ray's distance to it.
      const GridLine boundary =
          GridLineThrough(ideal_from_unit, UnitPoint(side, static_cast<double>(k) / cells, 0.0),
                          UnitPoint(side, static_cast<double>(k) / cells, 1.0));
      const Eigen::Vector2d boundary_normal = boundary.normal.normalized();
      const double den = boundary_normal.dot(dir);
      if (std::abs(den) < 1e-9) continue;
      const double t_k = boundary_normal.dot(boundary.point - q) / den;
      const double sin_angle = std::abs(den);  // |sin| of the angle between the ray and the boundary
      if (sin_angle < kMinSin) {
        // The ray as it came: the steps written here back to zeros, its rows' colours.
        for (int k = 0; k < ray->row_step_count; ++k) ray->row_steps[k] = SideProfiles::RowStep{};
        ray->row_step_count = 0, ray->pattern = plain_pattern, ray->other = plain_other;
        return true;
      }
      SideProfiles::RowStep& step = ray->row_steps[ray->row_step_count++];
      step.row = r;
      step.depth = (origin - map.ToImage(q + t_k * dir)).dot(normal);
      step.delta = delta;
      step.sigma_scale = 1.0 / sin_angle;  // sin_angle >= kMinSin
      stepped = true;
    }
    if (stepped) ray->pattern[r - 1] = cell_of(r, c_in), ray->other[r - 1] = cell_of(r, c_in);
  }
  return true;
}

// The rays of side `side` a model fit uses (FitSide's arguments) into `rays`, and the border cell's mean
// depth (px), or NaN with fewer than 4 rays. Only rays in the middle of a code column are used, away from
// the corners, each followed inward across the marker's rows (`skew_pass`: TurnSkewedSides's).
double CollectSideRays(const cv::Mat& bits, int cells, int side, const PixelMap& map,
                       const cv::Matx33d& ideal_from_unit, const cv::Matx33d& unit_from_ideal,
                       const Line& line, const std::vector<char>& valid,
                       const std::vector<Eigen::Vector2d>& origins,
                       const std::vector<Eigen::Vector2d>& ideal_origins,
                       const std::vector<Eigen::Vector2d>& normals, double sigma_along, bool skew_pass,
                       std::vector<SideRay>* rays) {
  rays->clear();
  double depth_sum = 0;
  // The boundaries between rows r-1 and r (r = 1..kRows + 1) as lines in ideal pixels: a point, a normal.
  GridLine row_boundary[SideProfiles::kRows + 2];
  for (int r = 1; r <= SideProfiles::kRows + 1; ++r)
    row_boundary[r] = GridLineThrough(ideal_from_unit, UnitPoint(side, 0.0, static_cast<double>(r) / cells),
                                      UnitPoint(side, 1.0, static_cast<double>(r) / cells));
  // The cells of rows 1..kRows along the side (InnerCell), read once.
  thread_local std::vector<uint8_t> row_cells;  // row r's cell k at r * cells + k
  row_cells.assign(static_cast<size_t>(SideProfiles::kRows + 1) * cells, 0);
  for (int r = 1; r <= SideProfiles::kRows && r < cells; ++r)
    for (int k = 0; k < cells; ++k)
      row_cells[r * cells + k] = static_cast<uint8_t>(InnerCell(bits, cells, side, k, r));
  auto cell_of = [&](int r, int k) { return k >= 0 && k < cells ? row_cells[r * cells + k] : 0; };
  for (size_t i = 0; i < valid.size(); ++i) {
    if (!valid[i]) continue;
    const Eigen::Vector2d& q = ideal_origins[i];
    const double along = AlongSide(unit_from_ideal, side, q);
    const double a = along * cells;
    const int col = FloorToInt(a);
    const double frac = a - col;
    // Away from the corners (where the perpendicular side's outer edge is near) and the middle of a
    // column (but blur along the side is modelled: `other` below).
    if (col < 1 || col > cells - 2 || frac < 0.1 || frac > 0.9) continue;
    if ((col == 1 && frac < 0.4) || (col == cells - 2 && frac > 0.6)) continue;
    const Eigen::Vector2d on_line_ideal = q - (line.n.dot(q) - line.c) * line.n;
    const Eigen::Vector2d on_line = map.ToImage(on_line_ideal);
    // Built in place at the end of `rays` (removed again where the ray is not used): no copy of it.
    rays->emplace_back();
    SideRay& ray = rays->back();
    ray.index = static_cast<int>(i), ray.along = along, ray.delta = (on_line - origins[i]).dot(normals[i]);
    // Follow the ray inward (in ideal pixels): where it crosses the boundaries of rows 1..kRows + 1
    // (lines of the marker's grid, not parallel to the side under perspective and not crossed at
    // right angles, so the ray drifts across columns), and which column it is in within each row.
    const Eigen::Vector2d dir = (map.ToIdeal(origins[i] - normals[i]) - q).normalized();  // inward
    double t[SideProfiles::kRows + 2];
    t[0] = 0.0;
    for (int r = 1; r <= SideProfiles::kRows + 1; ++r) {
      const double den = row_boundary[r].normal.dot(dir);
      t[r] = std::abs(den) > 1e-12 ? row_boundary[r].normal.dot(row_boundary[r].point - q) / den : NAN;
    }
    bool ok = true;
    for (int r = 1; r <= SideProfiles::kRows && ok; ++r) {
      ok = std::isfinite(t[r]) && t[r] > t[r - 1];
      if (!ok) break;
      // Depth of the boundary between rows r-1 and r, px inward from the ray's origin (raw pixels).
      ray.depths[r - 1] = (origins[i] - map.ToImage(q + t[r] * dir)).dot(normals[i]);
      // The row's column at the middle of its stretch of the ray, and the part of the row's level that
      // comes from cells of the other colour under blur along the side (Gaussian of sigma_along px).
      const double at = AlongSide(unit_from_ideal, side, q + 0.5 * (t[r] + t[r + 1]) * dir) * cells;
      // (Not a number where the ray's point maps to infinity: the ray is not used; casting it is undefined.)
      if (!std::isfinite(at)) {
        ok = false;
        break;
      }
      const int c = FloorToInt(at);
      // Beyond the marker's outline (a ray near an acute corner drifts across the perpendicular side's
      // border into its margin) the row is not the code the model takes it for: in the skew pass
      // (TurnSkewedSides) the ray is not used. (Elsewhere too it would move the corners of passes that
      // settle: fast mode's corners then left the accurate mode's, black tool 3 markers lost.)
      if (skew_pass && (at < 0.0 || at > cells)) {
        ok = false;
        break;
      }
      ray.pattern[r - 1] = static_cast<uint8_t>(r < cells ? cell_of(r, c) : 0);
      const cv::Vec3d c0 = ideal_from_unit * UnitPoint(side, (at - 0.5) / cells, (r + 0.5) / cells);
      const cv::Vec3d c1 = ideal_from_unit * UnitPoint(side, (at + 0.5) / cells, (r + 0.5) / cells);
      // sqrt, not std::hypot (a libm call, 54 instructions; 17 % of its values differ in the last bit from
      // sqrt's): the operands are differences of ideal pixels, far from over- or underflow (raycache).
      const double column_dx = c1[0] / c1[2] - c0[0] / c0[2], column_dy = c1[1] / c1[2] - c0[1] / c0[2];
      const double column_px = std::sqrt(column_dx * column_dx + column_dy * column_dy);
      const double scale = column_px / sigma_along;
      // Phi at the cells' boundaries k - at, each computed once: a cell after one of the other colour
      // takes its first boundary's from there (the same values as a memo of each boundary's, in the same
      // order, without the memo's initialisation and look-ups; sideray).
      double other = 0;
      if (r < cells) {
        const uint8_t* row = &row_cells[r * cells];
        bool have = false;  // phi_k holds Phi at boundary k (cell k - 1 was of the other colour)
        double phi_k = 0;
        for (int k = std::max(0, c - 3); k <= std::min(cells - 1, c + 3); ++k) {
          if (!row[k]) {
            have = false;
            continue;
          }
          if (!have) phi_k = Phi((k - at) * scale);
          const double phi_next = Phi((k + 1 - at) * scale);
          other += phi_next - phi_k;
          phi_k = phi_next, have = true;
        }
      }
      ray.other[r - 1] = other;
    }
    if (ok)
      ok = AddRowSteps(row_cells, cells, side, map, ideal_from_unit, unit_from_ideal, origins[i], normals[i],
                       q, dir, t, &ray);
    if (!ok) {
      rays->pop_back();
      continue;
    }
    depth_sum += ray.depths[0];
  }
  if (rays->size() < 4) return NAN;
  return depth_sum / rays->size();
}

// The side sampled about its line moved `shift` px outward and fitted cold (FitSideProfiles).
bool FitCold(const SideRays& side, double shift, SideProfiles* profiles, SideFit* fit) {
  side.SampleProfiles(profiles, shift);
  fit->warm = false;
  fit->e = 0.0;
  return FitSideProfiles(*profiles, fit);
}

// FitCold about the line moved `*shift` px outward; an edge beyond the profiles' middle (more than 0.75
// cell from their line) is sampled and fitted again about where it was found (*shift moved to it).
bool FitColdAbout(const SideRays& side, double* shift, SideProfiles* profiles, SideFit* fit) {
  if (FitCold(side, *shift, profiles, fit)) return true;
  if (!fit->beyond) return false;
  *shift += fit->beyond_e;
  return FitCold(side, *shift, profiles, fit);
}

// The whole side's model fit about its line (fit->e then px outward from it), false when it fails. A
// previous pass's fit warm-starts it. An edge beyond the profiles' middle (more than 0.75 cell from their
// line: the line a cell inside or outside, on the code's edge or the margin's) is sampled and fitted again
// about where it was found. A fit of the wrong polarity has found an edge with the bright side inward:
// - the border's inner edge, the crossings a cell inside (code white, border dark): the side is sampled
//   and fitted again one cell outward;
// - or the margin's outer edge, the crossings a margin's width outside (a margin narrower than the
//   profiles over a dark surround: black tool). One cell outward the profiles then lie on the surround,
//   and a fit there takes the dark surround for the border and the margin for a code row: its edge shows
//   no step (EdgeHasStep), and the side fitted from there settled outside the marker or failed in every
//   pass, whichever start led there (bench/results/2026-12-06-polarity.md). Then the side is sampled and
//   fitted again half a cell inward (the true edge within 0.75 cell for margins up to 1.25 cells), and
//   that fit is kept where it shows a step.
bool FitWholeSide(const SideRays& side, SideProfiles* profiles, SideFit* fit) {
  side.SampleProfiles(profiles, 0.0);
  // A warm fit keeps the previous pass's other parameters but starts its edge at e = 0, on the line the
  // profiles were just sampled about (this pass's line, not where the previous fit put the edge; starting
  // at the previous offset saved 8 % of evaluations but moved start-dependent markers: speed8).
  if (fit->warm) fit->e = 0.0;
  double shift = 0.0;
  bool ok = FitSideProfiles(*profiles, fit);
  if (ok) DetrendSurround(profiles, fit);  // a face's shade beyond the margin (side_model.h)
  if (!ok && fit->wrong_polarity) {
    const SideFit wrong = *fit;
    shift = side.cell;
    ok = FitColdAbout(side, &shift, profiles, fit);
    if (!ok || !EdgeHasStep(*profiles, *fit)) {
      SideFit inward = wrong;
      double inward_shift = -0.5 * side.cell;
      const bool inward_ok = FitColdAbout(side, &inward_shift, profiles, &inward);
      if (inward_ok && EdgeHasStep(*profiles, inward)) *fit = inward, shift = inward_shift, ok = true;
    }
  } else if (!ok && fit->beyond) {
    shift = fit->beyond_e;
    ok = FitCold(side, shift, profiles, fit);
  }
  if (!ok) {
    fit->warm = false;
    return false;
  }
  fit->warm = true;
  fit->second_step = SecondStepBeyondMargin(*profiles, *fit);
  fit->e += shift;
  return true;
}

// The side's direction from the model (FitSide's `tilt`): each half of the side's rays is sampled about
// the whole side's edge (fit->e) and only its edge fitted; the halves' edges about the line turned by the
// estimate so far give the turn. A turn that moves the side's ends by more than a tenth of a cell is
// re-profiled about the turned line (the whole side fitted again into `fit`, then its halves), at most
// twice. Sets *tilt (px per unit of `along`) and *tilt_at (the rays' mean `along`) unless a half cannot
// be fitted or the turn takes the ends beyond the profiles' reach (1.5 cells).
void TurnSide(const SideRays& side, SideProfiles* profiles, SideFit* fit, double* tilt, double* tilt_at) {
  double split = 0;
  for (const SideRay& ray : side.rays) split += ray.along / side.rays.size();
  double along_half[2];
  for (int half = 0; half < 2; ++half) {
    int n = 0;
    along_half[half] = 0;
    for (const SideRay& ray : side.rays)
      if ((ray.along >= split) == (half == 1)) along_half[half] += ray.along, ++n;
    if (n < 3) return;
    along_half[half] /= n;
  }
  double turn = 0.0;
  for (int round = 0; round < 3; ++round) {
    double e_half[2];
    for (int half = 0; half < 2; ++half) {
      side.SampleProfiles(profiles, fit->e, half, split, turn);
      profiles->edge_only = true;
      SideFit part = *fit;
      part.e = 0.0;
      if (!FitSideProfiles(*profiles, &part)) return;
      e_half[half] = part.e;
    }
    const double step = (e_half[1] - e_half[0]) / (along_half[1] - along_half[0]);
    turn += step;
    if (0.5 * std::abs(turn) > 1.5 * side.cell) return;
    if ((!side.skew_pass && 0.5 * std::abs(step) < 0.1 * side.cell) || round == 2) break;
    side.SampleProfiles(profiles, fit->e, -1, split, turn);
    SideFit again = *fit;
    again.e = 0.0;
    if (!FitSideProfiles(*profiles, &again)) break;
    DetrendSurround(profiles, &again);
    again.e += fit->e;
    *fit = again;
  }
  *tilt = turn;
  *tilt_at = split;
}

// The side model's offset of side `side` (px, outward from `line`), or NaN. The rays (origins and
// outward normals in raw pixels, ideal origins) are those of the crossing pass; only those in the
// middle of a code column are used, grouped by the column's code rows (CollectSideRays). `polarity`: the
// marker's (SideProfiles::polarity); the fit about the line: FitWholeSide.
// The side's direction: `tilt` (optional) gets the model's change of the offset along the side (px per
// unit of `along`, 0..1 from the side's start corner) and `tilt_at` the rays' mean `along`, where the
// offset is the one returned; NaN when the halves cannot be fitted (TurnSide). Each half of the side's
// rays is sampled about the whole side's edge and only its edge fitted (SideProfiles::edge_only): the
// line the crossings (or the current corners) give may be turned a few pixels over a side where the
// crossings mix the outer edge with the code's (a narrow margin on a dark surround, a candidate a cell
// off at one end), and the model only moves it.
double FitSide(const cv::Mat& gray, const cv::Mat& bits, int cells, int side, const PixelMap& map,
               const cv::Matx33d& ideal_from_unit, const cv::Matx33d& unit_from_ideal, const Line& line,
               const std::vector<char>& valid, const std::vector<Eigen::Vector2d>& origins,
               const std::vector<Eigen::Vector2d>& ideal_origins, const std::vector<Eigen::Vector2d>& normals,
               double sigma_along, bool fit_gamma, double gamma_hint, bool hold_gamma, int polarity,
               double paper, SideProfiles* profiles, SideFit* fit, double* tilt = nullptr,
               double* tilt_at = nullptr, bool skew_pass = false) {
  if (tilt) *tilt = NAN;
  if (bits.empty()) return NAN;
  thread_local SideRays rays;
  const double cell = CollectSideRays(bits, cells, side, map, ideal_from_unit, unit_from_ideal, line, valid,
                                      origins, ideal_origins, normals, sigma_along, skew_pass, &rays.rays);
  if (!(cell > 0.5)) return NAN;
  rays.gray = &gray;
  rays.origins = &origins;
  rays.normals = &normals;
  rays.cell = cell;
  rays.du = std::clamp(cell / 4.0, 0.1, 0.5);
  rays.u0 = -(SideProfiles::kRows - 0.4) * cell;
  const double u1 = 1.6 * cell + 1.0;
  rays.bins = static_cast<int>(std::ceil((u1 - rays.u0) / rays.du)) + 1;
  rays.fit_gamma = fit_gamma;
  rays.gamma_hint = gamma_hint;
  rays.hold_gamma = hold_gamma;
  rays.polarity = polarity;
  rays.paper = paper;
  rays.skew_pass = skew_pass;
  rays.tie_paper = false;
  if (!FitWholeSide(rays, profiles, fit)) return NAN;
  // A second step beyond the margin (SecondStepBeyondMargin: a small face's edge or next face, the other
  // marker's margin) is no part of the model: the side is fitted again (warm) with the profiles ending
  // kSecondStepCut cell before the dip (smallface: always with the margin tied to the paper; now where the
  // free refit's margin stays too bright, below). The pentagon's 60-frame video
  // session (diag_session, 1300 sides): +0.053 -> +0.021 px outward; each side ends about where it is
  // without face shading (+0.025 with shading 0 on main; the rest is these cells' own, present on sides
  // with no step beyond). Ending at the dip: +0.028; 0.5 cell before it +0.015 (top and bottom sides -0.003
  // / +0.008 against +0.015 / +0.034 unshaded); the cut alone (margin free) +0.028, the tie alone +0.040.
  // The pentagon's map (bench_imaging_maps' row) -0.728 -> -0.228 %, cameras 7.29 -> 2.32 mm.
  constexpr double kSecondStepCut = 0.3;
  // The refit leaves the margin free first, and ties it only where it stays brighter than the paper
  // (kSecondStepTieExcess; stepfix, bench/results/2026-12-07-stepfix.md: with the collapsed-margin gate
  // in SecondStepBeyondMargin, maps mcmt-sim box +0.025 -> +0.020 %, reference wood +0.417 -> +0.409,
  // mcmt-sim pentagon -0.232 -> -0.240). The tied fit starts from the first fit, as before.
  if (std::isfinite(fit->second_step)) {
    const double end = fit->e + fit->second_step - kSecondStepCut * cell;
    rays.bins = std::min(rays.bins, static_cast<int>(std::ceil((end - rays.u0) / rays.du)) + 1);
    SideFit untied = *fit;
    const bool untied_ok = FitWholeSide(rays, profiles, &untied);
    // Without the paper's level (NaN) the tie has no effect (MarginWeight): the free fit is kept.
    if (!untied_ok || MarginExcessOverPaper(*profiles, untied) > kSecondStepTieExcess) {
      SideFit again = *fit;
      rays.tie_paper = true;
      if (FitWholeSide(rays, profiles, &again)) *fit = again;
    } else {
      *fit = untied;
    }
  }
  if (tilt) TurnSide(rays, profiles, fit, tilt, tilt_at);
  return fit->e;
}

// The profiles across one side in one refinement pass (SampleSide): `n` rays along the side, each
// sampled at `m` steps of `ds` px from -h to +h px along its outward normal.
struct SideSamples {
  int n = 0, m = 0;
  double h = 0, ds = 0;
  std::vector<float> profiles;  // n x m
  std::vector<Eigen::Vector2d> origins, ideal_origins, normals;
  std::vector<char> valid, clean;
  int num_clean = 0, num_valid = 0;
};

// Samples the profiles across side `side` of the corners `img` (raw pixels; `ideal`: undistorted;
// `centre`: their mean) in pass `pass` of a refinement (RefineOnce). False with fewer than 4 rays.
bool SampleSide(const cv::Mat& gray, const cv::Mat& bits, int cells, const PixelMap& map,
                const std::array<Eigen::Vector2d, 4>& img, const std::array<Eigen::Vector2d, 4>& ideal,
                const Eigen::Vector2d& centre, int side, int pass, bool model_pass, double first_width,
                SideSamples* s) {
  const Eigen::Vector2d a = ideal[side], b = ideal[(side + 1) % 4];
  const Eigen::Vector2d dir = (b - a).normalized();
  const double length_img = (img[(side + 1) % 4] - img[side]).norm();
  const double cell_along = length_img / cells;
  // Cell depth across the edge: the marker's extent along this side's normal / cells.
  const Eigen::Vector2d side_dir = (img[(side + 1) % 4] - img[side]) / length_img;
  const Eigen::Vector2d side_normal(side_dir.y(), -side_dir.x());
  const double extent = 0.5 * (std::abs(side_normal.dot(img[(side + 2) % 4] - img[side])) +
                               std::abs(side_normal.dot(img[(side + 3) % 4] - img[side])));
  const double cell = extent / cells;
  // Half-width of the profile across the edge: half a cell, so that the level read on each side
  // is the border's and the surround's, not the next cell's. The first pass searches wider (the
  // initial corners may be a pixel or two off).
  s->h = pass == 0
             ? std::clamp(std::min(0.9 * cell * first_width, 2.0 * first_width), 0.75, 3.0 * first_width)
             : std::clamp(0.5 * cell, 0.75, 3.0);
  const double margin = std::min(0.3, std::max(0.6 * cell_along, 1.5) / length_img);
  // Model passes sample a fixed number of rays and steps (4 per cell, 5 per half-profile): their
  // sampling then moves continuously with the estimate, so the passes converge to one place
  // whatever the start.
  s->n =
      model_pass ? 4 * cells : std::clamp(static_cast<int>((1.0 - 2.0 * margin) * length_img / 0.7), 6, 240);
  const int steps = model_pass ? 5 : std::max(3, static_cast<int>(std::ceil(s->h / 0.25)));
  s->m = 2 * steps + 1;
  s->ds = s->h / steps;
  const int n = s->n, m = s->m;
  s->profiles.assign(static_cast<size_t>(n) * m, 0.f);
  // (Every ray's origin, ideal origin and normal is set below: no zeros first.)
  s->origins.resize(n);
  s->ideal_origins.resize(n);
  s->normals.resize(n);
  s->clean.assign(n, 0);
  s->valid.assign(n, 0);
  s->num_clean = 0, s->num_valid = 0;
  // Without a camera every ray's tangent is dir normalized again (as it was, once for all rays).
  Eigen::Vector2d dir_tangent = dir;
  dir_tangent.normalize();
  // Without the marker's bits every ray is clean.
  const bool no_bits = bits.empty();
  thread_local std::vector<uint8_t> neighbours;
  neighbours.resize(cells);
  if (!no_bits) InnerNeighbours(bits, cells, side, neighbours.data());
  const RayImage image(gray);
  for (int i = 0; i < n; ++i) {
    const double t = margin + (1.0 - 2.0 * margin) * (i + 0.5) / n;
    const Eigen::Vector2d q = a + t * (b - a);
    const Eigen::Vector2d p = map.ToImage(q);
    Eigen::Vector2d tangent = dir_tangent;
    if (map.camera) {
      tangent = map.ToImage(q + 0.5 * dir) - map.ToImage(q - 0.5 * dir);
      tangent.normalize();
    }
    Eigen::Vector2d normal(tangent.y(), -tangent.x());
    if (normal.dot(p - centre) < 0) normal = -normal;
    s->origins[i] = p;
    s->ideal_origins[i] = q;
    s->normals[i] = normal;
    float* prof = &s->profiles[static_cast<size_t>(i) * m];
    if (SampleLineInto(image, m, p, normal, -s->h, s->ds, prof) < m) continue;
    s->valid[i] = 1;
    ++s->num_valid;
    s->clean[i] = no_bits || CleanNeighbour(neighbours.data(), cells, t * cells) ? 1 : 0;
    s->num_clean += s->clean[i];
  }
  return s->num_valid >= 4;
}

// The line (ideal pixels) through the side's crossings of the mid level between its profiles' inner
// and outer levels (`level_in`, `level_out`: medians over the rays next to clean code cells where there
// are enough of them), false when the levels differ by less than 8 grey levels (no clean crossing: a
// margin narrower than the profile between a dark border and a dark surround, or the candidate a pixel
// or two off) or fewer than 4 rays cross.
bool CrossingLine(const SideSamples& s, const PixelMap& map, Line* line, double* level_in,
                  double* level_out) {
  thread_local std::vector<float> inside, outside;
  thread_local std::vector<Eigen::Vector2d> points;
  const int n = s.n, m = s.m;
  const bool use_clean = s.num_clean >= std::max(4, s.num_valid / 5);
  inside.clear();
  outside.clear();
  for (int i = 0; i < n; ++i) {
    if (!s.valid[i] || (use_clean && !s.clean[i])) continue;
    inside.push_back(s.profiles[static_cast<size_t>(i) * m]);
    outside.push_back(s.profiles[static_cast<size_t>(i) * m + m - 1]);
  }
  *level_in = MedianInPlace(&inside), *level_out = MedianInPlace(&outside);
  if (!(std::abs(*level_out - *level_in) >= 8.0)) return false;
  const float mid = static_cast<float>(0.5 * (*level_in + *level_out));
  const float sign = *level_out > *level_in ? 1.f : -1.f;  // (v - mid) * sign goes - to + outward
  points.clear();
  for (int i = 0; i < n; ++i) {
    if (!s.valid[i] || (use_clean && !s.clean[i])) continue;
    const float* prof = &s.profiles[static_cast<size_t>(i) * m];
    // Crossing of the mid level (inside -> outside direction) nearest to the profile's centre: the
    // steps j with v_j <= 0 < v_j+1, v = (prof - mid) * sign, in order of j.
    double best = 1e9;
    auto value = [&](int j) { return (prof[j] - mid) * sign; };
    auto take = [&](int j) {
      const float v0 = value(j), v1 = value(j + 1);
      const double at = -s.h + (j + v0 / (v0 - v1)) * s.ds;
      if (std::abs(at) < std::abs(best)) best = at;
    };
    if (m <= 64) {
      // Every sample's sign bits at once (SSE2: four at a time, the same float operations), then the
      // crossings from the bits: v_j <= 0 (bit j of at_or_below) and v_j+1 > 0 (bit j + 1 of above).
      uint64_t at_or_below = 0, above = 0;
      int j = 0;
#ifdef __SSE2__
      const __m128 mids = _mm_set1_ps(mid), signs = _mm_set1_ps(sign), zero = _mm_setzero_ps();
      auto four_at = [&](int j0) {  // the bits of samples j0 .. j0 + 3
        const __m128 v = _mm_mul_ps(_mm_sub_ps(_mm_loadu_ps(prof + j0), mids), signs);
        at_or_below |= static_cast<uint64_t>(_mm_movemask_ps(_mm_cmple_ps(v, zero))) << j0;
        above |= static_cast<uint64_t>(_mm_movemask_ps(_mm_cmpgt_ps(v, zero))) << j0;
      };
      for (; j + 4 <= m; j += 4) four_at(j);
      // The last four end at m (overlapping the ones before: those bits are set again, the same).
      if (j < m && m >= 4) four_at(m - 4), j = m;
#endif
      for (; j < m; ++j) {
        const float v = value(j);
        at_or_below |= static_cast<uint64_t>(v <= 0.f) << j;
        above |= static_cast<uint64_t>(v > 0.f) << j;
      }
      for (uint64_t crossings = at_or_below & (above >> 1) & ((uint64_t{1} << (m - 1)) - 1); crossings;
           crossings &= crossings - 1)
        take(__builtin_ctzll(crossings));
    } else {
      for (int j = 0; j + 1 < m; ++j)
        if (value(j) <= 0.f && value(j + 1) > 0.f) take(j);
    }
    if (best > 1e8) continue;
    points.push_back(map.ToIdeal(s.origins[i] + best * s.normals[i]));
  }
  return points.size() >= 4 && FitLine(points, line);
}

// The gamma of the marker's other sides (their latest fits with gamma free), for a side whose code
// shows no contrast in its first rows; 1 without one.
double OtherSidesGamma(const std::array<SideFit, 4>& side_fits, int side) {
  double gamma_sum = 0;
  int gamma_count = 0;
  for (int other = 0; other < 4; ++other)
    if (other != side && side_fits[other].warm && side_fits[other].gamma_fitted)
      gamma_sum += side_fits[other].gamma, ++gamma_count;
  return gamma_count > 0 ? gamma_sum / gamma_count : 1.0;
}

// Side `side`'s line moved `e` px outward (from the centre of the corners `ideal`); with a finite `tilt`
// (FitSide) also turned: the line through the side's points at along 0 and 1 (on the line, the marker's
// homography's points projected), moved by the offsets the tilt gives there.
void MoveLine(const std::array<Eigen::Vector2d, 4>& ideal, const cv::Matx33d& ideal_from_unit, int side,
              double e, double tilt, double tilt_at, Line* line) {
  Eigen::Vector2d ideal_centre = Eigen::Vector2d::Zero();
  for (int k = 0; k < 4; ++k) ideal_centre += ideal[k] / 4.0;
  const double outward = line->n.dot(ideal_centre) < line->c ? 1.0 : -1.0;
  if (!std::isfinite(tilt)) {
    line->c += outward * e;
    return;
  }
  Eigen::Vector2d q[2];
  for (int end = 0; end < 2; ++end) {
    const cv::Vec3d u = ideal_from_unit * UnitPoint(side, end, 0.0);
    const Eigen::Vector2d x(u[0] / u[2], u[1] / u[2]);
    q[end] = x - (line->n.dot(x) - line->c) * line->n + outward * (e + tilt * (end - tilt_at)) * line->n;
  }
  const Eigen::Vector2d d = (q[1] - q[0]).normalized();
  Eigen::Vector2d n(-d.y(), d.x());
  if (n.dot(line->n) < 0) n = -n;
  *line = {n, n.dot(q[0])};
}

// The corners (raw pixels) where consecutive sides' lines (ideal pixels) meet; false where two are
// parallel.
bool CornersFromLines(const std::array<Line, 4>& lines, const PixelMap& map,
                      std::array<Eigen::Vector2d, 4>* corners) {
  for (int k = 0; k < 4; ++k) {
    Eigen::Vector2d p;
    if (!Intersect(lines[(k + 3) % 4], lines[k], &p)) return false;
    (*corners)[k] = map.ToImage(p);
  }
  return true;
}

// One refinement's state across its passes (RefineOnce).
struct Refinement {
  Refinement(const cv::Mat& gray, const cv::Mat& bits, int cells, const PixelMap& map, bool model_fit,
             bool fit_gamma, double held_gamma, int polarity, double first_width, bool* kept_lines)
      : gray(gray),
        bits(bits),
        cells(cells),
        map(map),
        model_fit(model_fit),
        fit_gamma(fit_gamma),
        held_gamma(held_gamma),
        polarity(polarity),
        first_width(first_width),
        kept_lines(kept_lines) {
    side_moved.fill(std::numeric_limits<double>::infinity());
  }
  const cv::Mat& gray;
  const cv::Mat& bits;
  int cells;
  const PixelMap& map;
  bool model_fit, fit_gamma;
  double held_gamma;  // > 0: the camera's gamma, known, held in every side's model
  int polarity;
  double first_width;
  bool* kept_lines;
  std::array<Eigen::Vector2d, 4> img;  // the corners, raw pixels
  SideSamples samples;
  SideProfiles side_profiles;
  std::array<SideFit, 4> side_fits;  // each side's model fit of the previous model pass
  // Sides of the latest pass located neither by crossings nor by the model (they kept their line).
  std::array<bool, 4> side_unfitted{};
  std::array<bool, 4> side_modelled{};  // located by the side model in the latest pass
  // How far each side's line moved in the latest model pass (px, at its corners; infinite before one).
  std::array<double, 4> side_moved;
  bool skew_turn = false;  // the model turns the sides of a skewed quad (SkewTurnWeight; TurnSkewedSides)
  double blur_cells = 0;   // the refinement's fitted blur sigma in cells of the quad (SkewTurnWeight)
  double paper = 0;        // the paper's level, read once per refinement (MarkerPaperLevel); 0: unknown
  // A crossing pass's crossing line beyond its profiles is no crossing (LineWithinProfiles).
  bool lines_within_profiles = false;
  double sigma_sum = 0;
  int sigma_count = 0;
};

// A quad's corners as OpenCV points.
std::array<cv::Point2d, 4> CvQuad(const std::array<Eigen::Vector2d, 4>& q) {
  return {cv::Point2d(q[0].x(), q[0].y()), cv::Point2d(q[1].x(), q[1].y()), cv::Point2d(q[2].x(), q[2].y()),
          cv::Point2d(q[3].x(), q[3].y())};
}

// The paper's level of a normal print (the code's other colour), linear, from the inner cells of the quad
// `corners` (bits: the code; `cells` with the border), under a Gaussian blur of `sigma_px` and the encoding
// gamma `gamma` (1: linear). The value at cell k's centre (SampleCellCentres, linearised as
// 255 (v / 255)^gamma) is v_k = B + (P - B) w_k, w_k the part of the blur about the centre on cells of the
// other colour: over its 5 x 5 neighbourhood, in the quad's cell units at its centre (blur covariance
// sigma^2 (J^T J)^-1, J the homography's Jacobian there, its diagonal taken), separable:
//   w_k = sum over (dr, dc) of colour(dr, dc) g_row(dr) g_col(dc),
//   g(d) = Phi((d + 1/2) / s) - Phi((d - 1/2) / s)   (a cell's box under the blur, s in cells).
// B is the mean of the cells with w <= 0.2, P the mean of (v_k - (1 - w_k) B) / w_k over those with
// w >= 0.8 (where a blur wider than the model's moves it least); over the cells whose neighbourhood lies
// within the outline. 0 (unknown) where no cell reaches either or a centre leaves the image.
double PaperLevel(const cv::Mat& gray, const std::array<Eigen::Vector2d, 4>& corners, const cv::Mat& bits,
                  int cells, double sigma_px, double gamma) {
  if (bits.empty() || cells < 6 || !(sigma_px > 0)) return 0.0;
  const std::array<cv::Point2d, 4> quad = CvQuad(corners);
  thread_local std::vector<float> values;
  if (!SampleCellCentres(gray, quad, cells, &values)) return 0.0;
  // The homography's Jacobian at the quad's centre, per cell (px per cell along each of its axes):
  // x = (h0 . u) / (h2 . u), dx/du_i = (h0_i - x h2_i) / (h2 . u).
  const cv::Matx33d h = QuadFromUnitSquare(quad);
  const cv::Vec3d mid = h * cv::Vec3d(0.5, 0.5, 1.0);
  const double x = mid[0] / mid[2], y = mid[1] / mid[2];
  Eigen::Matrix2d px_from_cell;
  for (int i = 0; i < 2; ++i)
    px_from_cell(0, i) = (h(0, i) - x * h(2, i)) / mid[2] / cells,
                    px_from_cell(1, i) = (h(1, i) - y * h(2, i)) / mid[2] / cells;
  const Eigen::Matrix2d cell_covariance =
      sigma_px * sigma_px * (px_from_cell.transpose() * px_from_cell).inverse();
  if (!(cell_covariance(0, 0) > 0) || !(cell_covariance(1, 1) > 0)) return 0.0;
  double g_col[5], g_row[5];
  const double s_col = std::sqrt(cell_covariance(0, 0)), s_row = std::sqrt(cell_covariance(1, 1));
  for (int d = -2; d <= 2; ++d)
    g_col[d + 2] = Phi((d + 0.5) / s_col) - Phi((d - 0.5) / s_col),
              g_row[d + 2] = Phi((d + 0.5) / s_row) - Phi((d - 0.5) / s_row);
  constexpr double kPaperWhite = 0.8;
  double white_sum = 0, black_sum = 0;
  int whites = 0, blacks = 0;
  thread_local std::vector<std::pair<double, double>> white_cells;  // (w, linear value)
  white_cells.clear();
  for (int row = 2; row < cells - 2; ++row)
    for (int col = 2; col < cells - 2; ++col) {
      double other = 0, total = 0;
      for (int dr = -2; dr <= 2; ++dr)
        for (int dc = -2; dc <= 2; ++dc) {
          const double g = g_row[dr + 2] * g_col[dc + 2];
          total += g, other += GridCell(bits, cells, row + dr, col + dc) * g;
        }
      const double w = other / total;
      const double value = 255.0 * PowInline(values[row * cells + col] / 255.0, gamma);
      if (w >= kPaperWhite) white_cells.emplace_back(w, value);
      if (w <= 1.0 - kPaperWhite) black_sum += value, ++blacks;
    }
  if (white_cells.empty() || blacks == 0) return 0.0;
  const double border = black_sum / blacks;
  for (const auto& [w, value] : white_cells) white_sum += (value - (1.0 - w) * border) / w, ++whites;
  return white_sum / whites;
}

// The blur MarkerPaperLevel reads the paper with, times the sides' largest. paperexcess: 1.3 took the black
// tool's map to +0.040 % but plain to -0.231 % and webcam to -0.202 %; 1.0 (its "M1") is kept here.
constexpr double kPaperBlurFactor = 1.0;

// The paper's level (PaperLevel) of a normal print at the refinement's current corners in the image's
// units (encoded again with the gamma it was read with: each side's model takes it to linear light with
// its own gamma, SideProfiles::paper), with the blur kPaperBlurFactor times the largest of the sides' latest
// fits (the fits of cells a pixel deep find too little) and the gamma their mean (the known gamma where
// held; 1 on linear images); 0 on other prints and before any side has been fitted.
double MarkerPaperLevel(const Refinement& r) {
  if (r.polarity <= 0) return 0.0;
  double sigma = 0, gamma_sum = 0;
  int gammas = 0;
  for (const SideFit& fit : r.side_fits) {
    if (!fit.warm) continue;
    sigma = std::max(sigma, fit.sigma);
    if (fit.gamma_fitted) gamma_sum += fit.gamma, ++gammas;
  }
  if (!(sigma > 0)) return 0.0;  // no side fitted yet (a fit's blur is at least 0.15 px)
  double gamma = 1.0;
  if (r.fit_gamma) gamma = r.held_gamma > 0 ? r.held_gamma : gammas > 0 ? gamma_sum / gammas : 1.0;
  const double linear = PaperLevel(r.gray, r.img, r.bits, r.cells, kPaperBlurFactor * sigma, gamma);
  return linear > 0 ? 255.0 * PowInline(linear / 255.0, 1.0 / gamma) : 0.0;
}

thread_local RefinementCounts refinement_counts;  // RefinementCountsOnThisThread

// A side's choice between the side model's valleys, made by a cold fit and kept by the warm fits after
// it (FitSideModels, side_model.cc): one surround level or a margin, and the margin's width q (px).
struct SurroundChoice {
  bool single = false;
  double margin = 0;
};
using SurroundChoices = std::array<SurroundChoice, 4>;

// Whether two refinements' sides made the same choices: the same surround model on every side, and
// margins within kSameMarginPx (a valley jump moves a margin by a cell or more: the margin widths of
// one marker's sides came out 1 to 20 px).
constexpr double kSameMarginPx = 0.5;
bool SameChoices(const SurroundChoices& a, const SurroundChoices& b) {
  for (int k = 0; k < 4; ++k)
    if (a[k].single != b[k].single || (!a[k].single && std::abs(a[k].margin - b[k].margin) > kSameMarginPx))
      return false;
  return true;
}

// The line of side `side` through the corners `ideal`.
Line LineThrough(const std::array<Eigen::Vector2d, 4>& ideal, int side) {
  const Eigen::Vector2d dir = (ideal[(side + 1) % 4] - ideal[side]).normalized();
  const Eigen::Vector2d normal(-dir.y(), dir.x());
  return {normal, normal.dot(ideal[side])};
}

// A side whose line moved less than this in a model pass (px, at its corners) is settled: the next
// model passes of the refinement keep its line and fit (LocateSide) while the other sides go on. Its
// next fit would move it by about a fifth of that (the passes converge linearly).
constexpr double kSideSettledPx = 3e-4;

// How far side `side` of the quad `ideal` is turned by the model (LocateSide) where its crossings alone
// would give its direction: 0 to 1 as the larger |cosine| of the quad's angles at the side's ends grows
// from kSkewTurnFrom to kSkewTurnFull (smoothly: the corners must not depend on the start; angles below
// 53 to 37 deg), both less kSkewTurnBlurShift where the blur is a large part of a cell (below). On a quad
// that skewed (views beyond about 65 deg with the tilt's axis off the sides) the crossings' line turns its
// end at the acute angle inward: the perpendicular side's border and margin lie within the blur and the rows'
// reach there, and the code cells next to the border are narrower than the blur
// (bench/results/2026-12-05-steep.md, 2026-12-05-steep2.md). Below, the crossings' direction is the better
// one (their rays are twice the halves' the model turns by): from 0.3 / 0.5 the median corner errors of
// ImagingCatalogueOnReferenceRenders grew by 0.01-0.025 px, and from 0.5 / 0.7 the caliscope board's camera 1
// under tone auto came out +0.269 % in size (DetectorRealData, bound 0.2 %; 0.6 / 0.8: +0.186 %). Blurred,
// the crossings' bias at an acute angle reaches smaller skews: the perpendicular side's border lies within
// the blur of the side's crossings near that end. Under the catalogue's gaussian blur 1.2 (fitted sigma
// 0.52-0.66 cell on 15-22 px markers) the acute angles of markers at 50-60 deg came out 1.6 deg too square,
// the long diagonal -1.3 % and the map +0.212 % (gamma 2.2 with blur 0.8, 0.40-0.54 cell: +0.145
// %). With `blur_cells` (the fitted sigma in cells of the quad) from kSkewBlurFrom to kSkewBlurFull the
// onset moves by kSkewTurnBlurShift (angles below 84 to 73 deg), smoothly; a shift of 0.4 (78 to 66 deg)
// left the blur map at +0.060 % (the acute angles of 70-80 deg still 0.55 deg too square), 0.5 gives
// +0.036 % (gamma 2.2: +0.055 / +0.025 %). Sharp reference renders fit 0.30-0.38 cell (plain), larger
// markers less: their corners stay as they were (bench/results/2026-12-06-blurrow.md).
constexpr double kSkewTurnFrom = 0.6, kSkewTurnFull = 0.8;
constexpr double kSkewBlurFrom = 0.38, kSkewBlurFull = 0.48, kSkewTurnBlurShift = 0.5;
double SkewTurnWeight(const std::array<Eigen::Vector2d, 4>& ideal, int side, double blur_cells) {
  const double shift = kSkewTurnBlurShift * SmoothStep(blur_cells, kSkewBlurFrom, kSkewBlurFull);
  double skew = 0;
  for (int k : {side, (side + 1) % 4}) {
    const Eigen::Vector2d a = (ideal[(k + 3) % 4] - ideal[k]).normalized();
    const Eigen::Vector2d b = (ideal[(k + 1) % 4] - ideal[k]).normalized();
    skew = std::max(skew, std::abs(a.dot(b)));
  }
  return SmoothStep(skew, kSkewTurnFrom - shift, kSkewTurnFull - shift);
}

// Whether a crossing line `line` lies within the profiles it was found in: at both of side `side`'s
// corners `ideal`, its distance |n . x - c| to the corner x is at most `h` (the profiles' half-width, px).
// Every crossing lies within h of the side, so a line beyond h at a corner was extrapolated from
// crossings of different edges: on a half-cell margin over a dark surround, the border's edge on some
// rays and the code's or the margin's far edge on others. Such first-pass lines, turned 3-4 px at one
// end, led the model passes of 10 of the dark grey map's 12 unrefined markers (13-19 px) 5-45 px off,
// beyond the refinement's limit, and cornerSubPix left them 0.66 px inward per side
// (bench/results/2026-12-06-darkland.md). Such a side keeps its line in that pass (where asked: the
// retry of a refinement that failed, RefineMarkerCorners).
bool LineWithinProfiles(const std::array<Eigen::Vector2d, 4>& ideal, int side, const Line& line, double h) {
  for (const Eigen::Vector2d& x : {ideal[side], ideal[(side + 1) % 4]})
    if (!(std::abs(line.n.dot(x) - line.c) <= h)) return false;
  return true;
}

// Side `side`'s line in pass `pass` (its crossings', or with the model its model offset about them or
// about the current side), false when it cannot be located without the model or has too few rays.
bool LocateSide(Refinement* r, const std::array<Eigen::Vector2d, 4>& ideal,
                const cv::Matx33d& ideal_from_unit, const cv::Matx33d& unit_from_ideal,
                const Eigen::Vector2d& centre, int side, int pass, bool model_pass, Line* line) {
  if (model_pass && !r->skew_turn && r->side_modelled[side] && r->side_fits[side].warm &&
      r->side_moved[side] < kSideSettledPx) {
    *line = LineThrough(ideal, side);
    r->sigma_sum += r->side_fits[side].sigma, ++r->sigma_count;
    return true;
  }
  SideSamples& s = r->samples;
  if (!SampleSide(r->gray, r->bits, r->cells, r->map, r->img, ideal, centre, side, pass, model_pass,
                  r->first_width, &s))
    return false;
  double level_in, level_out;
  const bool crossed =
      CrossingLine(s, r->map, line, &level_in, &level_out) &&
      (model_pass || !r->lines_within_profiles || LineWithinProfiles(ideal, side, *line, s.h));
  // Without a clean crossing (or, where asked, in a crossing pass with a crossing line beyond the
  // profiles: LineWithinProfiles) the side keeps the line through the current corners. A model pass fits
  // its edge from there (its profiles reach over border, margin and surround); without the model it
  // fails.
  if (!crossed) {
    if (!r->model_fit) return false;
    *line = LineThrough(ideal, side);
  }
  r->side_unfitted[side] = !crossed;
  if (!crossed && r->kept_lines) *r->kept_lines = true;
  if (!model_pass) return true;
  SideFit& fit = r->side_fits[side];
  const double sigma_along = fit.warm ? fit.sigma : 0.8;
  // The line's direction is the crossings' where their levels have the marker's polarity (the border's
  // side darker for a normal print: the outer edge). Without a crossing, or with levels of the other
  // order (the crossings mix the code's edge in: the line lies up to a cell inside along part of the
  // side), the model turns the line too. So it does on the sides of a skewed quad in the skew pass
  // (TurnSkewedSides).
  const bool turn_line = !crossed || (r->polarity != 0 && (level_out - level_in) * r->polarity < 0);
  const double turn_weight = turn_line      ? 1.0
                             : r->skew_turn ? SkewTurnWeight(ideal, side, r->blur_cells)
                                            : 0.0;
  double tilt = NAN, tilt_at = 0.5;
  // A known gamma (held_gamma > 0) is held on every side.
  const double gamma_hint = r->held_gamma > 0 ? r->held_gamma : OtherSidesGamma(r->side_fits, side);
  ++refinement_counts.side_fits;
  const double e = FitSide(r->gray, r->bits, r->cells, side, r->map, ideal_from_unit, unit_from_ideal, *line,
                           s.valid, s.origins, s.ideal_origins, s.normals, sigma_along, r->fit_gamma,
                           gamma_hint, r->held_gamma > 0, r->polarity, r->paper, &r->side_profiles, &fit,
                           turn_weight > 0 ? &tilt : nullptr, &tilt_at, r->skew_turn);
  r->side_modelled[side] = std::isfinite(e);
  if (!std::isfinite(e)) return true;
  r->side_unfitted[side] = false;
  tilt *= turn_weight;
  MoveLine(ideal, ideal_from_unit, side, e, tilt, tilt_at, line);
  r->sigma_sum += fit.sigma, ++r->sigma_count;
  return true;
}

// One pass of a refinement: every side located (LocateSide) and the corners where their lines meet
// into `next`; false when a side or a corner fails.
bool RefinePass(Refinement* r, int pass, bool model_pass, std::array<Eigen::Vector2d, 4>* next) {
  std::array<Eigen::Vector2d, 4> ideal;
  for (int k = 0; k < 4; ++k) ideal[k] = r->map.ToIdeal(r->img[k]);
  const cv::Matx33d ideal_from_unit = QuadFromUnitSquare(CvQuad(ideal));
  const cv::Matx33d unit_from_ideal = ideal_from_unit.inv();
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  for (int k = 0; k < 4; ++k) centre += r->img[k] / 4.0;
  // Read once per refinement, after the sides' first fits.
  if (model_pass && !(r->paper > 0)) r->paper = MarkerPaperLevel(*r);
  std::array<Line, 4> lines;
  for (int side = 0; side < 4; ++side)
    if (!LocateSide(r, ideal, ideal_from_unit, unit_from_ideal, centre, side, pass, model_pass, &lines[side]))
      return false;
  for (int side = 0; side < 4 && model_pass; ++side) {
    const Line& l = lines[side];
    r->side_moved[side] =
        std::max(std::abs(l.n.dot(ideal[side]) - l.c), std::abs(l.n.dot(ideal[(side + 1) % 4]) - l.c));
  }
  if (model_pass) ++refinement_counts.model_passes;
  return CornersFromLines(lines, r->map, next);
}

// The distance between two points of the refinement (ideal pixels) or of the image.
double Distance(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return (a - b).norm(); }
double Distance(const cv::Point2d& a, const cv::Point2d& b) { return cv::norm(a - b); }

// The sum of quad `q`'s four sides.
template <typename Point>
double QuadPerimeter(const std::array<Point, 4>& q) {
  double perimeter = 0;
  for (int k = 0; k < 4; ++k) perimeter += Distance(q[(k + 1) % 4], q[k]);
  return perimeter;
}

// The largest distance of a corner of `to` from the same corner of `from`.
template <typename Point>
double MaxCornerMove(const std::array<Point, 4>& from, const std::array<Point, 4>& to) {
  double moved = 0;
  for (int k = 0; k < 4; ++k) moved = std::max(moved, Distance(to[k], from[k]));
  return moved;
}

// One refinement from `corners` (RefineMarkerCorners). `model_everywhere` (with model_fit): every side
// was located by the side model in the last pass (not by its crossings alone). `model_only` (with
// model_fit): no crossing-only passes, for corners already on the edges (RefineMarkerCorners).
// `lines_within_profiles` (with model_fit): a crossing line beyond its profiles is no crossing
// (LineWithinProfiles). `choices` (optional): the sides' surround choices of the last model pass.
// `settled` (optional): the model passes ended by moving the corners less than their limit (not at
// kMaxModelPasses, where the corners are the mean of the last two passes).
// Passes of crossing-based line fits (`passes`; without the model until the corners move less than
// 0.01 px, at most `passes` + 4): they find each side's direction and bring the profiles onto the edges.
// Then passes that also fit the side model (detector/side_model.h) to each side: its offset replaces the
// crossings' (each with the cell depths of the previous one's corners), at least two (one in a
// model-only round), until the corners move less than `settled_px` (at most kMaxModelPasses); a side
// whose line has settled (kSideSettledPx) keeps it meanwhile: where the search started
// (the candidate, the previous frame) must not change where the corners end up. Passes that do not
// settle are mostly a two-cycle (a poorly modelled side whose warm-started fits alternate between two
// valleys: 0.2 px apart on a 40 px marker at 74 deg); which of its two states the last pass is in
// depends on the start, their mean does not: the corners are the mean of the last two passes then.
bool RefineOnce(const cv::Mat& gray, int cells, const cv::Mat& bits, const CameraModel* camera, int passes,
                std::array<cv::Point2d, 4>* corners, bool model_fit, double* blur_sigma, double first_width,
                bool model_only, bool fit_gamma, bool* kept_lines, int polarity, bool* model_everywhere,
                double held_gamma, bool lines_within_profiles = false, SurroundChoices* choices = nullptr,
                bool* settled = nullptr) {
  CV_Assert(model_fit || !model_only);
  CV_Assert(model_fit || !lines_within_profiles);
  if (blur_sigma) *blur_sigma = NAN;
  CV_Assert(gray.type() == CV_8UC1);
  const PixelMap map = MapOf(camera);
  Refinement r(gray, bits, cells, map, model_fit, fit_gamma, held_gamma, polarity, first_width, kept_lines);
  r.lines_within_profiles = lines_within_profiles;
  for (int k = 0; k < 4; ++k) r.img[k] = Eigen::Vector2d((*corners)[k].x, (*corners)[k].y);
  const std::array<Eigen::Vector2d, 4> original = r.img;
  const double perimeter = QuadPerimeter(r.img);
  if (!(perimeter > 4 * 4.0)) return false;
  constexpr int kMaxModelPasses = 6;
  // A model-only round (RefineMarkerCorners) starts from corners settled by the passes before it: its
  // first (cold) pass moving them less than kRoundSettledPx ends it (a second pass moved them by 1e-4 to
  // 1e-3 px more: bench/results/2026-12-05-speed4.md).
  constexpr double kRoundSettledPx = 0.004;
  // The first refinement's model passes only bring the corners near the edges, and the model-only
  // rounds after it (RefineMarkerCorners) settle them from fits started cold: those passes stop at
  // kFirstSettledPx (kRoundSettledPx as the rounds: 7.56 passes per marker in bench_detector; 0.02 px:
  // 7.05; 0.01 and 0.03 px: 7.15 and 7.20; 0.05 px: 7.39, the rounds then moving the corners by more
  // than their own limit more often: bench/results/2026-12-05-fewerfits.md).
  constexpr double kFirstSettledPx = 0.02;
  const double settled_px = model_only ? kRoundSettledPx : kFirstSettledPx;
  const int min_model_passes = model_only ? 1 : 2;
  bool converged = false, model_converged = false;
  int model_passes = 0;
  const int max_passes = std::max(1, passes) + 4;
  std::array<Eigen::Vector2d, 4> previous = r.img;  // the corners before the latest pass
  for (int pass = model_only ? 1 : 0;; ++pass) {
    // With the side model, `passes` crossing passes are enough: they only need to bring the profiles
    // onto the edges (the model passes fix the offsets, and their crossings the directions).
    const bool crossings_done =
        model_only || pass >= max_passes || (pass >= std::max(1, passes) && (converged || model_fit));
    if (crossings_done && (!model_fit || model_converged || model_passes >= kMaxModelPasses)) break;
    if (crossings_done) r.sigma_sum = 0, r.sigma_count = 0;  // the last model pass's blur is reported
    const bool model_pass = crossings_done && model_fit;
    std::array<Eigen::Vector2d, 4> next;
    if (!RefinePass(&r, pass, model_pass, &next)) return false;
    const double moved = MaxCornerMove(r.img, next);
    converged = moved < 0.01;
    previous = r.img;
    r.img = next;
    if (model_pass) ++model_passes;
    model_converged = model_pass && model_passes >= min_model_passes && moved < settled_px;
  }
  if (settled) *settled = model_fit && model_converged;
  if (choices)
    for (int side = 0; side < 4; ++side)
      (*choices)[side] = {r.side_fits[side].single_surround, r.side_fits[side].margin_width()};
  std::array<Eigen::Vector2d, 4>& img = r.img;
  if (model_fit && !model_converged && model_passes >= 2)
    for (int k = 0; k < 4; ++k) img[k] = 0.5 * (img[k] + previous[k]);
  if (model_everywhere) {
    *model_everywhere = model_fit;
    for (int side = 0; side < 4; ++side) *model_everywhere = *model_everywhere && r.side_modelled[side];
  }
  for (int side = 0; side < 4; ++side)
    if (r.side_unfitted[side]) return false;
  const double limit = std::max(3.0, 0.2 * perimeter / 4.0);
  for (int k = 0; k < 4; ++k) {
    if (!std::isfinite(img[k].x()) || !std::isfinite(img[k].y()) || (img[k] - original[k]).norm() > limit)
      return false;
  }
  *corners = CvQuad(img);
  if (blur_sigma && r.sigma_count > 0) *blur_sigma = r.sigma_sum / r.sigma_count;
  return true;
}

// The corners of a refinement's end `corners` with the sides of a skewed quad turned by the model
// (SkewTurnWeight, with `blur_px` the refinement's fitted blur sigma, NaN: none): one model pass to start
// the fits from the profiles about them, then kSkewPasses that
// also turn those sides; false (corners unchanged) when the quad is not skewed or a pass fails. A fixed
// number of passes, not passes until the corners settle: turned by the model, a skewed side's line has
// two fixed points on some markers (no margin on grey, 25.6 px at 71 deg: 0.65 px apart), and which one
// passes that settle reach depends on where they start (fast mode's candidates are not the accurate
// mode's). These passes start from the refinement's end, which does not depend on the start, and in
// them TurnSide always takes its three rounds (no choice that jumps with the corners).
constexpr int kSkewPasses = 2;
bool TurnSkewedSides(const cv::Mat& gray, int cells, const cv::Mat& bits, const CameraModel* camera,
                     std::array<cv::Point2d, 4>* corners, bool fit_gamma, int polarity, double held_gamma,
                     double blur_px) {
  std::array<Eigen::Vector2d, 4> ideal;
  const PixelMap map = MapOf(camera);
  for (int k = 0; k < 4; ++k) ideal[k] = map.ToIdeal(Eigen::Vector2d((*corners)[k].x, (*corners)[k].y));
  const double blur_cells = std::isfinite(blur_px) ? blur_px * 4.0 * cells / QuadPerimeter(ideal) : 0.0;
  double weight = 0;
  for (int side = 0; side < 4; ++side) weight = std::max(weight, SkewTurnWeight(ideal, side, blur_cells));
  if (weight <= 0) return false;
  Refinement r(gray, bits, cells, map, true, fit_gamma, held_gamma, polarity, 1.0, nullptr);
  r.blur_cells = blur_cells;
  for (int k = 0; k < 4; ++k) r.img[k] = Eigen::Vector2d((*corners)[k].x, (*corners)[k].y);
  for (int pass = 1; pass <= 1 + kSkewPasses; ++pass) {
    r.skew_turn = pass >= 2;
    std::array<Eigen::Vector2d, 4> next;
    if (!RefinePass(&r, pass, true, &next)) return false;
    r.img = next;
  }
  for (int k = 0; k < 4; ++k)
    if (r.side_unfitted[k] || !std::isfinite(r.img[k].x()) || !std::isfinite(r.img[k].y())) return false;
  *corners = CvQuad(r.img);
  return true;
}

// Whether each of `end`'s corners lies within kMaxMoveCells cells of `start`'s (a cell: the start quad's
// mean side / `cells`):
//   max_k |end_k - start_k| <= kMaxMoveCells * perimeter(start) / (4 cells).
// Each refinement limits its own move (RefineOnce: max(3 px, 1.6 cells)), but the model-only rounds and
// the skew pass of RefineMarkerCorners each start where the one before ended, so their moves add up. A
// candidate lies on its marker's outline to a pixel; corners that end cells from it have left the marker
// (with a third code row in the side model, wood seed 51 image 3 id 155 of the start probe ended 12.5 px
// from its start and from the truth: bench/results/2026-12-06-row3.md, 2026-12-06-blurrow.md).
constexpr double kMaxMoveCells = 2.0;
bool EndsNearItsStart(const std::array<cv::Point2d, 4>& start, const std::array<cv::Point2d, 4>& end,
                      int cells) {
  return MaxCornerMove(start, end) <= kMaxMoveCells * QuadPerimeter(start) / (4.0 * cells);
}
}  // namespace

RefinementCounts RefinementCountsOnThisThread() { return refinement_counts; }

bool RefineMarkerCorners(const cv::Mat& gray, int cells, const cv::Mat& bits, const CameraModel* camera,
                         int passes, std::array<cv::Point2d, 4>* corners, bool model_fit, double* blur_sigma,
                         bool fit_gamma, bool* kept_lines, int polarity, double held_gamma) {
  if (kept_lines) *kept_lines = false;
  // A candidate quadrilateral a few pixels off (a corner cut by the threshold) can leave a side's
  // first profiles entirely on one side of the edge: retry with first profiles twice as wide. So can a
  // candidate a pixel off on a marker of cells barely a pixel deep (15 px at 65 deg): the crossings lock
  // onto the border's inner edge, the model cannot reach the outer edge from there and the side keeps
  // its crossing line, a cell inside (2.4 px off in fast mode, whose candidate was one pixel from the
  // accurate mode's). With the model, a refinement where some side was not located by it is retried
  // wide too, and the wide one is taken where the model located every side.
  std::array<cv::Point2d, 4> narrow = *corners;
  double narrow_sigma = NAN;
  bool narrow_kept = false, narrow_modelled = false;
  SurroundChoices narrow_choices, wide_choices, held_choices;
  const bool narrow_ok =
      RefineOnce(gray, cells, bits, camera, passes, &narrow, model_fit, &narrow_sigma, 1.0, false, fit_gamma,
                 &narrow_kept, polarity, &narrow_modelled, held_gamma, false, &narrow_choices);
  // The model passes' fits are warm-started from the previous pass's: they keep the margin and surround
  // their first fit found where the profiles show several that fit (a margin beyond the profiles' reach
  // or as wide as the blur, a dark surround: the margin widths of one marker's sides came out 1 to 20
  // px), and that first fit was made about corners that depend on the candidate (fast mode's region
  // search gives another one). So the corners are refined again from where the passes ended, with model
  // passes only and the fits started from the profiles about those corners, until such a round moves
  // no corner by kSettledPx (at most kRounds; 0.01 px left fast mode's corners of a wood-mounted marker at
  // 70 deg 0.018 px from the accurate mode's, which the skew pass took to 0.024). Rounds that do not
  // settle are mostly a two-cycle (a side whose cold fit alternates between two margins); which state
  // the last round is in depends on the start, the mean of the last two does not. A round whose sides
  // made the same surround choices as the refinement before it (SameChoices: its cold fits found the
  // valleys the warm ones had kept) has not jumped between states; it only converged further, and ends
  // the rounds at kRepeatSettledPx, or at kRepeatConvergedPx where its own passes also settled (within
  // kRoundSettledPx, not at their cap): a cold start from the corners found the same valleys and the
  // same fixed point. Measured on bench_accuracy --quick (bench/results/2026-12-07-fewerpasses.md): after
  // such a round of 0.01-0.02 px the next moved the corners by a median 0.0003 px (4 of 102 by more than
  // 0.005 px, none by 0.02 px); after one that ended at the passes' cap, 8 of 72 by more than 0.005 px.
  // -0.9 % of the accurate mode's instructions. Measured before on bench_detector (issue 15,
  // bench/results/2026-12-07-passes.md): every round that moved more than kSettledPx repeated its choices; 3
  // of 4 such second rounds are saved, -2.0 % of the accurate mode's instructions; bench_accuracy --quick's
  // corners within 0.0001 px of before on average (7 of 1442 markers more than 0.005 px, the largest 0.022
  // px). Last, the sides of a skewed quad are turned by the model (TurnSkewedSides).
  auto take = [&](std::array<cv::Point2d, 4> c, double sigma, bool kept, SurroundChoices choices) {
    constexpr int kRounds = 4;
    constexpr double kSettledPx = 0.005, kRepeatSettledPx = 0.01, kRepeatConvergedPx = 0.02;
    std::array<cv::Point2d, 4> before = c;
    int unsettled = 0;
    for (int round = 0; round < kRounds && model_fit; ++round) {
      std::array<cv::Point2d, 4> again = c;
      double again_sigma = NAN;
      bool again_kept = false;
      SurroundChoices again_choices;
      bool again_settled = false;
      ++refinement_counts.rounds;
      if (!RefineOnce(gray, cells, bits, camera, passes, &again, true, &again_sigma, 1.0, true, fit_gamma,
                      &again_kept, polarity, nullptr, held_gamma, false, &again_choices, &again_settled))
        break;
      const double moved = MaxCornerMove(c, again);
      const bool repeated = SameChoices(choices, again_choices);
      const double repeated_px = again_settled ? kRepeatConvergedPx : kRepeatSettledPx;
      before = c;
      c = again, sigma = again_sigma, kept = again_kept, choices = again_choices;
      if (moved < kSettledPx || (repeated && moved < repeated_px)) {
        unsettled = 0;
        break;
      }
      ++unsettled;
    }
    if (unsettled >= 2)
      for (int k = 0; k < 4; ++k) c[k] = 0.5 * (c[k] + before[k]);
    if (model_fit) TurnSkewedSides(gray, cells, bits, camera, &c, fit_gamma, polarity, held_gamma, sigma);
    const bool ok = EndsNearItsStart(*corners, c, cells);
    if (ok) *corners = c;
    if (blur_sigma) *blur_sigma = ok ? sigma : NAN;
    if (kept_lines) *kept_lines = kept;
    return ok;
  };
  if (narrow_ok && (narrow_modelled || !model_fit))
    return take(narrow, narrow_sigma, narrow_kept, narrow_choices);
  std::array<cv::Point2d, 4> wide = *corners;
  double wide_sigma = NAN;
  bool wide_kept = false, wide_modelled = false;
  const bool wide_ok =
      RefineOnce(gray, cells, bits, camera, passes, &wide, model_fit, &wide_sigma, 2.0, false, fit_gamma,
                 &wide_kept, polarity, &wide_modelled, held_gamma, false, &wide_choices);
  if (wide_ok && (wide_modelled || !narrow_ok))
    return take(wide, wide_sigma, wide_kept || (!narrow_ok && narrow_kept), wide_choices);
  if (narrow_ok) return take(narrow, narrow_sigma, narrow_kept, narrow_choices);
  // Neither located every side within the limit: with the model, once more from the candidate with the
  // crossing lines held within their profiles (LineWithinProfiles). Only here: held in every refinement,
  // a crossing line of a candidate cut by the threshold, rightly beyond its profiles at one corner, was
  // held too (a 14.6 px marker at 59 deg 0.31 -> 1.57 px off on the dark grey map).
  std::array<cv::Point2d, 4> held = *corners;
  double held_sigma = NAN;
  bool held_kept = false;
  if (model_fit && RefineOnce(gray, cells, bits, camera, passes, &held, true, &held_sigma, 1.0, false,
                              fit_gamma, &held_kept, polarity, nullptr, held_gamma, true, &held_choices))
    return take(held, held_sigma, held_kept || narrow_kept || wide_kept, held_choices);
  if (blur_sigma) *blur_sigma = NAN;
  if (kept_lines) *kept_lines = narrow_kept || wide_kept;
  return false;
}

// ---------------------------------------------------------------------------------------------------

MarkerDetector::MarkerDetector(const MarkerConfig& markers, const DetectorOptions& options)
    : markers_(markers), options_(options) {
  LinkOpenCvOverrides();  // cv::aruco::detectMarkers' calls reach mcmt's cheaper definitions
  options_.Validate();
  if (options_.tone == "auto") tone_ = std::make_unique<ToneEstimator>();
  dictionary_ = LoadDictionary(markers.dictionary);
  bits_.resize(dictionary_->bytesList.rows);
  // Rejected candidates are read again only where a random pattern is rarely taken for an id: the
  // chance that one lies within the correction margin of any id in any rotation below 1e-3 (DICT_6X6_250
  // at error_correction_rate 0.6: 1.1e-4; DICT_4X4_*: 3e-3 to 0.06, never), and not for inverted markers
  // (their dark inner areas are candidates too).
  const int n = dictionary_->markerSize * dictionary_->markerSize;
  const int correctable = static_cast<int>(dictionary_->maxCorrectionBits * options_.error_correction_rate);
  double within = 0, binomial = 1;  // sum over k <= correctable of C(n, k)
  for (int k = 0; k <= correctable; ++k) within += binomial, binomial = binomial * (n - k) / (k + 1);
  const double chance = within * 4.0 * dictionary_->bytesList.rows / std::pow(2.0, n);
  reread_ = options_.reread_rejected && !options_.inverted && chance < 1e-3;
  // The own search reads every quad it finds: a border cell of the other colour only where random
  // patterns are rarely ids.
  // Eight of the 28 border cells of DICT_6X6 (blurred markers read their thin border's cells next to
  // white code cells as white: 7 and 8 on two markers OpenCV finds, bench_accuracy's blur 1.2 and webcam;
  // OpenCV allows 12, 35 % of the 36 inner cells).
  own_border_errors_ = chance < 1e-3 ? 8 : 0;
}

MarkerDetector::~MarkerDetector() = default;

void MarkerDetector::SetCamera(const CameraModel& camera) { camera_ = std::make_unique<CameraModel>(camera); }

const cv::Mat& MarkerDetector::MarkerBits(int id) {
  cv::Mat& bits = bits_[id];
  if (bits.empty())
    bits = cv::aruco::Dictionary::getBitsFromByteList(dictionary_->bytesList.rowRange(id, id + 1),
                                                      dictionary_->markerSize);
  return bits;
}

void MarkerDetector::Reset() {
  last_.clear();
  frames_since_full_ = 0;
}

std::vector<MarkerDetector::Raw> MarkerDetector::Search(const cv::Mat& gray, const cv::Rect& roi,
                                                        double min_perimeter, double max_perimeter,
                                                        int window_min, int window_max) {
  if (options_.candidate_search == "own" && options_.corner_refinement == "edges" && !options_.aruco3 &&
      !options_.inverted && !markers_.inverted)
    return OwnSearch(gray, roi, min_perimeter, max_perimeter);
  cv::Ptr<cv::aruco::DetectorParameters> p = cv::aruco::DetectorParameters::create();
  // Inverted prints only (markers.inverted): searched as dark-bordered markers of the negated image.
  // OpenCV's detectInvertedMarker sees a white-bordered marker only as the hole of the dark ring around
  // it, a contour that breaks where the ring is thin (a ChArUco board's one-cell ring at steep views).
  const bool negated = options_.inverted && markers_.inverted;
  const bool whole = roi.area() == gray.rows * gray.cols;
  cv::Mat view;
  if (negated)
    cv::bitwise_not(whole ? gray : gray(roi), view);  // a new image: `gray` stays as it is
  else
    view = whole ? gray : gray(roi).clone();
  const double side = std::max(view.cols, view.rows);
  p->adaptiveThreshWinSizeMin = window_min;
  p->adaptiveThreshWinSizeMax = window_max;
  p->adaptiveThreshWinSizeStep = options_.adaptive_window_step;
  p->adaptiveThreshConstant = options_.adaptive_constant;
  p->minMarkerPerimeterRate = min_perimeter / side;
  p->maxMarkerPerimeterRate = max_perimeter / side;
  p->polygonalApproxAccuracyRate = options_.polygonal_approx_rate;
  p->minCornerDistanceRate = options_.min_corner_distance_rate;
  // With OpenCV's detectInvertedMarker its grouping is what pairs a quad with the one just inside it (it
  // reads the smaller as a white-bordered marker): its default is kept there (0.01 gave wrong ids on
  // DICT_4X4_1000, DetectorAccuracy.InvertedMarkers). The negated image's markers are dark-bordered
  // ones in a white margin, searched as the plain search does (0.05 lost a 51 px marker of an inverted
  // print there, as it loses markers with narrow margins:
  // DetectorAccuracy.InvertedPrintsMarginIsNotTheMarker).
  p->minMarkerDistanceRate = options_.inverted && !negated ? std::max(0.05, options_.min_marker_distance_rate)
                                                           : options_.min_marker_distance_rate;
  p->minDistanceToBorder = options_.min_distance_to_border;
  p->errorCorrectionRate = options_.error_correction_rate;
  p->perspectiveRemovePixelPerCell = options_.perspective_pixels_per_cell;
  p->perspectiveRemoveIgnoredMarginPerCell = options_.perspective_ignored_margin;
  p->detectInvertedMarker = options_.inverted && !negated;
  p->useAruco3Detection = options_.aruco3;
  p->minSideLengthCanonicalImg = options_.aruco3_min_side;
  if (options_.corner_refinement == "subpix") {
    p->cornerRefinementMethod = cv::aruco::CORNER_REFINE_SUBPIX;
    p->cornerRefinementWinSize = options_.subpix_window;
  } else if (options_.corner_refinement == "contour") {
    p->cornerRefinementMethod = cv::aruco::CORNER_REFINE_CONTOUR;
  } else {
    p->cornerRefinementMethod = cv::aruco::CORNER_REFINE_NONE;
  }
  std::vector<ArucoQuad> corners, rejected;
  std::vector<int> ids;
  // mcmt's own detectMarkers where it takes these parameters (the same lists; aruco_search.h), else OpenCV's.
  if (!DetectMarkersAsOpenCV(view, *dictionary_, *p, &corners, &ids, &rejected)) {
    std::vector<std::vector<cv::Point2f>> found, others;
    {
      const ArucoContourFloor floor(p->minMarkerPerimeterRate, p->minSideLengthCanonicalImg);
      cv::aruco::detectMarkers(view, dictionary_, found, ids, p, others);
    }
    auto quads = [](const std::vector<std::vector<cv::Point2f>>& in, std::vector<ArucoQuad>* out) {
      out->resize(in.size());
      for (size_t i = 0; i < in.size(); ++i) std::copy_n(in[i].begin(), 4, (*out)[i].begin());
    };
    quads(found, &corners);
    quads(others, &rejected);
  }
  std::vector<Raw> out;
  out.reserve(ids.size());
  for (size_t i = 0; i < ids.size(); ++i) {
    if (!markers_.Accepts(ids[i])) continue;
    Raw r;
    r.id = ids[i];
    for (int k = 0; k < 4; ++k) r.corners[k] = cv::Point2d(corners[i][k].x + roi.x, corners[i][k].y + roi.y);
    out.push_back(r);
  }
  if (reread_ && options_.corner_refinement == "edges") {
    const size_t accepted = out.size();
    for (const auto& c : rejected) {
      std::array<cv::Point2d, 4> quad;
      for (int k = 0; k < 4; ++k) quad[k] = cv::Point2d(c[k].x + roi.x, c[k].y + roi.y);
      // Not where a marker was accepted (a margin's or a window's other quad of it).
      bool covered = false;
      for (size_t j = 0; j < accepted && !covered; ++j) covered = CentreInside(quad, out[j].corners);
      if (covered) continue;
      Raw r;
      if (RereadCandidate(gray, quad, &r) && markers_.Accepts(r.id)) {
        out.push_back(r);
        continue;
      }
      if (options_.inside_rejected_level > 0 && SearchInsideRejected(gray, quad, &r) &&
          markers_.Accepts(r.id))
        out.push_back(r);
    }
  }
  return out;
}

// A broken-border quad is read only where its border cells are darker than the ring of cells just
// outside it by this much (grey levels; IdentifyCells' floor on the code's two colours): its border is
// ink and its ring the margin's paper. The quads of the markers this search found: 53-110 levels
// (medians of 28 border and 36 ring cell centres at the quad); the quads it read in vain, dark regions
// with no bright ring: -12 to +12 (catalogue test's blur renders, seed 11: 22 of 27 quads over 8
// images; bench_detector's blurred frames: 10 of 12). Those reads cost 15 M instructions on
// bench_detector's 10 blurred frames (1572.0 -> 1556.8 M), some in DeconvolvedCells and one in
// RereadCandidate's refinement; the markers found are the same.
constexpr double kBrokenBorderDepth = 20.0;

// Under blur a thin border (under 1.5 px at 60-75 deg) is brighter than the local mean less
// adaptive_constant where a white code cell adjoins it: at OpenCV's windows its contour breaks into
// pieces (12-101 px against perimeters of 89-117) and no candidate is left. Dark below the mean of a
// 5 px window *plus* 3 grey levels the border stays whole and its outer boundary is the marker's quad
// (within 0.5-1.7 px of the true corners on the catalogue test's lost blur markers). Searched with the
// own search's QuadFinder on the tiles with contrast that no marker found so far touches (a flat
// surface has no dark pixels), each quad read as a rejected candidate is. Catalogue test (8 images,
// seed 11): blur 1.2 recall <75 deg 0.829 -> 0.971 (34 of 35), ~3.4 quads per image (read:
// kBrokenBorderDepth). On every frame it cost +47 % instructions on bench_detector's sharp frames (337.6 ->
// 494.9 M: the threshold image and contours 6.8 M, the reads 8.9 M per frame), so Detect runs it on blurred
// frames only. Quads under broken_border_min_perimeter_px are not read: the markers under 20 px it found
// (steep, cells ~1 px) had corners ~0.13 px inward on average and took the blur map's scale error from +0.036
// to +0.166 % (bench_imaging_maps, reference renderer, 150 frames, 1.0 m; with the floor: +0.036, unchanged).
void MarkerDetector::SearchBrokenBorders(const cv::Mat& gray, const cv::Rect& roi, double min_perimeter,
                                         double max_perimeter, std::vector<Raw>* out) {
  if (options_.broken_border_window <= 0) return;
  QuadFinder finder(gray(roi), OwnQuadSearch(min_perimeter, max_perimeter));
  for (const Raw& r : *out) {
    const std::vector<cv::Point2f> points = FloatQuad(r.corners);
    if ((cv::boundingRect(points) & roi).empty()) continue;  // (Cover would clamp it onto the edge)
    std::array<cv::Point2d, 4> local = r.corners;
    for (auto& c : local) c -= cv::Point2d(roi.x, roi.y);
    finder.Cover(local, 0.0);
  }
  const size_t before = out->size();
  std::vector<std::array<cv::Point2d, 4>> quads;
  for (const std::array<cv::Point2d, 4>& local :
       finder.FindBelowMean(options_.broken_border_window, options_.broken_border_offset)) {
    std::array<cv::Point2d, 4> quad = local;  // image pixels (local: the region's)
    for (auto& c : quad) c += cv::Point2d(roi.x, roi.y);
    if (QuadPerimeter(quad) < options_.broken_border_min_perimeter_px) continue;
    double border = 0, ring = 0;
    if (!BorderAndRing(gray, quad, Cells(), &border, &ring) || ring - border < kBrokenBorderDepth) continue;
    quads.push_back(local);
  }
  stats_.broken_border_quads += ReadRegionQuads(gray, roi, quads, &finder, out);
  stats_.broken_border_found += static_cast<long long>(out->size() - before);
}

bool MarkerDetector::SearchInsideRejected(const cv::Mat& gray, const std::array<cv::Point2d, 4>& quad,
                                          Raw* r) {
  const double perimeter = QuadPerimeter(quad);
  const std::vector<cv::Point2f> points(quad.begin(), quad.end());
  const cv::Rect box =
      (cv::boundingRect(points) + cv::Size(4, 4) - cv::Point(2, 2)) & cv::Rect(0, 0, gray.cols, gray.rows);
  // Quads smaller than the candidate (not its outline again).
  QuadFinder finder(gray(box), OwnQuadSearch(options_.min_perimeter_px, 0.95 * perimeter));
  for (double level : {options_.low_threshold_level, options_.inside_rejected_level}) {
    if (level == 0) continue;
    for (std::array<cv::Point2d, 4> q : finder.Find(level)) {
      for (auto& c : q) c += cv::Point2d(box.x, box.y);
      if (ReadQuad(gray, q, r)) return true;
    }
  }
  return false;
}

QuadSearch MarkerDetector::OwnQuadSearch(double min_perimeter, double max_perimeter) const {
  QuadSearch search;
  search.tile_px = options_.threshold_tile_px;
  search.min_contrast = options_.min_tile_contrast;
  search.min_perimeter = min_perimeter;
  search.max_perimeter = max_perimeter;
  search.max_deviation_rate = options_.polygonal_approx_rate;
  search.min_side_rate = options_.min_corner_distance_rate;
  search.min_distance_to_border = options_.min_distance_to_border;
  return search;
}

bool MarkerDetector::ReadQuad(const cv::Mat& gray, const std::array<cv::Point2d, 4>& quad, Raw* r) {
  return ReadCode(gray, quad, quad, 1, own_border_errors_, r) || (reread_ && RereadCandidate(gray, quad, r));
}

std::vector<MarkerDetector::Raw> MarkerDetector::OwnSearch(const cv::Mat& gray, const cv::Rect& roi,
                                                           double min_perimeter, double max_perimeter) {
  QuadFinder finder(gray(roi), OwnQuadSearch(min_perimeter, max_perimeter));
  // The mid level first; then, on the tiles where no marker was found yet, a lower level (on a grey
  // surface without margin the marker is one component with the surface at the mid level), a still
  // lower one (a thin blurred margin on a dark surface is dark at the others), a higher one (a blurred
  // border breaks at the mid level where the code's bright cells touch it), and last a local mean's
  // threshold (OpenCV's adaptive threshold: thin margins at 60-75 deg under gamma and sharpening).
  std::vector<Raw> out;
  for (double level : {options_.threshold_level, options_.second_threshold_level,
                       options_.low_threshold_level, options_.high_threshold_level, -1.0}) {
    if (level == 0 || (level < 0 && options_.mean_window_px == 0)) continue;
    ReadRegionQuads(gray, roi,
                    level > 0 ? finder.Find(level)
                              : finder.FindBelowMean(options_.mean_window_px, options_.adaptive_constant),
                    &finder, &out);
  }
  return out;
}

int MarkerDetector::ReadRegionQuads(const cv::Mat& gray, const cv::Rect& roi,
                                    const std::vector<std::array<cv::Point2d, 4>>& quads, QuadFinder* finder,
                                    std::vector<Raw>* out) {
  int read = 0;
  for (const std::array<cv::Point2d, 4>& local : quads) {
    std::array<cv::Point2d, 4> quad = local;  // image pixels (local: the region's)
    for (auto& c : quad) c += cv::Point2d(roi.x, roi.y);
    ++read;
    Raw r;
    if (!ReadQuad(gray, quad, &r) || !markers_.Accepts(r.id)) continue;
    out->push_back(r);
    finder->Cover(local, 0.0);
  }
  return read;
}

bool MarkerDetector::RereadCandidate(const cv::Mat& gray, const std::array<cv::Point2d, 4>& quad, Raw* r) {
  const int cells = Cells();
  // A dark-bordered quad (or a bright-bordered one with inverted markers) against its ring.
  const int polarity = MarkerPolarity(gray, quad, cells);
  if (polarity == 0 || (polarity < 0 && !options_.inverted) || (polarity > 0 && markers_.inverted))
    return false;
  // The quad's sides located by mid-level crossings (no code known yet): the contour's polygon sits up
  // to a cell inside a blurred marker, and its cells read a cell off.
  ++stats_.rereads;
  std::array<cv::Point2d, 4> corners = quad;
  if (!RefineMarkerCorners(gray, cells, cv::Mat(), camera_.get(), 1, &corners, false)) return false;
  if (!ReadCode(gray, quad, corners, polarity, 1, r)) return false;
  ++stats_.rereads_found;
  return true;
}

bool MarkerDetector::ReadCode(const cv::Mat& gray, const std::array<cv::Point2d, 4>& quad,
                              const std::array<cv::Point2d, 4>& corners, int polarity, int max_border_errors,
                              Raw* r) {
  const int cells = Cells();
  std::vector<float> values;
  if (!SampleCellCentres(gray, corners, cells, &values)) return false;
  if (IdentifyCells(values, quad, polarity, max_border_errors, r)) return true;
  // Cells about as narrow as the optics' blur (a blurred marker at 60-75 deg: 1.4-3 px across under
  // 1.2 px blur) read 3-8 bits wrong at their centres even at the true corners; their levels unmixed
  // (DeconvolvedCells) read 0-1 wrong (bench_accuracy's renders, build/bench/diag_recall).
  const double area =
      std::abs(cv::contourArea(std::vector<cv::Point2f>{corners[0], corners[1], corners[2], corners[3]}));
  if (area > kDeconvolvedCellPx2 * cells * cells) return false;
  if (!DeconvolvedCells(gray, corners, cells, kDeconvolutionSigmaPx, &values)) return false;
  if (!IdentifyCells(values, quad, polarity, max_border_errors, r)) return false;
  r->deconvolved = true;
  ++stats_.deconvolved_reads;
  return true;
}

bool MarkerDetector::IdentifyCells(const std::vector<float>& values, const std::array<cv::Point2d, 4>& quad,
                                   int polarity, int max_border_errors, Raw* r) {
  const int cells = Cells();
  // Two classes split where the between-class variance is largest (Otsu on the cells' values).
  std::vector<float> sorted = values;
  std::sort(sorted.begin(), sorted.end());
  const size_t n = sorted.size();
  double total = 0;
  for (float v : sorted) total += v;
  double below = 0, best = -1, threshold = 0;
  for (size_t i = 0; i + 1 < n; ++i) {
    below += sorted[i];
    const double w0 = double(i + 1) / n, w1 = 1.0 - w0;
    const double m0 = below / (i + 1), m1 = (total - below) / (n - i - 1);
    const double between = w0 * w1 * (m1 - m0) * (m1 - m0);
    if (between > best) best = between, threshold = 0.5 * (sorted[i] + sorted[i + 1]);
  }
  if (sorted.back() - sorted.front() < 20.f) return false;
  // Bits relative to the border's colour; at most max_border_errors border cells of the other colour.
  const bool dark_border = polarity > 0;
  cv::Mat bits(cells, cells, CV_8U);
  int border_errors = 0;
  for (int row = 0; row < cells; ++row)
    for (int col = 0; col < cells; ++col) {
      const bool bright = values[row * cells + col] > threshold;
      const uint8_t bit = bright == dark_border ? 1 : 0;
      bits.at<uint8_t>(row, col) = bit;
      if (row == 0 || col == 0 || row == cells - 1 || col == cells - 1) border_errors += bit;
    }
  if (border_errors > max_border_errors) return false;
  int id = -1, rotation = 0;
  const cv::Mat inner = bits(cv::Rect(1, 1, cells - 2, cells - 2)).clone();
  if (!dictionary_->identify(inner, id, rotation, options_.error_correction_rate)) return false;
  r->id = id;
  // OpenCV's corner order for the rotation it reports (corner 0: the code's top-left).
  for (int k = 0; k < 4; ++k) r->corners[k] = quad[(k + 4 - rotation) % 4];
  return true;
}

std::vector<cv::Rect> MarkerDetector::TrackRegions(cv::Size size) const {
  // Origins on the own search's tile grid (threshold_tile_px, anchored at the searched image's origin):
  // its tiles in a region are the full search's.
  const int tile = std::max(1, options_.threshold_tile_px);
  std::vector<cv::Rect> regions;
  for (const Raw& r : last_) {
    cv::Rect rect = GrownBox(r.corners, options_.fast_band_sides, 4.0, size);
    const cv::Point origin(rect.x / tile * tile, rect.y / tile * tile);
    rect = cv::Rect(origin, rect.br());
    if (rect.area() > 0) regions.push_back(rect);
  }
  for (bool merged = true; merged;) {
    merged = false;
    for (size_t i = 0; i < regions.size() && !merged; ++i) {
      for (size_t j = i + 1; j < regions.size() && !merged; ++j) {
        if ((regions[i] & regions[j]).area() > 0) {
          regions[i] |= regions[j];
          regions.erase(regions.begin() + j);
          merged = true;
        }
      }
    }
  }
  return regions;
}

std::vector<MarkerDetector::Raw> MarkerDetector::FullSearch(const cv::Mat& gray, const cv::Rect& roi) {
  return Search(gray, roi, options_.min_perimeter_px,
                options_.max_perimeter_rate * std::max(gray.cols, gray.rows), options_.adaptive_window_min,
                options_.adaptive_window_max);
}

// The unsharp mask y = (1 + k) x - k G x inverted: x = (y + k G x) / (1 + k), iterated from x = y
// (each step shrinks the error by k / (1 + k)), on encoded values or (unsharp_linear) on linear ones;
// then smoothed by `smoothing` px (sharp_smoothing) in linear light where the gamma is known (the
// model's blur is linear light's), and encoded again into `to`.
void MarkerDetector::UnsharpRegion(const cv::Mat& from, double smoothing, cv::Mat to) {
  const double k = options_.unsharp_amount;
  from.convertTo(unsharp_in_, CV_32F, 1.0 / 255.0);
  auto undo = [&]() {
    unsharp_in_.copyTo(unsharp_out_);
    for (int it = 0; it < 8; ++it) {
      cv::GaussianBlur(unsharp_out_, unsharp_blur_, cv::Size(0, 0), options_.unsharp_sigma);
      unsharp_out_ = (unsharp_in_ + k * unsharp_blur_) * (1.0 / (1.0 + k));
    }
    cv::max(unsharp_out_, 0.0, unsharp_in_);
  };
  const bool in_linear = options_.unsharp_linear && options_.gamma > 0;
  if (!in_linear) undo();
  if (options_.gamma > 0) cv::pow(unsharp_in_, options_.gamma, unsharp_in_);
  if (in_linear) undo();
  if (smoothing > 0) cv::GaussianBlur(unsharp_in_, unsharp_in_, cv::Size(0, 0), smoothing);
  if (options_.gamma > 0) cv::pow(unsharp_in_, 1.0 / options_.gamma, unsharp_in_);
  unsharp_in_.convertTo(to, CV_8U, 255.0);
}

namespace {

// `image` (8-bit or deeper; gray, BGR or BGRA) as 8-bit gray (shared, not copied, when it is one).
cv::Mat GrayImage(const cv::Mat& image) {
  cv::Mat gray;
  if (image.channels() == 3)
    cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
  else if (image.channels() == 4)
    cv::cvtColor(image, gray, cv::COLOR_BGRA2GRAY);
  else
    gray = image;
  if (gray.depth() != CV_8U) gray.convertTo(gray, CV_8U);
  return gray;
}

}  // namespace

cv::Rect MarkerDetector::RegionBox(const Raw& r, cv::Size image) {
  return GrownBox(r.corners, 0.5, 6.0, image);
}

std::vector<MarkerDetector::Raw> MarkerDetector::DropDuplicates(const cv::Mat& gray,
                                                                const std::vector<Raw>& raw) {
  const int cells = Cells();
  std::map<int, std::vector<size_t>> by_id;
  for (size_t i = 0; i < raw.size(); ++i) by_id[raw[i].id].push_back(i);
  std::vector<Raw> unique;
  for (const auto& [id, indices] : by_id) {
    if (indices.size() == 1) {
      unique.push_back(raw[indices[0]]);
      continue;
    }
    bool same_place = true;
    for (size_t j = 1; j < indices.size(); ++j)
      same_place = same_place && CentreInside(raw[indices[j]].corners, raw[indices[0]].corners) &&
                   CentreInside(raw[indices[0]].corners, raw[indices[j]].corners);
    if (!same_place) {
      if (!options_.drop_duplicate_ids)
        for (size_t j : indices) unique.push_back(raw[j]);
      continue;
    }
    const cv::Mat& bits = MarkerBits(id);
    size_t best = indices[0];
    int best_mismatches = cells * cells + 1;
    for (size_t j : indices) {
      const int mismatches = CodeMismatches(gray, raw[j].corners, bits, cells);
      if (mismatches < best_mismatches) best = j, best_mismatches = mismatches;
    }
    unique.push_back(raw[best]);
  }
  return unique;
}

std::vector<MarkerDetector::Raw> MarkerDetector::DropLookAlikes(const cv::Mat& gray,
                                                                std::vector<Raw> unique) const {
  // Inverted prints (markers.inverted): only white-bordered markers are real; the dark parts of an
  // inverted marker can look like a normal one.
  if (markers_.inverted && options_.inverted) {
    const int cells = Cells();
    std::vector<Raw> kept;
    for (const Raw& r : unique)
      if (MarkerPolarity(gray, r.corners, cells) < 0) kept.push_back(r);
    unique.swap(kept);
  }
  // A marker inside another one's quad is a pattern of its bits, not a marker.
  if (unique.size() > 1) {
    std::vector<double> areas;  // px^2 (contourArea: unsigned)
    for (const Raw& r : unique) areas.push_back(cv::contourArea(FloatQuad(r.corners)));
    std::vector<Raw> kept;
    for (size_t i = 0; i < unique.size(); ++i) {
      bool nested = false;
      for (size_t j = 0; j < unique.size() && !nested; ++j)
        nested = j != i && areas[j] > 1.5 * areas[i] && CentreInside(unique[i].corners, unique[j].corners);
      if (!nested) kept.push_back(unique[i]);
    }
    unique.swap(kept);
  }
  return unique;
}

// "edges": the region a marker is refined on (gamma-encoded camera images linearised: edges are located
// on intensities proportional to light, where a blurred step crosses halfway at the true edge; in
// encoded values it shifts to the dark side). A camera's sharpening (unsharp_amount) undone: the region
// stays encoded, a known gamma is held in the side model (not applied through an 8-bit table) and fitted
// per side where unknown.
const cv::Mat* MarkerDetector::RefineRegion(const cv::Mat& gray, const Raw& r, cv::Rect* roi) {
  const bool linearise = options_.gamma != 1.0 && options_.gamma != 0.0;
  const bool unsharp = options_.unsharp_amount > 0;
  *roi = RegionBox(r, gray.size());
  if (!linearise && !unsharp) return &gray;
  if (linear_.size() != gray.size()) linear_.create(gray.size(), CV_8U);
  if (!unsharp) {
    if (gamma_lut_.empty()) {
      gamma_lut_.create(1, 256, CV_8U);
      for (int v = 0; v < 256; ++v)
        gamma_lut_.at<uint8_t>(v) = cv::saturate_cast<uint8_t>(255.0 * std::pow(v / 255.0, options_.gamma));
    }
    // Linearised a little beyond the region: its smoothing (sharp_smoothing) reads up to OpenCV's
    // kernel radius for 8-bit images (about 3 sigma) outside it.
    const int pad = static_cast<int>(std::ceil(3.0 * options_.sharp_smoothing)) + 1;
    const cv::Rect padded =
        cv::Rect(roi->x - pad, roi->y - pad, roi->width + 2 * pad, roi->height + 2 * pad) &
        cv::Rect(0, 0, gray.cols, gray.rows);
    cv::LUT(gray(padded), gamma_lut_, linear_(padded));
    return &linear_;
  }
  UnsharpRegion(gray(*roi), 0.0, linear_(*roi));
  return &linear_;
}

// The border's polarity is known unless both prints are searched for (`inverted` without
// markers.inverted: a quad's border against its ring depends on the surround, not the print).
// A marker is refined on its region `roi` of `from` only: the working images (linear_, smooth_) hold
// this marker's region, and outside it what earlier markers and frames left (a refinement from a
// candidate far off the marker sampled there: memcheck's uninitialised reads, results that could
// depend on the images before). Beyond the region a ray counts as beyond the image.
bool MarkerDetector::RefineInRegion(const cv::Mat& from, const cv::Rect& roi, const Raw& r,
                                    std::array<cv::Point2d, 4>* corners, double* blur, bool* kept_lines) {
  const int cells = Cells();
  const int polarity = !options_.inverted ? 1 : markers_.inverted ? -1 : 0;
  const bool unsharp = options_.unsharp_amount > 0;
  const cv::Point2d origin(roi.x, roi.y);
  std::optional<CameraModel> region_camera;
  if (camera_) region_camera = CameraInRegion(*camera_, roi);
  std::array<cv::Point2d, 4> local = *corners;
  for (cv::Point2d& c : local) c -= origin;
  const bool ok = RefineMarkerCorners(from(roi), cells, MarkerBits(r.id),
                                      region_camera ? &*region_camera : nullptr, options_.edge_passes, &local,
                                      options_.edge_model, blur, options_.gamma == 0 || unsharp, kept_lines,
                                      polarity, unsharp ? options_.gamma : 0.0);
  if (ok)
    for (int k = 0; k < 4; ++k) (*corners)[k] = local[k] + origin;
  return ok;
}

// Sharp images: interpolated edge profiles lock to the pixel grid (sides along an image axis keep one
// phase all along). Every marker is refined first on its region smoothed a little (sharp_smoothing):
// crossing and model fit are unbiased under symmetric blur, the locking is gone. A blurred frame (the
// mean of its markers' blur from those fits, sqrt(sigma^2 - smoothing^2), 0.55 px or more) needs no
// smoothing: its markers are refined from their candidates on their unsmoothed regions. The choice
// rests on this frame's markers only: never on earlier frames (nor the detector's mode, whose
// histories differ). The mean, not the median: the sim's blur is 0.4-0.58 px per marker, and the
// upper median of a frame's two markers flipped the choice between the modes (0.13 px at 640x480).
std::vector<MarkerDetector::Refined> MarkerDetector::RefineSmoothed(const cv::Mat& gray,
                                                                    const std::vector<Raw>& unique,
                                                                    bool* sharp_frame) {
  const double s = options_.sharp_smoothing;
  const bool unsharp = options_.unsharp_amount > 0;
  std::vector<double> blurs;  // each smoothed fit's blur, px
  std::vector<Refined> smoothed;
  for (const Raw& r : unique) {
    cv::Rect roi;
    if (smooth_.size() != gray.size()) smooth_.create(gray.size(), CV_8U);
    if (unsharp) {
      roi = RegionBox(r, gray.size());
      UnsharpRegion(gray(roi), s, smooth_(roi));
    } else {
      const cv::Mat* source = RefineRegion(gray, r, &roi);
      cv::GaussianBlur((*source)(roi), smooth_(roi), cv::Size(0, 0), s);
    }
    Refined m;
    m.corners = r.corners;
    double sigma = NAN;
    m.refined = RefineInRegion(smooth_, roi, r, &m.corners, &sigma, &m.kept_lines);
    if (m.refined && std::isfinite(sigma)) blurs.push_back(std::sqrt(std::max(0.0, sigma * sigma - s * s)));
    smoothed.push_back(m);
  }
  double mean = 0;
  for (double b : blurs) mean += b / blurs.size();
  *sharp_frame = blurs.empty() || mean < 0.55;
  return smoothed;
}

bool MarkerDetector::RefineCorners(const cv::Mat& gray, const Refined* smoothed, Raw* r) {
  const int cells = Cells();
  const cv::Mat& bits = MarkerBits(r->id);
  // A refinement counts only if the code reads at the refined corners about as well as at the
  // candidate's (which decoded): not a cell off.
  const std::array<cv::Point2d, 4> candidate = r->corners;
  int candidate_mismatches = -1;  // read once, when a refinement is to be judged
  // A marker read from unmixed levels is judged on them (its cells' centres read wrong anywhere).
  auto mismatches = [&](const std::array<cv::Point2d, 4>& corners) {
    if (!r->deconvolved) return CodeMismatches(gray, corners, bits, cells);
    std::vector<float> levels;
    if (!DeconvolvedCells(gray, corners, cells, kDeconvolutionSigmaPx, &levels)) return cells * cells;
    return LevelMismatches(levels, bits, cells);
  };
  int refined_mismatches = -1;  // the last judged refinement's
  auto reads = [&](const std::array<cv::Point2d, 4>& corners) {
    if (candidate_mismatches < 0) candidate_mismatches = mismatches(candidate);
    refined_mismatches = mismatches(corners);
    return refined_mismatches <= candidate_mismatches + cells;
  };
  // The refinement on the marker's region of the frame itself (not smoothed), from `corners`. The region
  // is the candidate's, where the refinement starts. (id123's retry took it about the rejected smoothed
  // refinement's corners; the 5 markers it refines in bench_accuracy 8 end the same either way.)
  auto refine_unsmoothed = [&](std::array<cv::Point2d, 4>* corners, bool* kept) {
    cv::Rect roi;
    Raw about = *r;
    about.corners = candidate;
    const cv::Mat* source = RefineRegion(gray, about, &roi);
    return RefineInRegion(*source, roi, *r, corners, nullptr, kept);
  };
  bool slid = false;  // edges fitted, but a cell off: the region is too confusing to trust
  bool kept_lines = false;
  bool refined = false;
  if (smoothed) {
    refined = smoothed->refined, kept_lines = smoothed->kept_lines;
    if (refined) r->corners = smoothed->corners;
  } else {
    refined = refine_unsmoothed(&r->corners, &kept_lines);
  }
  // A cell off after a side kept its line (no clean crossing: the edge is not clear there) is an
  // unrefined marker, not a confusing region.
  if (refined && !reads(r->corners)) refined = false, slid = !kept_lines;
  // A sharp frame's marker whose smoothed refinement reads its code worse than the candidate does (within
  // the allowance above) is refined again from its candidate on the region itself, and takes that
  // refinement if its code reads better still. Across sides whose cells are 1-1.4 px deep the smoothing
  // can carry a side's fit into the code rows, or the surround pull it off: a side ends 0.6-1.2 px off and
  // the code reads a few cells worse, yet passes. bench_accuracy 8: 13 of the 3622 markers refined on sharp
  // frames read worse than their candidates, 11 read better unsmoothed; 8 of those came closer to the
  // truth (worst corner 0.93 -> 0.30, 1.13 -> 0.10, 1.50 -> 0.20, 3.25 -> 0.72 px), 3 moved 0.03-0.13 px
  // further; corners > 0.5 px off 450 -> 438, every other marker bit-identical
  // (bench/results/2026-12-07-gross.md).
  if (refined && smoothed && refined_mismatches > candidate_mismatches) {
    const int smoothed_mismatches = refined_mismatches;
    std::array<cv::Point2d, 4> plain = candidate;
    bool plain_kept = false;
    if (refine_unsmoothed(&plain, &plain_kept) && mismatches(plain) < smoothed_mismatches) r->corners = plain;
  }
  if (refined) return true;
  // A sharp frame's marker whose refinement on the smoothed region failed, or ended a cell off after a
  // side kept its line, is refined again from its candidate on the region itself before it falls back to
  // cornerSubPix. On cells about a pixel deep across a foreshortened side the smoothing (sharp_smoothing,
  // 0.6 px) blurs the border into the first code rows: that side's fit lost them (its gamma at its bound,
  // in the skew pass border and code levels 8 apart) and the side ended 1.3 px outward, the code read a
  // cell off, and cornerSubPix placed the marker's corners up to 1.63 px off (catalogue test, no margin
  // on grey, id 123, 15.9 px at 69 deg); refined on the unsmoothed region from the same candidate they end
  // within 0.25 px. bench_accuracy 8: corners > 0.5 px off 463 -> 450 (bench/results/2026-12-07-id123.md).
  // A marker dropped as a cell off without a kept line (`slid`) stays dropped: rescued so, 2 of 5 had
  // corners 0.53 and 0.93 px off.
  if (smoothed && !slid) {
    std::array<cv::Point2d, 4> plain = candidate;
    bool plain_kept = false;
    if (refine_unsmoothed(&plain, &plain_kept) && reads(plain)) {
      r->corners = plain;
      return true;
    }
  }
  r->corners = candidate;
  // A refinement a cell off is dropped: the marker's surroundings mislead edge fits, and a corner a
  // pixel off passes a bundle adjustment's outlier test yet biases it. No clean edge on some side (a
  // small or blurred marker, one cut by the image border, glare): OpenCV's corner refinement in a
  // window of about half a cell rather than the candidate polygon's pixel-level corners, or dropped
  // (drop_unrefined).
  ++stats_.refine_failures;
  if (slid || options_.drop_unrefined) {
    ++stats_.dropped;
    return false;
  }
  SubPixelCorners(gray, cells, &r->corners);
  return true;
}

std::vector<marker_t> MarkerDetector::Detect(const cv::Mat& image) {
  const cv::Mat gray = GrayImage(image);
  ++stats_.frames;

  // Where this frame is searched: in fast mode between full searches, TrackRegions, each as the full
  // search searches the image (every threshold window, every perimeter: a marker inside one, away from
  // its edges, gives the full search's candidate; regions do not overlap, so a marker is found once per
  // candidate, as in the full search); else the whole image.
  const bool tracked = options_.fast && !last_.empty() && frames_since_full_ + 1 < options_.full_search_every;
  const std::vector<cv::Rect> regions =
      tracked ? TrackRegions(gray.size()) : std::vector<cv::Rect>{cv::Rect(0, 0, gray.cols, gray.rows)};
  std::vector<Raw> raw;
  for (const cv::Rect& roi : regions) {
    const std::vector<Raw> found = FullSearch(gray, roi);
    raw.insert(raw.end(), found.begin(), found.end());
  }
  if (tracked) {
    ++frames_since_full_;
  } else {
    frames_since_full_ = 0;
    ++stats_.full_searches;
  }
  std::vector<Raw> unique = DropLookAlikes(gray, DropDuplicates(gray, raw));

  const bool edges = options_.corner_refinement == "edges";
  std::vector<Refined> smoothed;
  bool use_smoothed = false;
  if (edges && options_.sharp_smoothing > 0) smoothed = RefineSmoothed(gray, unique, &use_smoothed);
  // A blurred frame (its markers' mean fitted blur >= 0.55 px: RefineSmoothed) is searched again for
  // markers whose border broke at the adaptive threshold (SearchBrokenBorders), in the same regions.
  if (edges && reread_ && !use_smoothed && !smoothed.empty() && options_.broken_border_window > 0) {
    const size_t before = unique.size();
    for (const cv::Rect& roi : regions)
      SearchBrokenBorders(gray, roi, options_.min_perimeter_px,
                          options_.max_perimeter_rate * std::max(gray.cols, gray.rows), &unique);
    if (unique.size() > before) unique = DropLookAlikes(gray, DropDuplicates(gray, unique));
  }
  std::vector<marker_t> out;
  out.reserve(unique.size());
  for (size_t i = 0; i < unique.size(); ++i) {
    Raw& r = unique[i];
    if (edges && !RefineCorners(gray, use_smoothed ? &smoothed[i] : nullptr, &r)) continue;
    marker_t m;
    m.id = r.id;
    for (int k = 0; k < 4; ++k) {
      m.corners[k][0] = r.corners[k].x;
      m.corners[k][1] = r.corners[k].y;
    }
    out.push_back(m);
  }
  stats_.markers += static_cast<long long>(out.size());
  if (tone_) ObserveTone(gray, out);
  if (options_.fast) last_ = unique;
  return out;
}

}  // namespace mcmt
