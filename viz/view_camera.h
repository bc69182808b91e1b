// The viewer's own camera: an orbit camera (MRPT's CCamera model) whose projection is computed here
// so that callers (tests, overlays) know where a 3D point lands in a rendered image.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace mrpt::opengl {
class CCamera;
}

namespace mcmt::viz {

// Orbit camera as MRPT renders it: the eye sits at
//   pointing + distance * (cos(az) cos(el), sin(az) cos(el), sin(el))
// looking at `pointing`, world +Z up, a perspective projection with the vertical field of view
// fov_deg over a viewport of viewport_width x viewport_height pixels whose lower-left corner is at
// (viewport_x, viewport_y) (OpenGL: y from the bottom) of an image image_height pixels tall.
struct ViewCamera {
  Eigen::Vector3d pointing = Eigen::Vector3d::Zero();
  double azimuth_deg = -110.0;
  double elevation_deg = 30.0;
  double distance = 5.0;
  double fov_deg = 45.0;  // vertical
  int viewport_x = 0, viewport_y = 0;
  int viewport_width = 1280, viewport_height = 720;
  int image_height = 720;

  Eigen::Vector3d Eye() const;
  // World point -> pixel of the whole rendered image (top-left origin, x right, y down, pixel
  // centres at integer + 0.5 from the top-left corner... i.e. (0.5, 0.5) is the centre of the
  // top-left pixel's area [0,1]^2). Returns false when the point is behind the eye or outside the
  // viewport.
  bool Project(const Eigen::Vector3d& p_world, Eigen::Vector2d* pixel) const;
  // Depth of a point along the viewing direction (positive in front of the eye).
  double Depth(const Eigen::Vector3d& p_world) const;

  // Copies the orbit parameters into an MRPT camera.
  void ApplyTo(mrpt::opengl::CCamera* camera) const;
};

// Frames the points: pointing at the centre of their bounding box, the given azimuth, elevation
// and field of view kept, and the smallest distance (within 2%) at which every point projects
// inside the viewport with `margin` (fraction of the viewport) to spare.
void FramePoints(const std::vector<Eigen::Vector3d>& points, double margin, ViewCamera* camera);

}  // namespace mcmt::viz
