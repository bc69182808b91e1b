// The simulator's renderer.
//
// The scene is a set of planar convex patches (the body's faces and the markers with their quiet
// zones) over a per-camera background. Every pixel's value is the exact mean of the scene over the
// pixel's square footprint [u-0.5, u+0.5] x [v-0.5, v+0.5] (pixel centres at integer coordinates,
// OpenCV's convention): the footprint is mapped onto each patch's plane by the affine map that is the
// first-order expansion of (pixel -> undistorted ray -> plane) at the pixel centre, i.e. a
// parallelogram, and clipped exactly against the patch outline and against each marker cell. The
// neglected second-order terms move an edge by far less than 1e-3 px at the scales simulated.
// Patches are composited front to back by their depth at the pixel centre, taking coverage as disjoint
// (exact for a marker on its face, for adjacent faces and for occluding edges over a full surface).
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <random>
#include <stdexcept>

#include "core/dictionary.h"
#include "sim/sim.h"
#include "sim/sim_internal.h"

namespace mcmt {
namespace sim {

namespace {

using Vec2 = Eigen::Vector2d;
using Poly = std::vector<Vec2>;

// Clips a convex polygon by the half-plane n . p <= d (Sutherland-Hodgman).
void ClipHalfPlane(const Poly& in, const Vec2& n, double d, Poly* out) {
  out->clear();
  const size_t k = in.size();
  for (size_t i = 0; i < k; ++i) {
    const Vec2& a = in[i];
    const Vec2& b = in[(i + 1) % k];
    const double da = n.dot(a) - d, db = n.dot(b) - d;
    if (da <= 0) out->push_back(a);
    if ((da < 0 && db > 0) || (da > 0 && db < 0)) out->push_back(a + (b - a) * (da / (da - db)));
  }
}

double PolygonArea(const Poly& p) {
  double a = 0;
  const size_t k = p.size();
  for (size_t i = 0; i < k; ++i) {
    const Vec2& u = p[i];
    const Vec2& v = p[(i + 1) % k];
    a += u.x() * v.y() - u.y() * v.x();
  }
  return 0.5 * std::abs(a);
}

// Area of a convex polygon intersected with a convex polygon given as half-planes n . p <= d.
double ClippedArea(const Poly& polygon, const std::vector<std::pair<Vec2, double>>& half_planes) {
  Poly a = polygon, b;
  for (const auto& [n, d] : half_planes) {
    ClipHalfPlane(a, n, d, &b);
    a.swap(b);
    if (a.size() < 3) return 0.0;
  }
  return PolygonArea(a);
}

double RectArea(const Poly& polygon, double x0, double y0, double x1, double y1) {
  Poly a = polygon, b;
  ClipHalfPlane(a, Vec2(-1, 0), -x0, &b);
  if (b.size() < 3) return 0;
  ClipHalfPlane(b, Vec2(1, 0), x1, &a);
  if (a.size() < 3) return 0;
  ClipHalfPlane(a, Vec2(0, -1), -y0, &b);
  if (b.size() < 3) return 0;
  ClipHalfPlane(b, Vec2(0, 1), y1, &a);
  if (a.size() < 3) return 0;
  return PolygonArea(a);
}

uint64_t Mix(uint64_t x) {  // splitmix64
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// The surface's wood-like grain at a point of a face (patch coordinates, metres): a brightness factor.
inline double Grain(const RenderOptions& o, const Vec2& c) {
  if (o.surface_texture <= 0) return 1.0;
  const double k = 2.0 * M_PI / o.surface_texture_period;
  return 1.0 + o.surface_texture * std::sin(k * c.x() + 1.5 * std::sin(0.37 * k * c.y()));
}

// A planar convex patch in the object frame.
struct Patch {
  Eigen::Vector3d origin, e1, e2, normal;
  Poly outline;                                      // convex, counter-clockwise, patch coordinates
  std::vector<std::pair<Vec2, double>> half_planes;  // the outline as n . p <= d
  double xmin, xmax, ymin, ymax;                     // outline bounds
  bool is_marker = false;
  // Marker: a grid x grid cells of side `cell` covering [-half, half]^2, row 0 at +y; 1 = white.
  int grid = 0;
  double cell = 0, half = 0;
  std::vector<uint8_t> cells;
  double albedo = 0.5;  // faces
};

struct CameraCache {
  CameraModel model;
  int index = -1;
  cv::Mat background;  // CV_32F, gray levels, lighting applied
  cv::Mat lighting;    // CV_32F, relative brightness
  cv::Mat rays;        // CV_64FC2: undistorted normalised coordinates per pixel (distorted cameras)
  cv::Mat jacobians;   // CV_64FC4: d(normalised)/d(pixel) per pixel, row-major 2x2
  bool distorted = false;
};

bool SameModel(const CameraModel& a, const CameraModel& b) {
  return a.width == b.width && a.height == b.height && a.fx == b.fx && a.fy == b.fy && a.cx == b.cx &&
         a.cy == b.cy && a.model == b.model && a.distortion == b.distortion;
}

// A patch seen by one camera: its frame in camera coordinates and its image bounds.
struct ViewPatch {
  const Patch* patch;
  Eigen::Vector3d origin, e1, e2, normal;
  double n_dot_origin;
  int u0, u1, v0, v1;  // pixel bounds (inclusive)
  double shade;        // relative brightness from its orientation to the light
};

}  // namespace

double ConvexPolygonRectArea(const std::vector<Eigen::Vector2d>& polygon, double x0, double y0, double x1,
                             double y1) {
  if (polygon.size() < 3 || !(x1 > x0) || !(y1 > y0)) return 0.0;
  // Orientation does not matter for clipping; the area is unsigned.
  return RectArea(polygon, x0, y0, x1, y1);
}

CellSpan CellsOverlapping(double from, double to, int grid) {
  constexpr double kIntLimit = 2147483648.0;  // 2^31: floor(to) below it converts to int
  CellSpan span;
  if (!(to >= 0 && to < kIntLimit)) return span;  // before the grid, too far, or NaN
  span.last = std::min(grid - 1, static_cast<int>(std::floor(to)));
  // Below the grid (-inf and NaN included) from counts from cell 0; above 2^31 (only when from > to)
  // it is held below the limit of the conversion, past `last`.
  span.first = from > 0 ? static_cast<int>(std::floor(std::min(from, kIntLimit - 1))) : 0;
  return span;
}

struct Renderer::Impl {
  std::vector<Patch> patches;
  Eigen::Vector3d light_in_rig = Eigen::Vector3d(0.3, 0.2, 1.0).normalized();
  mutable std::mutex mutex;
  mutable std::vector<std::unique_ptr<CameraCache>> caches;

  const CameraCache& Cache(const SimCamera& camera, int index, const RenderOptions& o) const;
  void RenderInto(const SimCamera& camera, const CameraCache& cache, const Rigid3& rig_from_object,
                  const RenderOptions& o, cv::Mat* image) const;
};

Renderer::Renderer(const SimObject& object, const std::string& dictionary, const RenderOptions& options)
    : options_(options), impl_(new Impl) {
  if (options.supersampling < 0 || options.supersampling > 64)
    throw std::invalid_argument("supersampling: expected 0..64");
  if (options.quiet_zone_cells < 0 || options.quiet_zone_cells > 10)
    throw std::invalid_argument("quiet zone: expected 0..10 cells");
  cv::Ptr<cv::aruco::Dictionary> dict = LoadDictionary(dictionary);
  const int bits = dict->markerSize;
  for (const SimFace& f : object.faces) {
    if (f.vertices.size() < 3) continue;
    Patch p;
    p.origin = f.vertices[0];
    p.e1 = (f.vertices[1] - f.vertices[0]).normalized();
    p.normal = (f.vertices[1] - f.vertices[0]).cross(f.vertices[2] - f.vertices[0]).normalized();
    p.e2 = p.normal.cross(p.e1);
    for (const auto& v : f.vertices) p.outline.emplace_back(p.e1.dot(v - p.origin), p.e2.dot(v - p.origin));
    p.albedo = options.surface_albedo >= 0 ? options.surface_albedo : f.albedo;
    p.albedo *=
        0.114 * options.surface_tint[0] + 0.587 * options.surface_tint[1] + 0.299 * options.surface_tint[2];
    impl_->patches.push_back(p);
  }
  for (const SimMarker& m : object.markers) {
    if (m.id < 0 || m.id >= dict->bytesList.rows)
      throw std::invalid_argument("marker id " + std::to_string(m.id) + " is not in dictionary " +
                                  dictionary + " (" + std::to_string(dict->bytesList.rows) + " markers)");
    Patch p;
    p.is_marker = true;
    p.origin = m.object_from_marker.translation();
    p.e1 = m.object_from_marker.linear().col(0);
    p.e2 = m.object_from_marker.linear().col(1);
    p.normal = m.object_from_marker.linear().col(2);
    const int q = options.quiet_zone_cells;
    p.grid = bits + 2 + 2 * q;
    p.cell = m.size / (bits + 2);
    p.half = 0.5 * m.size + q * p.cell;
    p.outline = {Vec2(-p.half, -p.half), Vec2(p.half, -p.half), Vec2(p.half, p.half), Vec2(-p.half, p.half)};
    p.cells.assign(p.grid * p.grid, 1);
    cv::Mat img = MarkerImage(*dict, m.id, bits + 2);
    for (int i = 0; i < bits + 2; ++i)
      for (int j = 0; j < bits + 2; ++j) {
        const bool white = !options.solid_markers && img.at<uint8_t>(i, j) > 127;
        p.cells[(i + q) * p.grid + (j + q)] = white ? 1 : 0;
      }
    if (options.inverted)
      for (auto& c : p.cells) c = 1 - c;
    impl_->patches.push_back(p);
  }
  for (Patch& p : impl_->patches) {
    p.xmin = p.ymin = 1e300;
    p.xmax = p.ymax = -1e300;
    // Make the outline counter-clockwise and derive its half-planes.
    double signed_area = 0;
    for (size_t i = 0; i < p.outline.size(); ++i) {
      const Vec2& a = p.outline[i];
      const Vec2& b = p.outline[(i + 1) % p.outline.size()];
      signed_area += a.x() * b.y() - a.y() * b.x();
    }
    if (signed_area < 0) std::reverse(p.outline.begin(), p.outline.end());
    for (size_t i = 0; i < p.outline.size(); ++i) {
      const Vec2& a = p.outline[i];
      const Vec2& b = p.outline[(i + 1) % p.outline.size()];
      const Vec2 n(b.y() - a.y(), a.x() - b.x());  // outward for counter-clockwise
      p.half_planes.emplace_back(n, n.dot(a));
      p.xmin = std::min(p.xmin, a.x());
      p.xmax = std::max(p.xmax, a.x());
      p.ymin = std::min(p.ymin, a.y());
      p.ymax = std::max(p.ymax, a.y());
    }
  }
}

Renderer::~Renderer() = default;

const CameraCache& Renderer::Impl::Cache(const SimCamera& camera, int index, const RenderOptions& o) const {
  std::lock_guard<std::mutex> lock(mutex);
  for (const auto& c : caches)
    if (c->index == index && SameModel(c->model, camera.model)) return *c;
  auto cache = std::make_unique<CameraCache>();
  cache->model = camera.model;
  cache->index = index;
  const CameraModel& m = camera.model;
  const int w = m.width, h = m.height;
  cv::RNG rng(Mix(o.seed * 1000003ULL + static_cast<uint64_t>(index) * 7919ULL + 11));
  // Lighting: a linear ramp across the image in a random direction.
  cache->lighting.create(h, w, CV_32F);
  const double phi = rng.uniform(0.0, 2 * CV_PI);
  const double g = o.lighting_gradient;
  for (int v = 0; v < h; ++v) {
    float* row = cache->lighting.ptr<float>(v);
    for (int u = 0; u < w; ++u) {
      const double s = (u - 0.5 * w) / w * std::cos(phi) + (v - 0.5 * h) / h * std::sin(phi);
      row[u] = static_cast<float>(1.0 + g * s);
    }
  }
  // Background: multi-octave value noise plus a few soft shapes (a room's clutter), or uniform.
  cv::Mat bg(h, w, CV_32F, cv::Scalar(o.background_level));
  if (o.textured_background) {
    bg.setTo(cv::Scalar(120.0));
    const int octaves[5][2] = {{4, 3}, {8, 6}, {16, 12}, {32, 24}, {96, 72}};
    const double amps[5] = {45, 28, 16, 9, 5};
    for (int k = 0; k < 5; ++k) {
      cv::Mat small(octaves[k][1], octaves[k][0], CV_32F);
      rng.fill(small, cv::RNG::UNIFORM, cv::Scalar(-amps[k]), cv::Scalar(amps[k]));
      cv::Mat big;
      cv::resize(small, big, cv::Size(w, h), 0, 0, cv::INTER_CUBIC);
      bg += big;
    }
    cv::Mat shapes(h, w, CV_32F, cv::Scalar(0));
    const int n_shapes = 12;
    for (int k = 0; k < n_shapes; ++k) {
      const cv::Point c(rng.uniform(0, w), rng.uniform(0, h));
      const double value = rng.uniform(-40.0, 40.0);
      const int a = rng.uniform(w / 40 + 2, w / 6 + 3), b = rng.uniform(h / 40 + 2, h / 6 + 3);
      if (k % 3 == 0)
        cv::ellipse(shapes, c, cv::Size(a, b), rng.uniform(0.0, 180.0), 0, 360, cv::Scalar(value), -1,
                    cv::LINE_AA);
      else if (k % 3 == 1)
        cv::line(shapes, c, cv::Point(c.x + a, c.y + b), cv::Scalar(value), std::max(1, w / 200),
                 cv::LINE_AA);
      else
        cv::rectangle(shapes, cv::Rect(c.x, c.y, a, b), cv::Scalar(value * 0.5), -1, cv::LINE_AA);
    }
    cv::GaussianBlur(shapes, shapes, cv::Size(0, 0), std::max(1.0, w / 320.0));
    bg += shapes;
    cv::max(bg, 5.0, bg);
    cv::min(bg, 250.0, bg);
  }
  cache->background = bg.mul(cache->lighting);
  // Distorted cameras: the undistorted ray and its Jacobian at every pixel centre.
  cache->distorted = m.model != DistortionModel::kNone;
  if (cache->distorted) {
    cache->rays.create(h, w, CV_64FC2);
    cache->jacobians.create(h, w, CV_64FC4);
    const internal::ValidRegion region(m);
    for (int v = 0; v < h; ++v) {
      cv::Vec2d* ray = cache->rays.ptr<cv::Vec2d>(v);
      cv::Vec4d* jac = cache->jacobians.ptr<cv::Vec4d>(v);
      for (int u = 0; u < w; ++u) {
        double x, y;
        if (!internal::UndistortNormalized(m, region, (u - m.cx) / m.fx, (v - m.cy) / m.fy, &x, &y)) {
          ray[u] = cv::Vec2d(NAN, NAN);
          jac[u] = cv::Vec4d(0, 0, 0, 0);
          continue;
        }
        ray[u] = cv::Vec2d(x, y);
        // d(pixel)/d(undistorted normalised) from the camera model's analytic projection Jacobian at
        // z = 1 (its first two columns), inverted.
        Eigen::Vector2d pixel;
        Eigen::Matrix<double, 2, 3> d_pixel;
        m.Project(Eigen::Vector3d(x, y, 1.0), &pixel, &d_pixel);
        const Eigen::Matrix2d inv = d_pixel.leftCols<2>().inverse();
        jac[u] = cv::Vec4d(inv(0, 0), inv(0, 1), inv(1, 0), inv(1, 1));
      }
    }
  }
  caches.push_back(std::move(cache));
  return *caches.back();
}

namespace {

// Patch `p` as `camera` sees it, with its pixel bounds (from points along its outline: edges curve under
// distortion; the whole image where the outline leaves the model's valid region); nothing for a back face,
// a face seen edge-on or one outside the image.
std::optional<ViewPatch> SeePatch(const Patch& p, const CameraModel& m, const CameraCache& cache,
                                  const internal::ValidRegion& region, const Rigid3& cam_from_object) {
  ViewPatch vp;
  vp.patch = &p;
  vp.origin = cam_from_object * p.origin;
  vp.e1 = cam_from_object.linear() * p.e1;
  vp.e2 = cam_from_object.linear() * p.e2;
  vp.normal = cam_from_object.linear() * p.normal;
  vp.n_dot_origin = vp.normal.dot(vp.origin);
  if (!(vp.n_dot_origin < 0)) return std::nullopt;  // back face (or seen edge-on)
  double umin = 1e300, umax = -1e300, vmin = 1e300, vmax = -1e300;
  bool unbounded = false;
  const size_t k = p.outline.size();
  for (size_t i = 0; i < k && !unbounded; ++i) {
    const Vec2& a = p.outline[i];
    const Vec2& b = p.outline[(i + 1) % k];
    const int steps = cache.distorted ? 8 : 1;
    for (int s = 0; s < steps; ++s) {
      const Vec2 q = a + (b - a) * (static_cast<double>(s) / steps);
      const Eigen::Vector3d x = vp.origin + q.x() * vp.e1 + q.y() * vp.e2;
      if (!(x.z() > 1e-6) || !region.Contains(x.x() / x.z(), x.y() / x.z())) {
        unbounded = true;
        break;
      }
      double px[2] = {0, 0};
      m.Project(x.data(), px);
      umin = std::min(umin, px[0]);
      umax = std::max(umax, px[0]);
      vmin = std::min(vmin, px[1]);
      vmax = std::max(vmax, px[1]);
    }
  }
  if (unbounded) {
    vp.u0 = 0, vp.u1 = m.width - 1, vp.v0 = 0, vp.v1 = m.height - 1;
    return vp;
  }
  const double margin = cache.distorted ? 3.0 : 1.5;
  vp.u0 = std::max(0, static_cast<int>(std::floor(umin - margin)));
  vp.u1 = std::min(m.width - 1, static_cast<int>(std::ceil(umax + margin)));
  vp.v0 = std::max(0, static_cast<int>(std::floor(vmin - margin)));
  vp.v1 = std::min(m.height - 1, static_cast<int>(std::ceil(vmax + margin)));
  if (vp.u0 > vp.u1 || vp.v0 > vp.v1) return std::nullopt;
  return vp;
}

// The undistorted ray (nx, ny, 1) through a pixel's centre and its Jacobian j with respect to the pixel.
struct PixelRay {
  double nx, ny, j00, j01, j10, j11;
};

// False where the pixel has no ray (outside a distortion model's valid region).
bool RayAt(const CameraModel& m, const CameraCache& cache, int u, int v, PixelRay* r) {
  if (cache.distorted) {
    const cv::Vec2d ray = cache.rays.at<cv::Vec2d>(v, u);
    if (!(ray[0] == ray[0])) return false;
    const cv::Vec4d j = cache.jacobians.at<cv::Vec4d>(v, u);
    *r = {ray[0], ray[1], j[0], j[1], j[2], j[3]};
    return true;
  }
  *r = {(u - m.cx) / m.fx, (v - m.cy) / m.fy, 1.0 / m.fx, 0, 0, 1.0 / m.fy};
  return true;
}

// Plain SxS point supersampling (comparison mode): the nearest patch hit per sample, the mean of the
// samples' values (`background` where no patch is hit); `lit`: the light's relative level at the pixel.
double SupersampledValue(const std::vector<const ViewPatch*>& candidates, const PixelRay& r, int ss,
                         double lit, double background, const RenderOptions& o) {
  double sum = 0;
  for (int sy = 0; sy < ss; ++sy)
    for (int sx = 0; sx < ss; ++sx) {
      const double du = (sx + 0.5) / ss - 0.5, dv = (sy + 0.5) / ss - 0.5;
      const Eigen::Vector3d ray(r.nx + r.j00 * du + r.j01 * dv, r.ny + r.j10 * du + r.j11 * dv, 1.0);
      double best_depth = 1e300, value = background;
      for (const ViewPatch* vp : candidates) {
        const double denom = vp->normal.dot(ray);
        if (!(denom < 0)) continue;
        const double t = vp->n_dot_origin / denom;
        const Eigen::Vector3d x = t * ray - vp->origin;
        const Vec2 q(vp->e1.dot(x), vp->e2.dot(x));
        const Patch& p = *vp->patch;
        bool inside = true;
        for (const auto& [n, d] : p.half_planes)
          if (n.dot(q) > d) inside = false;
        if (!inside) continue;
        const double key = t - (p.is_marker ? 1e-5 : 0.0);
        if (key >= best_depth) continue;
        best_depth = key;
        if (p.is_marker) {
          const int col = std::clamp(static_cast<int>(std::floor((q.x() + p.half) / p.cell)), 0, p.grid - 1);
          const int row = std::clamp(static_cast<int>(std::floor((p.half - q.y()) / p.cell)), 0, p.grid - 1);
          value = lit * vp->shade * (p.cells[row * p.grid + col] ? o.white_level : o.black_level);
        } else {
          value = lit * vp->shade * 255.0 * p.albedo * Grain(o, q);
        }
      }
      sum += value;
    }
  return sum / (ss * ss);
}

// One patch's part of a pixel: the depth along the ray (markers a little in front of the face they are
// glued on), the share of the pixel's footprint it covers, its level there.
struct Hit {
  double depth, coverage, value;
};

// The footprint `par` (patch coordinates, area `det`, bounds [xmin, xmax] x [ymin, ymax]) on marker `p`'s
// cells: the covered share and the mean level over the cells it covers. False where it covers no cell.
bool MarkerFootprint(const Patch& p, const Poly& par, double det, double pxmin, double pxmax, double pymin,
                     double pymax, const RenderOptions& o, double* coverage, double* value) {
  const double white = o.white_level, black = o.black_level;
  const double inv = 1.0 / p.cell;
  const CellSpan columns = CellsOverlapping((pxmin + p.half) * inv, (pxmax + p.half) * inv, p.grid);
  const CellSpan rows = CellsOverlapping((p.half - pymax) * inv, (p.half - pymin) * inv, p.grid);
  const int j0 = columns.first, j1 = columns.last, i0 = rows.first, i1 = rows.last;
  if (j0 > j1 || i0 > i1) return false;  // the footprint lies in the margin: no cell to read
  const bool inside = pxmin >= -p.half && pxmax <= p.half && pymin >= -p.half && pymax <= p.half;
  if (inside && j0 == j1 && i0 == i1) {
    *coverage = 1.0;
    *value = p.cells[i0 * p.grid + j0] ? white : black;
    return true;
  }
  double total = 0, white_area = 0;
  // Fast path: all the cells in range have the same colour -> one clip against their union.
  uint8_t first = p.cells[i0 * p.grid + j0];
  bool uniform = true;
  for (int i = i0; i <= i1 && uniform; ++i)
    for (int j = j0; j <= j1; ++j)
      if (p.cells[i * p.grid + j] != first) {
        uniform = false;
        break;
      }
  if (uniform) {
    total = RectArea(par, -p.half + j0 * p.cell, p.half - (i1 + 1) * p.cell, -p.half + (j1 + 1) * p.cell,
                     p.half - i0 * p.cell);
    white_area = first ? total : 0.0;
  } else {
    for (int i = i0; i <= i1; ++i)
      for (int j = j0; j <= j1; ++j) {
        const double area = RectArea(par, -p.half + j * p.cell, p.half - (i + 1) * p.cell,
                                     -p.half + (j + 1) * p.cell, p.half - i * p.cell);
        total += area;
        if (p.cells[i * p.grid + j]) white_area += area;
      }
  }
  if (!(total > 0)) return false;
  *coverage = std::min(1.0, total / det);
  *value = (white_area * white + (total - white_area) * black) / total;
  return true;
}

// Patch vp's part of the pixel whose footprint is the parallelogram the pixel square maps to on the
// patch's plane (through the ray's Jacobian). False where the footprint misses the patch.
bool FootprintHit(const ViewPatch& vp, const PixelRay& r, double lit, const RenderOptions& o, Poly* par,
                  Hit* hit) {
  const Eigen::Vector3d ray(r.nx, r.ny, 1.0);
  const double denom = vp.normal.dot(ray);
  if (!(denom < 0)) return false;
  const double t = vp.n_dot_origin / denom;
  const Eigen::Vector3d x = t * ray;
  const Eigen::Vector3d rel = x - vp.origin;
  const Vec2 c(vp.e1.dot(rel), vp.e2.dot(rel));
  // d(x)/d(nx) = t (e_x - ray (N . e_x) / denom), likewise for ny.
  const Eigen::Vector3d dx_dnx = t * (Eigen::Vector3d::UnitX() - ray * (vp.normal.x() / denom));
  const Eigen::Vector3d dx_dny = t * (Eigen::Vector3d::UnitY() - ray * (vp.normal.y() / denom));
  Eigen::Matrix2d dq_dn;
  dq_dn << vp.e1.dot(dx_dnx), vp.e1.dot(dx_dny), vp.e2.dot(dx_dnx), vp.e2.dot(dx_dny);
  Eigen::Matrix2d dn_dp;
  dn_dp << r.j00, r.j01, r.j10, r.j11;
  const Eigen::Matrix2d jac = dq_dn * dn_dp;  // patch coordinates per pixel
  const Vec2 a = 0.5 * jac.col(0), b = 0.5 * jac.col(1);
  const double det = std::abs(jac.determinant());
  if (!(det > 0)) return false;
  (*par)[0] = c - a - b;
  (*par)[1] = c + a - b;
  (*par)[2] = c + a + b;
  (*par)[3] = c - a + b;
  const double ext_x = std::abs(a.x()) + std::abs(b.x()), ext_y = std::abs(a.y()) + std::abs(b.y());
  const double pxmin = c.x() - ext_x, pxmax = c.x() + ext_x, pymin = c.y() - ext_y, pymax = c.y() + ext_y;
  const Patch& p = *vp.patch;
  if (pxmax <= p.xmin || pxmin >= p.xmax || pymax <= p.ymin || pymin >= p.ymax) return false;
  double coverage, value;
  if (p.is_marker) {
    if (!MarkerFootprint(p, *par, det, pxmin, pxmax, pymin, pymax, o, &coverage, &value)) return false;
  } else {
    bool inside = true;
    for (const Vec2& q : *par)
      for (const auto& [n, d] : p.half_planes)
        if (n.dot(q) > d) inside = false;
    if (inside) {
      coverage = 1.0;
    } else {
      const double area = ClippedArea(*par, p.half_planes);
      if (!(area > 0)) return false;
      coverage = std::min(1.0, area / det);
    }
    value = 255.0 * p.albedo * Grain(o, c);
  }
  *hit = {t - (p.is_marker ? 1e-5 : 0.0), coverage, lit * vp.shade * value};
  return true;
}

// The hits composited front to back, each covering what the nearer ones left of the pixel, the rest
// `background`.
double Composite(std::vector<Hit>* hits, double background) {
  std::sort(hits->begin(), hits->end(), [](const Hit& x, const Hit& y) { return x.depth < y.depth; });
  double rem = 1.0, acc = 0.0;
  for (const Hit& hit : *hits) {
    const double use = std::min(rem, hit.coverage);
    acc += use * hit.value;
    rem -= use;
    if (rem <= 1e-12) break;
  }
  if (rem > 0) acc += rem * background;
  return acc;
}

}  // namespace

void Renderer::Impl::RenderInto(const SimCamera& camera, const CameraCache& cache,
                                const Rigid3& rig_from_object, const RenderOptions& o, cv::Mat* image) const {
  const CameraModel& m = camera.model;
  const Rigid3 cam_from_object = Inverse(camera.rig_from_cam) * rig_from_object;
  const internal::ValidRegion region(m);
  std::vector<ViewPatch> views;
  int bu0 = m.width, bu1 = -1, bv0 = m.height, bv1 = -1;
  for (const Patch& p : patches) {
    std::optional<ViewPatch> vp = SeePatch(p, m, cache, region, cam_from_object);
    if (!vp) continue;
    const Eigen::Vector3d normal_rig = rig_from_object.linear() * p.normal;
    vp->shade = 1.0 - o.shading * (1.0 - std::max(0.0, normal_rig.dot(light_in_rig)));
    views.push_back(*vp);
    bu0 = std::min(bu0, vp->u0);
    bu1 = std::max(bu1, vp->u1);
    bv0 = std::min(bv0, vp->v0);
    bv1 = std::max(bv1, vp->v1);
  }
  if (views.empty()) return;

  std::vector<Hit> hits;
  std::vector<const ViewPatch*> candidates;
  Poly par(4);
  for (int v = bv0; v <= bv1; ++v) {
    float* out = image->ptr<float>(v);
    const float* light = cache.lighting.ptr<float>(v);
    const float* bg = cache.background.ptr<float>(v);
    for (int u = bu0; u <= bu1; ++u) {
      candidates.clear();
      for (const ViewPatch& vp : views)
        if (u >= vp.u0 && u <= vp.u1 && v >= vp.v0 && v <= vp.v1) candidates.push_back(&vp);
      if (candidates.empty()) continue;
      PixelRay ray;
      if (!RayAt(m, cache, u, v, &ray)) continue;
      const double lit = light[u];
      if (o.supersampling >= 1) {
        out[u] = static_cast<float>(SupersampledValue(candidates, ray, o.supersampling, lit, bg[u], o));
        continue;
      }
      hits.clear();
      for (const ViewPatch* vp : candidates) {
        Hit hit;
        if (FootprintHit(*vp, ray, lit, o, &par, &hit)) hits.push_back(hit);
      }
      if (hits.empty()) continue;
      out[u] = static_cast<float>(Composite(&hits, bg[u]));
    }
  }
}

cv::Mat Renderer::RenderIdeal(const SimCamera& camera, int camera_index,
                              const Rigid3& rig_from_object) const {
  const RenderOptions& o = options_.ForCamera(camera_index);
  const CameraCache& cache = impl_->Cache(camera, camera_index, o);
  cv::Mat image = cache.background.clone();
  impl_->RenderInto(camera, cache, rig_from_object, o, &image);
  return image;
}

namespace {

// The optics on the scene's linear image: Gaussian blur, defocus disc (its area per kernel cell),
// vignetting.
void Optics(const RenderOptions& o, cv::Mat* image) {
  if (o.blur_sigma > 0) cv::GaussianBlur(*image, *image, cv::Size(0, 0), o.blur_sigma);
  if (o.defocus_radius > 0) {
    const double radius = o.defocus_radius;
    const int r = static_cast<int>(std::ceil(radius)) + 1;
    cv::Mat kernel(2 * r + 1, 2 * r + 1, CV_32F, cv::Scalar(0));
    for (int y = 0; y < kernel.rows; ++y)
      for (int x = 0; x < kernel.cols; ++x) {
        int inside = 0;
        for (int a = 0; a < 8; ++a)
          for (int b = 0; b < 8; ++b) {
            const double dx = x - r - 0.5 + (b + 0.5) / 8, dy = y - r - 0.5 + (a + 0.5) / 8;
            inside += dx * dx + dy * dy <= radius * radius;
          }
        kernel.at<float>(y, x) = static_cast<float>(inside);
      }
    kernel /= cv::sum(kernel)[0];
    cv::filter2D(*image, *image, -1, kernel, cv::Point(-1, -1), 0, cv::BORDER_REFLECT);
  }
  if (o.vignetting > 0) {
    const double cx = 0.5 * (image->cols - 1), cy = 0.5 * (image->rows - 1), r2 = cx * cx + cy * cy;
    for (int y = 0; y < image->rows; ++y) {
      float* row = image->ptr<float>(y);
      for (int x = 0; x < image->cols; ++x)
        row[x] *= static_cast<float>(1.0 - o.vignetting * ((x - cx) * (x - cx) + (y - cy) * (y - cy)) / r2);
    }
  }
}

// The sensor and the camera's processing on one linear channel: read and shot noise, gamma encoding,
// sharpening (the result is still float; quantisation and JPEG follow).
void Sensor(const RenderOptions& o, cv::RNG* rng, cv::Mat* c) {
  if (o.noise_sigma > 0) {
    cv::Mat noise(c->size(), CV_32F);
    rng->fill(noise, cv::RNG::NORMAL, 0.0, o.noise_sigma);
    *c += noise;
  }
  if (o.shot_noise > 0) {  // variance shot_noise * level: unit normal noise scaled per pixel
    cv::Mat noise(c->size(), CV_32F), level;
    rng->fill(noise, cv::RNG::NORMAL, 0.0, 1.0);
    cv::max(*c, 0.0, level);
    cv::sqrt(level * o.shot_noise, level);
    *c += noise.mul(level);
  }
  if (o.gamma != 1.0) {
    cv::max(*c, 0.0, *c);
    cv::min(*c, 255.0, *c);
    *c *= 1.0 / 255.0;
    cv::pow(*c, 1.0 / o.gamma, *c);
    *c *= 255.0;
  }
  if (o.sharpen > 0) {
    cv::Mat smooth;
    cv::GaussianBlur(*c, smooth, cv::Size(0, 0), 1.0);
    *c += o.sharpen * (*c - smooth);
  }
}

}  // namespace

cv::Mat Renderer::Render(const SimCamera& camera, int camera_index, int64_t frame,
                         const Rigid3& rig_from_object, const Rigid3* previous_rig_from_object) const {
  const RenderOptions& o = options_.ForCamera(camera_index);
  const CameraCache& cache = impl_->Cache(camera, camera_index, o);
  cv::Mat image;
  if (o.motion_blur_samples > 1 && previous_rig_from_object != nullptr) {
    // Average over the exposure, which ends at the frame's pose: poses interpolated between the
    // previous frame's and this one's (slerp / lerp).
    const Eigen::Quaterniond q0(previous_rig_from_object->linear()), q1(rig_from_object.linear());
    const Eigen::Vector3d t0 = previous_rig_from_object->translation(), t1 = rig_from_object.translation();
    image = cv::Mat::zeros(camera.model.height, camera.model.width, CV_32F);
    const int n = o.motion_blur_samples;
    for (int k = 0; k < n; ++k) {
      const double s = 1.0 - o.exposure_fraction * (n - 1 - k) / std::max(1, n - 1);
      Rigid3 pose = Rigid3::Identity();
      pose.linear() = q0.slerp(s, q1).toRotationMatrix();
      pose.translation() = (1 - s) * t0 + s * t1;
      cv::Mat one = cache.background.clone();
      impl_->RenderInto(camera, cache, pose, o, &one);
      image += one;
    }
    image *= 1.0 / n;
  } else {
    image = cache.background.clone();
    impl_->RenderInto(camera, cache, rig_from_object, o, &image);
  }
  Optics(o, &image);
  cv::RNG rng(Mix(Mix(o.seed) ^ (static_cast<uint64_t>(camera_index) * 0x51ed27ULL) ^
                  (static_cast<uint64_t>(frame) * 0x2545f4914f6cdd1dULL)));
  cv::Mat result;
  if (o.bgr) {
    std::vector<cv::Mat> channels = {image * 0.96, image.clone(), image * 1.03};
    for (cv::Mat& c : channels) Sensor(o, &rng, &c);
    cv::Mat merged;
    cv::merge(channels, merged);
    merged.convertTo(result, CV_8UC3);
  } else {
    Sensor(o, &rng, &image);
    image.convertTo(result, CV_8U);
  }
  if (o.jpeg_quality > 0) {
    std::vector<uint8_t> buffer;
    cv::imencode(".jpg", result, buffer, {cv::IMWRITE_JPEG_QUALITY, o.jpeg_quality});
    result = cv::imdecode(buffer, o.bgr ? cv::IMREAD_COLOR : cv::IMREAD_GRAYSCALE);
  }
  return result;
}

RenderOptions RandomImaging(const RenderOptions& base, int cameras, uint64_t seed,
                            std::vector<std::string>* summary) {
  std::mt19937_64 rng(Mix(seed ^ 0x1a2b3c4d5e6fULL));
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  auto range = [&](double lo, double hi) { return lo + (hi - lo) * uni(rng); };
  RenderOptions session = base;
  session.cameras.clear();
  // The print and the surface, shared by every camera of the session.
  session.quiet_zone_cells = static_cast<int>(std::floor(range(0.0, 2.999)));
  // A dark surface needs a margin: markers glued on black without one have no outer edge to find.
  session.surface_albedo = session.quiet_zone_cells == 0 ? range(0.3, 0.9) : range(0.05, 0.9);
  session.surface_texture = uni(rng) < 0.5 ? 0.0 : range(0.05, 0.3);
  for (double& t : session.surface_tint) t = range(0.8, 1.2);
  session.shading = range(0.0, 0.5);
  for (int k = 0; k < cameras; ++k) {
    RenderOptions c = session;
    c.lighting_gradient = range(0.0, 0.4);
    c.vignetting = range(0.0, 0.35);
    c.blur_sigma = 0.0, c.defocus_radius = 0.0;
    if (uni(rng) < 0.5)
      c.blur_sigma = range(0.3, 1.2);
    else
      c.defocus_radius = range(0.5, 1.6);
    c.noise_sigma = range(1.0, 3.0);
    c.shot_noise = range(0.0, 0.12);
    c.gamma = uni(rng) < 0.25 ? 1.0 : range(1.8, 2.4);
    c.sharpen = uni(rng) < 0.4 ? 0.0 : range(0.2, 0.8);
    c.jpeg_quality = uni(rng) < 0.3 ? 0 : static_cast<int>(std::lround(range(60, 95)));
    if (summary) summary->push_back(DescribeImaging(c));
    session.cameras.push_back(c);
  }
  return session;
}

std::string DescribeImaging(const RenderOptions& o) {
  char text[512];
  std::snprintf(
      text, sizeof(text),
      "margin %d cells, surface %.2f (grain %.2f), shading %.2f, gradient %.2f, vignetting %.2f, "
      "blur %.2f px, defocus %.2f px, noise %.1f + shot %.3f/level, gamma %.2f, sharpen %.2f, jpeg %d",
      o.quiet_zone_cells, o.surface_albedo, o.surface_texture, o.shading, o.lighting_gradient, o.vignetting,
      o.blur_sigma, o.defocus_radius, o.noise_sigma, o.shot_noise, o.gamma, o.sharpen, o.jpeg_quality);
  return text;
}

namespace internal {

bool UndistortNormalized(const CameraModel& model, const ValidRegion& region, double xd, double yd, double* x,
                         double* y) {
  if (model.model == DistortionModel::kNone) {
    *x = xd, *y = yd;
    return true;
  }
  // The camera model's own unprojection (core/camera), checked by projecting back.
  const Eigen::Vector2d pixel(model.fx * xd + model.cx, model.fy * yd + model.cy);
  const Eigen::Vector2d u = model.Unproject(pixel);
  if (!u.allFinite() || !region.Contains(u.x(), u.y())) return false;
  const Eigen::Vector2d back = model.Project(Eigen::Vector3d(u.x(), u.y(), 1.0));
  if (!((back - pixel).norm() < 1e-7 * std::max(1.0, model.fx))) return false;
  *x = u.x(), *y = u.y();
  return true;
}

}  // namespace internal

}  // namespace sim
}  // namespace mcmt
