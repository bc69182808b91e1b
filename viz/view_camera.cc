#include "viz/view_camera.h"

#include <mrpt/opengl/CCamera.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace mcmt::viz {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

// Right, up and forward unit vectors of the eye, as gluLookAt builds them (MRPT's applyLookAt):
// forward f = normalize(pointing - eye), right s = normalize(f x up0), up u = s x f, where up0 is
// world +Z except when looking straight up or down.
void EyeBasis(const ViewCamera& c, Eigen::Vector3d* s, Eigen::Vector3d* u, Eigen::Vector3d* f) {
  const double az = c.azimuth_deg * kDegToRad;
  *f = (c.pointing - c.Eye()).normalized();
  Eigen::Vector3d up0(0, 0, 1);
  if (std::abs(std::abs(c.elevation_deg) - 90.0) <= 1e-6) {
    const double sgn = c.elevation_deg > 0 ? 1.0 : -1.0;
    up0 = Eigen::Vector3d(-std::cos(az) * sgn, -std::sin(az) * sgn, 0.0);
  }
  *s = f->cross(up0).normalized();
  *u = s->cross(*f);
}

}  // namespace

Eigen::Vector3d ViewCamera::Eye() const {
  const double az = azimuth_deg * kDegToRad, el = elevation_deg * kDegToRad;
  const double d = std::max(0.01, distance);
  return pointing +
         d * Eigen::Vector3d(std::cos(az) * std::cos(el), std::sin(az) * std::cos(el), std::sin(el));
}

double ViewCamera::Depth(const Eigen::Vector3d& p_world) const {
  Eigen::Vector3d s, u, f;
  EyeBasis(*this, &s, &u, &f);
  return f.dot(p_world - Eye());
}

bool ViewCamera::Project(const Eigen::Vector3d& p_world, Eigen::Vector2d* pixel) const {
  Eigen::Vector3d s, u, f;
  EyeBasis(*this, &s, &u, &f);
  const Eigen::Vector3d d = p_world - Eye();
  const double x = s.dot(d), y = u.dot(d), z = f.dot(d);
  if (!(z > 1e-9)) return false;
  // Perspective: normalised device coordinates in [-1, 1] over the viewport,
  //   ndc_x = x / (z tan(fov/2) aspect),  ndc_y = y / (z tan(fov/2)),  aspect = width / height.
  const double t = std::tan(0.5 * fov_deg * kDegToRad);
  const double aspect = static_cast<double>(viewport_width) / viewport_height;
  const double ndc_x = x / (z * t * aspect), ndc_y = y / (z * t);
  // Viewport pixels, then flipped to a top-left image origin.
  const double col = viewport_x + 0.5 * (ndc_x + 1.0) * viewport_width;
  const double row_from_bottom = viewport_y + 0.5 * (ndc_y + 1.0) * viewport_height;
  (*pixel) << col, image_height - row_from_bottom;
  return std::abs(ndc_x) <= 1.0 && std::abs(ndc_y) <= 1.0;
}

void ViewCamera::ApplyTo(mrpt::opengl::CCamera* camera) const {
  camera->set6DOFMode(false);
  camera->setProjectiveModel(true);
  camera->setPointingAt(static_cast<float>(pointing.x()), static_cast<float>(pointing.y()),
                        static_cast<float>(pointing.z()));
  camera->setAzimuthDegrees(static_cast<float>(azimuth_deg));
  camera->setElevationDegrees(static_cast<float>(elevation_deg));
  camera->setZoomDistance(static_cast<float>(std::max(0.01, distance)));
  camera->setProjectiveFOVdeg(static_cast<float>(fov_deg));
}

void FramePoints(const std::vector<Eigen::Vector3d>& points, double margin, ViewCamera* camera) {
  if (points.empty()) return;
  Eigen::Vector3d lo = points[0], hi = points[0];
  for (const auto& p : points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  camera->pointing = 0.5 * (lo + hi);
  double radius = 0.0;
  for (const auto& p : points) radius = std::max(radius, (p - camera->pointing).norm());
  radius = std::max(radius, 0.05);
  // Every point fits at this distance: the bounding sphere inside the narrower half-angle.
  const double half_v = 0.5 * camera->fov_deg * kDegToRad;
  const double aspect = static_cast<double>(camera->viewport_width) / camera->viewport_height;
  const double half_h = std::atan(std::tan(half_v) * aspect);
  const double shrink = std::max(0.05, 1.0 - 2.0 * margin);
  const double half = std::atan(std::tan(std::min(half_v, half_h)) * shrink);
  double far_ok = radius / std::sin(half) * 1.02;
  const int w = camera->viewport_width, h = camera->viewport_height;
  auto fits = [&](double distance) {
    ViewCamera c = *camera;
    c.distance = distance;
    const double mx = margin * w, my = margin * h;
    const double top = c.image_height - c.viewport_y - h;
    for (const auto& p : points) {
      Eigen::Vector2d px;
      if (c.Depth(p) < 0.05 * radius) return false;
      if (!c.Project(p, &px)) return false;
      if (px.x() < c.viewport_x + mx || px.x() > c.viewport_x + w - mx) return false;
      if (px.y() < top + my || px.y() > top + h - my) return false;
    }
    return true;
  };
  // Bisection on the distance between a fitting and a (possibly) too-close one.
  double near_bad = 0.0;
  for (int i = 0; i < 30 && far_ok - near_bad > 0.01 * far_ok; ++i) {
    const double mid = 0.5 * (near_bad + far_ok);
    if (fits(mid))
      far_ok = mid;
    else
      near_bad = mid;
  }
  camera->distance = far_ok;
}

}  // namespace mcmt::viz
