// A small exact renderer of square markers for the detector's tests and benchmark (independent of
// mcmt_sim): each output pixel is the area average (8x8 supersampling) of the marker texture seen
// through a homography, pixel centres at integer coordinates, optional Gaussian blur and noise.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <opencv2/aruco.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <vector>

#include "core/math.h"
#include "mcmt/marker_t.hpp"

namespace mcmt::testing {

struct RenderedMarker {
  int id = 0;
  std::array<cv::Point2d, 4> corners;  // ground truth, ArUco order
  double side_px = 0;                  // mean side length in the image
  double view_angle_deg = 0;           // angle between the marker normal and the viewing ray
};

// Texture of a marker (cells x cells, border included) with `quiet` cells of white around it, as
// `texels_per_cell` texels per cell. 0 = black, 255 = white (inverted swaps them).
inline cv::Mat MarkerTexture(const cv::aruco::Dictionary& dict, int id, int quiet, int texels_per_cell,
                             bool inverted) {
  const int cells = dict.markerSize + 2;
  cv::Mat marker;
  cv::aruco::drawMarker(cv::makePtr<cv::aruco::Dictionary>(dict), id, cells * texels_per_cell, marker, 1);
  cv::Mat tex(marker.rows + 2 * quiet * texels_per_cell, marker.cols + 2 * quiet * texels_per_cell, CV_8U,
              cv::Scalar(255));
  marker.copyTo(tex(cv::Rect(quiet * texels_per_cell, quiet * texels_per_cell, marker.cols, marker.rows)));
  if (inverted) tex = 255 - tex;
  return tex;
}

// Draws `texture` into the float image `canvas` (values 0..1 of black..white mapped to dark..light)
// through the homography image_from_texture (texture coordinates continuous: texel (r, c) covers
// [c, c+1] x [r, r+1]).
inline void DrawTexture(const cv::Mat& texture, const cv::Matx33d& image_from_texture, cv::Mat* canvas) {
  const cv::Matx33d texture_from_image = image_from_texture.inv();
  std::vector<cv::Point2d> box = {{0, 0},
                                  {double(texture.cols), 0},
                                  {double(texture.cols), double(texture.rows)},
                                  {0, double(texture.rows)}};
  double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
  for (const auto& b : box) {
    const cv::Vec3d p = image_from_texture * cv::Vec3d(b.x, b.y, 1.0);
    x0 = std::min(x0, p[0] / p[2]), x1 = std::max(x1, p[0] / p[2]);
    y0 = std::min(y0, p[1] / p[2]), y1 = std::max(y1, p[1] / p[2]);
  }
  const int c0 = std::max(0, int(std::floor(x0)) - 1),
            c1 = std::min(canvas->cols - 1, int(std::ceil(x1)) + 1);
  const int r0 = std::max(0, int(std::floor(y0)) - 1),
            r1 = std::min(canvas->rows - 1, int(std::ceil(y1)) + 1);
  constexpr int kS = 8;
  for (int r = r0; r <= r1; ++r) {
    float* row = canvas->ptr<float>(r);
    for (int c = c0; c <= c1; ++c) {
      double sum = 0;
      int inside = 0;
      for (int a = 0; a < kS; ++a) {
        for (int b = 0; b < kS; ++b) {
          const double x = c - 0.5 + (b + 0.5) / kS, y = r - 0.5 + (a + 0.5) / kS;
          const cv::Vec3d t = texture_from_image * cv::Vec3d(x, y, 1.0);
          const double u = t[0] / t[2], v = t[1] / t[2];
          if (u < 0 || v < 0 || u >= texture.cols || v >= texture.rows) continue;
          sum += texture.at<uint8_t>(int(v), int(u)) / 255.0;
          ++inside;
        }
      }
      if (inside == 0) continue;
      const double cover = double(inside) / (kS * kS);
      row[c] = float(row[c] * (1.0 - cover) + sum / (kS * kS));
    }
  }
}

struct SceneOptions {
  int width = 640, height = 480;
  double focal = 600;
  double min_side_px = 15, max_side_px = 60;
  double max_angle_deg = 75;
  int markers = 4;
  double blur_sigma = 0;
  double noise_sigma = 0;  // gray levels
  double dark = 30, light = 220;
  bool inverted = false;
  int quiet_cells = 1;      // white margin around each marker (cells)
  double background = 0.5;  // level of the surface around the quiet zones (0 dark .. 1 light)
};

// A canvas of levels 0 (dark) .. 1 (light) as the 8-bit image: blurred by o.blur_sigma, levels o.dark ..
// o.light, Gaussian noise of o.noise_sigma gray levels (cv::theRNG seeded with noise_seed), rounded and
// saturated.
inline cv::Mat CanvasToImage(cv::Mat canvas, const SceneOptions& o, uint64_t noise_seed) {
  if (o.blur_sigma > 0) cv::GaussianBlur(canvas, canvas, cv::Size(0, 0), o.blur_sigma);
  cv::Mat out;
  canvas.convertTo(canvas, CV_32F, o.light - o.dark, o.dark);
  if (o.noise_sigma > 0) {
    cv::Mat noise(canvas.size(), CV_32F);
    cv::theRNG().state = noise_seed;
    cv::randn(noise, 0.0, o.noise_sigma);
    canvas += noise;
  }
  canvas.convertTo(out, CV_8U);  // rounds and saturates
  return out;
}

// A random image with `markers` non-overlapping markers of random ids, sizes, poses; ground truth out.
inline cv::Mat RenderScene(const cv::aruco::Dictionary& dict, const SceneOptions& o, std::mt19937_64& rng,
                           std::vector<RenderedMarker>* truth) {
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  cv::Mat canvas(o.height, o.width, CV_32F, cv::Scalar(o.inverted ? 0.0 : o.background));
  truth->clear();
  const int cells = dict.markerSize + 2;
  const int tpc = 16;
  std::vector<cv::Rect> used;
  for (int attempt = 0; attempt < 200 && int(truth->size()) < o.markers; ++attempt) {
    const int id = std::uniform_int_distribution<int>(0, dict.bytesList.rows - 1)(rng);
    bool dup = false;
    for (const auto& t : *truth) dup = dup || t.id == id;
    if (dup) continue;
    const double side_px = o.min_side_px + (o.max_side_px - o.min_side_px) * uni(rng);
    // Pose: tilt (view angle) about a random in-plane axis, random roll, depth for the wanted size.
    const double tilt = std::acos(1.0 - uni(rng) * (1.0 - std::cos(o.max_angle_deg * M_PI / 180.0)));
    const double axis = 2 * M_PI * uni(rng), roll = 2 * M_PI * uni(rng);
    const double z = o.focal / side_px;  // side 1 at depth z looks side_px wide head-on
    const double cx = (0.12 + 0.76 * uni(rng)) * o.width, cy = (0.12 + 0.76 * uni(rng)) * o.height;
    const cv::Vec3d centre((cx - o.width / 2.0) * z / o.focal, (cy - o.height / 2.0) * z / o.focal, z);
    cv::Matx33d rz(std::cos(roll), -std::sin(roll), 0, std::sin(roll), std::cos(roll), 0, 0, 0, 1);
    cv::Vec3d ax(std::cos(axis), std::sin(axis), 0);
    cv::Mat rt;
    cv::Rodrigues(cv::Mat(ax * tilt), rt);
    // The tilt is relative to the viewing ray: rotate the fronto-parallel pose so that its normal
    // makes `tilt` with the ray to the centre.
    cv::Vec3d ray = centre / cv::norm(centre);
    cv::Vec3d zaxis(0, 0, 1);
    cv::Vec3d rot_axis = zaxis.cross(ray);
    double rot_angle = std::asin(std::min(1.0, cv::norm(rot_axis)));
    cv::Mat rr = cv::Mat::eye(3, 3, CV_64F);
    if (rot_angle > 1e-9) cv::Rodrigues(cv::Mat(rot_axis / cv::norm(rot_axis) * rot_angle), rr);
    cv::Matx33d R = cv::Matx33d(rr) * cv::Matx33d(rt) * rz;
    // Marker frame: x right, y down in the texture (image-like), texture units = cells * tpc per side 1.
    const cv::Mat tex = MarkerTexture(dict, id, o.quiet_cells, tpc, o.inverted);
    const double scale = 1.0 / (cells * tpc);  // marker units per texel
    const double off = o.quiet_cells * tpc;    // texels of quiet zone before the marker
    // point(u, v) in texels -> marker plane X = (u - off) * scale - 0.5, Y = (v - off) * scale - 0.5.
    cv::Matx33d K(o.focal, 0, o.width / 2.0, 0, o.focal, o.height / 2.0, 0, 0, 1);
    cv::Matx33d plane(R(0, 0), R(0, 1), centre[0], R(1, 0), R(1, 1), centre[1], R(2, 0), R(2, 1), centre[2]);
    cv::Matx33d tex_to_plane(scale, 0, -off * scale - 0.5, 0, scale, -off * scale - 0.5, 0, 0, 1);
    cv::Matx33d H = K * plane * tex_to_plane;
    RenderedMarker m;
    m.id = id;
    const double ts = cells * tpc;
    const cv::Point2d tc[4] = {{off, off}, {off + ts, off}, {off + ts, off + ts}, {off, off + ts}};
    double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
    bool in = true;
    for (int k = 0; k < 4; ++k) {
      const cv::Vec3d p = H * cv::Vec3d(tc[k].x, tc[k].y, 1);
      m.corners[k] = {p[0] / p[2], p[1] / p[2]};
      x0 = std::min(x0, m.corners[k].x), x1 = std::max(x1, m.corners[k].x);
      y0 = std::min(y0, m.corners[k].y), y1 = std::max(y1, m.corners[k].y);
      in = in && m.corners[k].x > 4 && m.corners[k].y > 4 && m.corners[k].x < o.width - 5 &&
           m.corners[k].y < o.height - 5;
    }
    if (!in) continue;
    const double grow = 0.25 * (x1 - x0) + 3;
    cv::Rect box(int(x0 - grow), int(y0 - grow), int(x1 - x0 + 2 * grow), int(y1 - y0 + 2 * grow));
    bool overlap = false;
    for (const auto& u : used) overlap = overlap || (u & box).area() > 0;
    if (overlap) continue;
    used.push_back(box);
    m.side_px = 0;
    for (int k = 0; k < 4; ++k) m.side_px += cv::norm(m.corners[(k + 1) % 4] - m.corners[k]) / 4;
    const cv::Vec3d normal(R(0, 2), R(1, 2), R(2, 2));
    m.view_angle_deg = std::acos(std::abs(normal.dot(ray))) * 180 / M_PI;
    DrawTexture(tex, H, &canvas);
    truth->push_back(m);
  }
  // The noise's seed drawn only with noise, as rng's later draws (the caller's next image) depend on it.
  return CanvasToImage(canvas, o, o.noise_sigma > 0 ? rng() : 0);
}

// Per-corner error statistics of detected markers against the truth.
struct CornerErrors {
  std::vector<double> errors;   // Euclidean, px
  std::vector<double> offsets;  // signed offset along the outward edge normals, px (+: outward)
};

// A quad's perimeter (px).
inline double QuadPerimeter(const std::array<cv::Point2d, 4>& q) {
  double sum = 0;
  for (int k = 0; k < 4; ++k) sum += cv::norm(q[(k + 1) % 4] - q[k]);
  return sum;
}

// A quad's skew: the mean over its corners of |angle - 90| (deg).
inline double QuadSkewDeg(const std::array<cv::Point2d, 4>& q) {
  double sum = 0;
  for (int k = 0; k < 4; ++k) {
    const cv::Point2d u = q[(k + 3) % 4] - q[k], v = q[(k + 1) % 4] - q[k];
    sum += 0.25 * std::abs(std::acos(u.dot(v) / (cv::norm(u) * cv::norm(v))) * 180 / M_PI - 90);
  }
  return sum;
}

// The outward unit normal of side `side` (corners side -> side + 1) of a marker's true quad.
inline cv::Point2d OutwardNormal(const RenderedMarker& truth, int side) {
  cv::Point2d centre(0, 0);
  for (const auto& c : truth.corners) centre += c * 0.25;
  const cv::Point2d d = truth.corners[(side + 1) % 4] - truth.corners[side];
  cv::Point2d n(d.y, -d.x);
  n *= 1.0 / cv::norm(n);
  const cv::Point2d mid = 0.5 * (truth.corners[side] + truth.corners[(side + 1) % 4]);
  return n.dot(mid - centre) < 0 ? -n : n;
}

// A detected marker's corners as points (its corner order, pixels).
inline std::array<cv::Point2d, 4> CornersOf(const marker_t& m) {
  std::array<cv::Point2d, 4> corners;
  for (int k = 0; k < 4; ++k) corners[k] = {m.corners[k][0], m.corners[k][1]};
  return corners;
}

inline void AddCornerErrors(const RenderedMarker& truth, const std::array<cv::Point2d, 4>& got,
                            CornerErrors* out) {
  for (int k = 0; k < 4; ++k) {
    const cv::Point2d e = got[k] - truth.corners[k];
    out->errors.push_back(cv::norm(e));
    double offset = 0;
    for (int side : {(k + 3) % 4, k}) offset += 0.5 * OutwardNormal(truth, side).dot(e);
    out->offsets.push_back(offset);
  }
}

inline double MedianOf(std::vector<double> v) { return Median(std::move(v), NAN); }
inline double MeanOf(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? NAN : s / v.size();
}

}  // namespace mcmt::testing
