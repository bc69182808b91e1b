// Helpers shared by the simulator's sources (not part of the public API).
#pragma once

#include <Eigen/Core>

#include "core/camera.h"
#include "core/se3.h"
#include "sim/sim.h"

namespace mcmt {
namespace sim {
namespace internal {

// Normalised image points a camera model maps one-to-one: beyond the first turning point of the
// radial distortion a point far outside the field of view could fold back into the image.
struct ValidRegion {
  explicit ValidRegion(const CameraModel& model);  // cached per distortion model and coefficients
  bool Contains(double x, double y) const { return x * x + y * y <= max_r2; }
  double max_r2 = 1e30;
};

// Does the open segment from -> to (object frame) cross a face of the object's body?
bool SegmentHitsBody(const SimObject& object, const Eigen::Vector3d& from, const Eigen::Vector3d& to);

// Undistorted normalised coordinates of a distorted normalised point (Newton; false if not converged
// or outside the valid region).
bool UndistortNormalized(const CameraModel& model, const ValidRegion& region, double xd, double yd, double* x,
                         double* y);

}  // namespace internal
}  // namespace sim
}  // namespace mcmt
