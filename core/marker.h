// Square marker geometry. Corners in the marker frame, ArUco order (what SOLVEPNP_IPPE_SQUARE
// expects): (-s/2, s/2, 0), (s/2, s/2, 0), (s/2, -s/2, 0), (-s/2, -s/2, 0); z out of the face.
#pragma once

#include <Eigen/Core>
#include <array>
#include <map>

namespace mcmt {

using MarkerCorners3d = std::array<Eigen::Vector3d, 4>;
using MarkerCorners2d = std::array<Eigen::Vector2d, 4>;

MarkerCorners3d MarkerCornersInMarker(double side);

// Side lengths: a default plus per-id overrides.
struct MarkerSizes {
  double default_size = 0.0;
  std::map<int, double> overrides;
  double Get(int id) const {
    auto it = overrides.find(id);
    return it != overrides.end() ? it->second : default_size;
  }
};

}  // namespace mcmt
