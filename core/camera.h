// Pinhole camera with OpenCV "radtan" (k1 k2 p1 p2 [k3 [k4 k5 k6]]) or Kannala-Brandt "fisheye"
// (k1..k4, OpenCV fisheye) distortion. Same formulas as cv::projectPoints / cv::fisheye::projectPoints.
// Pixel centres at integer coordinates (OpenCV's convention).
//
// Each distortion model is written once, in CameraModel::Distort below, templated on the scalar. Everything
// else follows from that one formula:
//   - Project (pixels) evaluates it on doubles, Ceres' Jets go through the templated Project;
//   - the Jacobian d pixel / d p_cam differentiates it with a small forward-mode dual number (DistortDual);
//   - Unproject inverts it by Newton's method with that Jacobian (fisheye: on FisheyeThetaD, its radial
//   part).
// To add a model:
//   1. add an enumerator to DistortionModel, its names to DistortionModelName / DistortionModelFromName
//      (core/src/camera.cc) and its coefficient count to Validate;
//   2. add its case to Distort (only +, -, *, /, sqrt, atan and comparisons on T, coefficients as T(d[i]));
//   3. if Newton on the 2-D formula does not converge over the image (strong radial models), give
//      Unproject a 1-D radial inversion as for fisheye;
//   4. add it to TestCameras() in tests/core/test_camera.cc (OpenCV agreement where OpenCV has it,
//      Jacobian against numeric and Jet derivatives, unprojection round trip over the whole image);
//   5. the file formats (core/src/config.cc, core/src/files.cc, lcmtypes camera_model_t) name it.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace mcmt {

enum class DistortionModel { kNone, kRadTan, kFisheye };

std::string DistortionModelName(DistortionModel model);            // "none", "radtan", "fisheye"
DistortionModel DistortionModelFromName(const std::string& name);  // throws std::invalid_argument

// A value and its derivatives with respect to two variables (x, y): the forward-mode differentiation
// that turns each Distort formula into its Jacobian. Only what the formulas use.
struct DistortDual {
  double v = 0.0, dx = 0.0, dy = 0.0;  // value, d/dx, d/dy
  DistortDual() = default;
  explicit DistortDual(double value) : v(value) {}
  DistortDual(double value, double d_dx, double d_dy) : v(value), dx(d_dx), dy(d_dy) {}
};
inline DistortDual operator+(const DistortDual& a, const DistortDual& b) {
  return {a.v + b.v, a.dx + b.dx, a.dy + b.dy};
}
inline DistortDual operator-(const DistortDual& a, const DistortDual& b) {
  return {a.v - b.v, a.dx - b.dx, a.dy - b.dy};
}
inline DistortDual operator*(const DistortDual& a, const DistortDual& b) {
  return {a.v * b.v, b.v * a.dx + a.v * b.dx, b.v * a.dy + a.v * b.dy};
}
inline DistortDual operator/(const DistortDual& a, const DistortDual& b) {
  const double q = 1.0 / (b.v * b.v);
  return {a.v / b.v, (b.v * a.dx - a.v * b.dx) * q, (b.v * a.dy - a.v * b.dy) * q};
}
inline bool operator>(const DistortDual& a, const DistortDual& b) { return a.v > b.v; }
inline DistortDual sqrt(const DistortDual& a) {
  const double s = std::sqrt(a.v), h = 0.5 / s;
  return {s, a.dx * h, a.dy * h};
}
inline DistortDual atan(const DistortDual& a) {
  const double h = 1.0 / (1.0 + a.v * a.v);
  return {std::atan(a.v), a.dx * h, a.dy * h};
}

struct CameraModel {
  int width = 0;
  int height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  DistortionModel model = DistortionModel::kNone;
  std::vector<double> distortion;  // radtan: 4, 5 or 8 values; fisheye: 4; none: empty

  // An undistorted camera of width x height px with focal length focal_px (fx = fy) and principal point
  // (cx, cy) px.
  static CameraModel Pinhole(int width, int height, double focal_px, double cx, double cy);

  // Throws std::invalid_argument naming the problem (non-positive focal length, wrong count...).
  void Validate() const;

  // Normalised image coordinates (x/z, y/z) -> distorted normalised coordinates: THE formula of each
  // model. Templated so that Ceres' Jets and DistortDual go through it.
  template <typename T>
  void Distort(const T& x, const T& y, T* xd, T* yd) const;
  // Fisheye's radial part: theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8).
  template <typename T>
  T FisheyeThetaD(const T& theta) const;
  // Distort with its 2x2 Jacobian d(xd, yd) / d(x, y), differentiated from Distort.
  void DistortWithJacobian(double x, double y, double* xd, double* yd, Eigen::Matrix2d* jacobian) const;

  // Camera-frame point -> pixel. Returns false when the point is behind the camera (z <= 0).
  template <typename T>
  bool Project(const T* p_cam, T* pixel) const {
    if (!(p_cam[2] > T(0))) return false;
    const T x = p_cam[0] / p_cam[2];
    const T y = p_cam[1] / p_cam[2];
    T xd, yd;
    Distort(x, y, &xd, &yd);
    pixel[0] = T(fx) * xd + T(cx);
    pixel[1] = T(fy) * yd + T(cy);
    return true;
  }

  // Pixel and, if jacobian is non-null, d pixel / d p_cam (2x3, row-major) analytically.
  bool Project(const Eigen::Vector3d& p_cam, Eigen::Vector2d* pixel,
               Eigen::Matrix<double, 2, 3>* jacobian = nullptr) const;
  Eigen::Vector2d Project(const Eigen::Vector3d& p_cam) const;  // NaNs when behind the camera

  // Pixel -> undistorted normalised coordinates (x/z, y/z), by iteration (converges to 1e-12 inside
  // the image for any calibration OpenCV would produce).
  Eigen::Vector2d Unproject(const Eigen::Vector2d& pixel) const;
  // Pixel -> pixel of the same ray in the ideal (undistorted) pinhole camera with the same K.
  Eigen::Vector2d Undistort(const Eigen::Vector2d& pixel) const;

  double HorizontalFovRad() const { return 2.0 * std::atan2(0.5 * width, fx); }
  bool InImage(const Eigen::Vector2d& pixel, double margin = 0.0) const;

  cv::Mat CameraMatrix() const;      // 3x3 CV_64F
  cv::Mat DistortionCoeffs() const;  // 1xN CV_64F (empty for none)
  bool operator==(const CameraModel& other) const;
};

template <typename T>
void CameraModel::Distort(const T& x, const T& y, T* xd, T* yd) const {
  const std::vector<double>& d = distortion;
  switch (model) {
    case DistortionModel::kNone:
      *xd = x;
      *yd = y;
      return;
    case DistortionModel::kRadTan: {
      const T r2 = x * x + y * y;
      const T r4 = r2 * r2, r6 = r4 * r2;
      const double k1 = d.size() > 0 ? d[0] : 0, k2 = d.size() > 1 ? d[1] : 0;
      const double p1 = d.size() > 2 ? d[2] : 0, p2 = d.size() > 3 ? d[3] : 0;
      const double k3 = d.size() > 4 ? d[4] : 0;
      T radial = T(1) + T(k1) * r2 + T(k2) * r4 + T(k3) * r6;
      if (d.size() >= 8) radial = radial / (T(1) + T(d[5]) * r2 + T(d[6]) * r4 + T(d[7]) * r6);
      *xd = x * radial + T(2 * p1) * x * y + T(p2) * (r2 + T(2) * x * x);
      *yd = y * radial + T(p1) * (r2 + T(2) * y * y) + T(2 * p2) * x * y;
      return;
    }
    case DistortionModel::kFisheye: {
      using std::atan;
      using std::sqrt;
      const T r2 = x * x + y * y;
      if (!(r2 > T(1e-30))) {  // on the axis: theta_d / r -> 1
        *xd = x;
        *yd = y;
        return;
      }
      const T r = sqrt(r2);
      const T scale = FisheyeThetaD(atan(r)) / r;
      *xd = x * scale;
      *yd = y * scale;
      return;
    }
  }
}

template <typename T>
T CameraModel::FisheyeThetaD(const T& theta) const {
  const std::vector<double>& d = distortion;
  const T t2 = theta * theta, t4 = t2 * t2, t6 = t4 * t2, t8 = t4 * t4;
  return theta * (T(1) + T(d[0]) * t2 + T(d[1]) * t4 + T(d[2]) * t6 + T(d[3]) * t8);
}

}  // namespace mcmt
