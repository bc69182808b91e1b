// Square marker geometry. Corners in the marker frame, ArUco order (what SOLVEPNP_IPPE_SQUARE
// expects): (-s/2, s/2, 0), (s/2, s/2, 0), (s/2, -s/2, 0), (-s/2, -s/2, 0); z out of the face.
#pragma once

#include <Eigen/Core>
#include <array>
#include <map>
#include <optional>
#include <string>

namespace mcmt {

using MarkerCorners3d = std::array<Eigen::Vector3d, 4>;
using MarkerCorners2d = std::array<Eigen::Vector2d, 4>;

MarkerCorners3d MarkerCornersInMarker(double side);

// Square-root information of each observed corner when the corners are intersections of the quad's fitted
// sides (what the detector's refinement does) and each side is located to the same precision along its
// normal at both of its ends. Corner k lies on the sides towards k - 1 and k + 1, with unit normals n1, n2:
//   Omega_k = (n1 n1^T + n2 n2^T + floor I) * 2 / (2 + 2 floor),   W_k^T W_k = Omega_k   (trace 2)
// A corner where the sides meet at a right angle gets W = I (the plain pixel residual); where they meet
// at a narrow angle (a marker seen at a steep angle, the corners of its long diagonal and also the obtuse
// ones) the direction along both sides is barely measured and gets little weight, the one across them
// more. `floor` (>= 0, relative) keeps every direction's weight above floor / (1 + floor).
using CornerWeights = std::array<Eigen::Matrix2d, 4>;
CornerWeights CornerSqrtInformation(const MarkerCorners2d& corners, double floor);
// How the corners' residuals weigh in a pose or bundle solve: the options corner_weights (`mode`) and
// corner_weight_floor (`floor`) of the mapper and the tracker, one struct in both option sets.
struct CornerWeighting {
  std::string mode = "equal";  // "equal" or "sides" (kCornerWeightsHelp)
  double floor = 0.05;         // relative (kCornerWeightFloorHelp)
  bool BySides() const { return mode == "sides"; }
  // By sides: CornerSqrtInformation(corners, floor); equal: nullopt (the plain pixel residual).
  std::optional<CornerWeights> For(const MarkerCorners2d& corners) const {
    if (!BySides()) return std::nullopt;
    return CornerSqrtInformation(corners, floor);
  }
};
// The help of the options that choose it.
inline constexpr const char* kCornerWeightsHelp =
    "equal (each corner's x and y residual weighs the same) or sides (corners as intersections of the "
    "marker's fitted sides: along two sides meeting at a narrow angle a corner weighs little)";
inline constexpr const char* kCornerWeightFloorHelp =
    "with corner_weights sides: the least weight of a direction, relative";

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
