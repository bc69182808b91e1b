#include "core/camera.h"

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace mcmt {
void CameraModel::DistortWithJacobian(double x, double y, double* xd, double* yd,
                                      Eigen::Matrix2d* jacobian) const {
  DistortDual dx, dy;
  Distort(DistortDual(x, 1, 0), DistortDual(y, 0, 1), &dx, &dy);
  *xd = dx.v;
  *yd = dy.v;
  *jacobian << dx.dx, dx.dy, dy.dx, dy.dy;
}

std::string DistortionModelName(DistortionModel model) {
  switch (model) {
    case DistortionModel::kNone:
      return "none";
    case DistortionModel::kRadTan:
      return "radtan";
    case DistortionModel::kFisheye:
      return "fisheye";
  }
  return "none";
}

DistortionModel DistortionModelFromName(const std::string& name) {
  if (name == "none" || name.empty()) return DistortionModel::kNone;
  if (name == "radtan" || name == "plumb_bob" || name == "rational_polynomial")
    return DistortionModel::kRadTan;
  if (name == "fisheye" || name == "equidistant" || name == "kannala_brandt")
    return DistortionModel::kFisheye;
  throw std::invalid_argument("unknown distortion model '" + name + "' (valid: none, radtan, fisheye)");
}

CameraModel CameraModel::Pinhole(int width, int height, double focal_px, double cx, double cy) {
  CameraModel c;
  c.width = width;
  c.height = height;
  c.fx = c.fy = focal_px;
  c.cx = cx;
  c.cy = cy;
  return c;
}

void CameraModel::Validate() const {
  if (width <= 0 || height <= 0)
    throw std::invalid_argument("image size must be positive, got " + std::to_string(width) + "x" +
                                std::to_string(height));
  if (!(fx > 0) || !(fy > 0) || !std::isfinite(fx) || !std::isfinite(fy))
    throw std::invalid_argument("focal lengths must be positive, got fx=" + std::to_string(fx) +
                                " fy=" + std::to_string(fy));
  if (!std::isfinite(cx) || !std::isfinite(cy)) throw std::invalid_argument("principal point is not finite");
  for (double v : distortion)
    if (!std::isfinite(v)) throw std::invalid_argument("distortion coefficient is not finite");
  const size_t n = distortion.size();
  switch (model) {
    case DistortionModel::kNone:
      if (n != 0)
        throw std::invalid_argument("distortion model none takes no coefficients, got " + std::to_string(n));
      break;
    case DistortionModel::kRadTan:
      if (n != 4 && n != 5 && n != 8)
        throw std::invalid_argument("radtan distortion needs 4, 5 or 8 coefficients, got " +
                                    std::to_string(n));
      break;
    case DistortionModel::kFisheye:
      if (n != 4)
        throw std::invalid_argument("fisheye distortion needs 4 coefficients, got " + std::to_string(n));
      break;
  }
}

bool CameraModel::Project(const Eigen::Vector3d& p_cam, Eigen::Vector2d* pixel,
                          Eigen::Matrix<double, 2, 3>* jacobian) const {
  if (!(p_cam.z() > 0)) return false;
  const double iz = 1.0 / p_cam.z();
  const double x = p_cam.x() * iz, y = p_cam.y() * iz;
  double xd, yd;
  Eigen::Matrix2d jd;
  if (jacobian)
    DistortWithJacobian(x, y, &xd, &yd, &jd);
  else
    Distort(x, y, &xd, &yd);  // the same values, without the derivatives
  if (pixel) *pixel = Eigen::Vector2d(fx * xd + cx, fy * yd + cy);
  if (jacobian) {
    // d(x, y) / d p = [[1/z, 0, -x/z], [0, 1/z, -y/z]]; pixel = diag(fx, fy) * (xd, yd) + c.
    Eigen::Matrix<double, 2, 3> jn;
    jn << iz, 0, -x * iz, 0, iz, -y * iz;
    Eigen::Matrix2d f = Eigen::Vector2d(fx, fy).asDiagonal();
    *jacobian = f * jd * jn;
  }
  return true;
}

Eigen::Vector2d CameraModel::Project(const Eigen::Vector3d& p_cam) const {
  Eigen::Vector2d pixel;
  if (!Project(p_cam, &pixel, nullptr))
    return Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
  return pixel;
}

Eigen::Vector2d CameraModel::Unproject(const Eigen::Vector2d& pixel) const {
  const Eigen::Vector2d target((pixel.x() - cx) / fx, (pixel.y() - cy) / fy);
  if (model == DistortionModel::kNone) return target;
  if (model == DistortionModel::kFisheye) {
    // Radial only: solve theta_d(theta) = |target| for theta by Newton, then r = tan(theta).
    const double rd = target.norm();
    if (rd < 1e-30) return target;
    double theta = std::min(rd, 1.5);
    for (int it = 0; it < 50; ++it) {
      const DistortDual theta_d = FisheyeThetaD(DistortDual(theta, 1, 0));
      const double f = theta_d.v - rd;
      const double df = theta_d.dx;
      if (df == 0) break;
      double step = f / df;
      double next = theta - step;
      if (next < 0) next = 0.5 * theta;
      if (next > 1.5707963) next = 0.5 * (theta + 1.5707963);
      const double change = std::abs(next - theta);
      theta = next;
      if (change < 1e-16 * std::max(1.0, theta)) break;
    }
    const double r = std::tan(theta);
    return target * (r / rd);
  }
  // radtan: Gauss-Newton on Distort(u) = target, starting from the target itself.
  Eigen::Vector2d u = target;
  for (int it = 0; it < 100; ++it) {
    double xd, yd;
    Eigen::Matrix2d j;
    DistortWithJacobian(u.x(), u.y(), &xd, &yd, &j);
    const Eigen::Vector2d residual(xd - target.x(), yd - target.y());
    const double det = j.determinant();
    if (!(std::abs(det) > 1e-300)) break;
    Eigen::Vector2d step = j.inverse() * residual;
    // Damp very large steps (far outside the region where the model is monotonic).
    const double limit = 0.5 * std::max(1.0, u.norm());
    if (step.norm() > limit) step *= limit / step.norm();
    u -= step;
    if (step.norm() < 1e-15 * std::max(1.0, u.norm()) || residual.norm() < 1e-16) break;
  }
  return u;
}

Eigen::Vector2d CameraModel::Undistort(const Eigen::Vector2d& pixel) const {
  const Eigen::Vector2d u = Unproject(pixel);
  return Eigen::Vector2d(fx * u.x() + cx, fy * u.y() + cy);
}

bool CameraModel::InImage(const Eigen::Vector2d& pixel, double margin) const {
  return pixel.x() >= -0.5 + margin && pixel.y() >= -0.5 + margin && pixel.x() <= width - 0.5 - margin &&
         pixel.y() <= height - 0.5 - margin;
}

cv::Mat CameraModel::CameraMatrix() const {
  cv::Mat k = (cv::Mat_<double>(3, 3) << fx, 0, cx, 0, fy, cy, 0, 0, 1);
  return k;
}

cv::Mat CameraModel::DistortionCoeffs() const {
  if (distortion.empty()) return cv::Mat();
  cv::Mat d(1, static_cast<int>(distortion.size()), CV_64F);
  for (size_t i = 0; i < distortion.size(); ++i) d.at<double>(0, static_cast<int>(i)) = distortion[i];
  return d;
}

bool CameraModel::operator==(const CameraModel& other) const {
  return width == other.width && height == other.height && fx == other.fx && fy == other.fy &&
         cx == other.cx && cy == other.cy && model == other.model && distortion == other.distortion;
}

}  // namespace mcmt
