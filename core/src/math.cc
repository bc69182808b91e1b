#include "core/math.h"

#include <Eigen/Geometry>
#include <cmath>

namespace mcmt {

Eigen::Vector2d PrincipalDirection2d(double sxx, double sxy, double syy) {
  const double half_difference = 0.5 * (sxx - syy);
  const double root = std::sqrt(half_difference * half_difference + sxy * sxy);
  // lambda - syy = half_difference + root (both >= 0 where sxx >= syy); lambda - sxx = root -
  // half_difference.
  Eigen::Vector2d direction = half_difference >= 0 ? Eigen::Vector2d(half_difference + root, sxy)
                                                   : Eigen::Vector2d(sxy, root - half_difference);
  const double norm = direction.norm();
  if (!(norm > 0)) return Eigen::Vector2d(1.0, 0.0);
  direction /= norm;
  if (direction.x() < 0 || (direction.x() == 0 && direction.y() < 0)) direction = -direction;
  return direction;
}

Rigid3 LookAt(const Eigen::Vector3d& position, const Eigen::Vector3d& target) {
  const Eigen::Vector3d forward = (target - position).normalized();
  Eigen::Vector3d right = forward.cross(Eigen::Vector3d::UnitZ());
  if (right.norm() < 1e-9) right = Eigen::Vector3d::UnitY();  // looking straight up or down
  right.normalize();
  const Eigen::Vector3d down = forward.cross(right);
  Rigid3 world_from_cam = Rigid3::Identity();
  world_from_cam.linear().col(0) = right;
  world_from_cam.linear().col(1) = down;
  world_from_cam.linear().col(2) = forward;
  world_from_cam.translation() = position;
  return world_from_cam;
}

}  // namespace mcmt
