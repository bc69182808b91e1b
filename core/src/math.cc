#include "core/math.h"

#include <Eigen/Geometry>

namespace mcmt {

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
