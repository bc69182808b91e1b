#include "core/marker.h"

#include <Eigen/Cholesky>

namespace mcmt {

MarkerCorners3d MarkerCornersInMarker(double side) {
  const double h = 0.5 * side;
  return {Eigen::Vector3d(-h, h, 0), Eigen::Vector3d(h, h, 0), Eigen::Vector3d(h, -h, 0),
          Eigen::Vector3d(-h, -h, 0)};
}

CornerWeights CornerSqrtInformation(const MarkerCorners2d& corners, double floor) {
  CornerWeights out;
  for (int k = 0; k < 4; ++k) {
    Eigen::Matrix2d omega = floor * Eigen::Matrix2d::Identity();
    for (int step : {1, 3}) {
      const Eigen::Vector2d d = corners[(k + step) % 4] - corners[k];
      const double length = d.norm();
      if (length <= 0) continue;
      const Eigen::Vector2d n(-d.y() / length, d.x() / length);
      omega += n * n.transpose();
    }
    omega *= 2.0 / (2.0 + 2.0 * floor);
    // Omega = L L^T, W = L^T: W^T W = Omega.
    Eigen::LLT<Eigen::Matrix2d> llt(omega);
    out[k] = llt.info() == Eigen::Success ? Eigen::Matrix2d(llt.matrixU()) : Eigen::Matrix2d::Identity();
  }
  return out;
}

}  // namespace mcmt
