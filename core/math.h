// Small pieces of math used across components, each written once: the cross-product matrix, the median,
// the principal direction of a 2-D scatter, and a camera pose looking at a point.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <vector>

#include "core/se3.h"

namespace mcmt {

// [v]x: Skew(v) * u = v.cross(u).
inline Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

// The upper median (element n/2 of the sorted values; no averaging for even n), `empty` when there is
// none. MedianInPlace reorders *values instead of taking a copy (no allocation: hot loops keep a buffer).
template <typename T>
double MedianInPlace(std::vector<T>* values, double empty = 0.0) {
  if (values->empty()) return empty;
  const auto mid = values->begin() + values->size() / 2;
  std::nth_element(values->begin(), mid, values->end());
  return static_cast<double>(*mid);
}
template <typename T>
double Median(std::vector<T> values, double empty = 0.0) {
  return MedianInPlace(&values, empty);
}

// The unit direction of largest spread of a 2-D scatter [[sxx, sxy], [sxy, syy]] (its eigenvector of
// the larger eigenvalue), with x > 0, or x = 0 and y > 0; (1, 0) where the scatter is isotropic. From
// the closed form lambda = (sxx + syy) / 2 + sqrt(((sxx - syy) / 2)^2 + sxy^2), in whichever of its two
// forms has no cancellation: (lambda - syy, sxy) or (sxy, lambda - sxx). Only +, -, *, / and sqrt, which
// IEEE 754 rounds correctly, so the result has the same bits on every machine (atan2, sin and cos come
// from the C library, whose last bits differ between CPUs and versions).
Eigen::Vector2d PrincipalDirection2d(double sxx, double sxy, double syy);

// world_from_cam of a camera at `position` looking at `target` in a world with z up, OpenCV camera axes
// (z forward, x right, y down, so the image's x axis is horizontal). Looking straight up or down, x is the
// world's y axis.
Rigid3 LookAt(const Eigen::Vector3d& position, const Eigen::Vector3d& target);

}  // namespace mcmt
