#include "core/marker.h"

namespace mcmt {

MarkerCorners3d MarkerCornersInMarker(double side) {
  const double h = 0.5 * side;
  return {Eigen::Vector3d(-h, h, 0), Eigen::Vector3d(h, h, 0), Eigen::Vector3d(h, -h, 0),
          Eigen::Vector3d(-h, -h, 0)};
}

}  // namespace mcmt
