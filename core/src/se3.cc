#include "core/se3.h"

#include <Eigen/Dense>
#include <Eigen/SVD>
#include <cmath>
#include <stdexcept>

#include "core/math.h"

namespace mcmt {

Eigen::Matrix3d RotationFromVector(const Eigen::Vector3d& rotation_vector) {
  const double theta2 = rotation_vector.squaredNorm();
  const Eigen::Matrix3d k = Skew(rotation_vector);
  if (theta2 < 1e-16) {
    // Taylor: R = I + K + K^2 / 2 (exact to machine precision at this size).
    return Eigen::Matrix3d::Identity() + k + 0.5 * k * k;
  }
  const double theta = std::sqrt(theta2);
  const double a = std::sin(theta) / theta;
  const double b = (1.0 - std::cos(theta)) / theta2;
  return Eigen::Matrix3d::Identity() + a * k + b * k * k;
}

Eigen::Vector3d VectorFromRotation(const Eigen::Matrix3d& rotation) {
  // Through the quaternion: stable everywhere, including near 0 and near pi.
  Eigen::Quaterniond q(rotation);
  q.normalize();
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  const Eigen::Vector3d v = q.vec();
  const double s = v.norm();
  if (s < 1e-300) return Eigen::Vector3d::Zero();
  const double angle = 2.0 * std::atan2(s, q.w());  // in [0, pi]
  if (s < 1e-8) {
    // angle ~ 2 s / w: use the series to keep full relative precision.
    return v * (2.0 / q.w()) * (1.0 + s * s / (3.0 * q.w() * q.w()));
  }
  return v * (angle / s);
}

Rigid3 RigidFromParams(const double* params) {
  Rigid3 t = Rigid3::Identity();
  t.linear() = RotationFromVector(Eigen::Vector3d(params[0], params[1], params[2]));
  t.translation() = Eigen::Vector3d(params[3], params[4], params[5]);
  return t;
}

Rigid3 RigidFromParams(const Vector6d& params) { return RigidFromParams(params.data()); }

Vector6d ParamsFromRigid(const Rigid3& a_from_b) {
  Vector6d p;
  p.head<3>() = VectorFromRotation(a_from_b.linear());
  p.tail<3>() = a_from_b.translation();
  return p;
}

Rigid3 RigidFromRvecTvec(const Eigen::Vector3d& rvec, const Eigen::Vector3d& tvec) {
  Rigid3 t = Rigid3::Identity();
  t.linear() = RotationFromVector(rvec);
  t.translation() = tvec;
  return t;
}

Rigid3 RigidFromQuaternion(const std::array<double, 4>& wxyz, const Eigen::Vector3d& translation) {
  Eigen::Quaterniond q(wxyz[0], wxyz[1], wxyz[2], wxyz[3]);
  const double n = q.norm();
  if (!(n > 0) || !std::isfinite(n)) throw std::invalid_argument("quaternion has zero or non-finite norm");
  q.coeffs() /= n;
  Rigid3 t = Rigid3::Identity();
  t.linear() = q.toRotationMatrix();
  t.translation() = translation;
  return t;
}

std::array<double, 4> QuaternionWxyz(const Rigid3& a_from_b) {
  Eigen::Quaterniond q(a_from_b.linear());
  q.normalize();
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  return {q.w(), q.x(), q.y(), q.z()};
}

Rigid3 Inverse(const Rigid3& a_from_b) {
  Rigid3 b_from_a = Rigid3::Identity();
  const Eigen::Matrix3d rt = a_from_b.linear().transpose();
  b_from_a.linear() = rt;
  b_from_a.translation() = -rt * a_from_b.translation();
  return b_from_a;
}

Rigid3 Normalized(const Rigid3& a_from_b) {
  Rigid3 out = a_from_b;
  Eigen::Quaterniond q(a_from_b.linear());
  q.normalize();
  out.linear() = q.toRotationMatrix();
  out.makeAffine();
  return out;
}

double RotationAngle(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return VectorFromRotation(a.transpose() * b).norm();
}

double RotationAngle(const Rigid3& a, const Rigid3& b) { return RotationAngle(a.linear(), b.linear()); }

double TranslationDistance(const Rigid3& a, const Rigid3& b) {
  return (a.translation() - b.translation()).norm();
}

Rigid3 PerturbLeft(const Rigid3& pose, const Vector6d& delta) {
  Rigid3 out = Rigid3::Identity();
  const Eigen::Matrix3d r = RotationFromVector(delta.head<3>());
  out.linear() = r * pose.linear();
  out.translation() = r * pose.translation() + delta.tail<3>();
  return out;
}

Matrix6d Adjoint(const Rigid3& a_from_b) {
  const Eigen::Matrix3d r = a_from_b.linear();
  Matrix6d ad = Matrix6d::Zero();
  ad.topLeftCorner<3, 3>() = r;
  ad.bottomLeftCorner<3, 3>() = Skew(a_from_b.translation()) * r;
  ad.bottomRightCorner<3, 3>() = r;
  return ad;
}

Eigen::Matrix3d PositionCovariance(const Rigid3& rig_from_object, const Matrix6d& covariance) {
  Eigen::Matrix<double, 3, 6> a;
  a << Eigen::Matrix3d::Identity(), -Skew(rig_from_object.translation());
  const Eigen::Matrix3d c = a * covariance * a.transpose();
  return 0.5 * (c + c.transpose());
}

Rigid3 MovedAlong(const Rigid3& pose, const std::array<double, 6>& twist, double dt) {
  Rigid3 out = pose;
  out.linear() = RotationFromVector(dt * Eigen::Vector3d(twist[0], twist[1], twist[2])) * pose.linear();
  out.translation() += dt * Eigen::Vector3d(twist[3], twist[4], twist[5]);
  return out;
}

std::array<double, 6> TwistIn(const Rigid3& new_from_old, const std::array<double, 6>& twist) {
  std::array<double, 6> out;
  for (int part = 0; part < 2; ++part)
    Eigen::Map<Eigen::Vector3d>(out.data() + 3 * part) =
        new_from_old.linear() * Eigen::Vector3d(twist[3 * part], twist[3 * part + 1], twist[3 * part + 2]);
  return out;
}

Rigid3 RandomRigid(std::mt19937_64& rng, double max_translation) {
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(-max_translation, max_translation);
  // A normalised 4D Gaussian is a uniform unit quaternion.
  Eigen::Quaterniond q;
  do {
    q = Eigen::Quaterniond(normal(rng), normal(rng), normal(rng), normal(rng));
  } while (q.norm() < 1e-6);
  q.normalize();
  Rigid3 t = Rigid3::Identity();
  t.linear() = q.toRotationMatrix();
  const double x = uniform(rng), y = uniform(rng), z = uniform(rng);
  t.translation() = Eigen::Vector3d(x, y, z);
  return t;
}

Rigid3 AlignRigid(const std::vector<Eigen::Vector3d>& points_b,
                  const std::vector<Eigen::Vector3d>& points_a) {
  if (points_a.size() != points_b.size())
    throw std::invalid_argument("AlignRigid: point lists differ in size");
  if (points_a.empty()) throw std::invalid_argument("AlignRigid: no points");
  const double n = static_cast<double>(points_a.size());
  Eigen::Vector3d mean_a = Eigen::Vector3d::Zero(), mean_b = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < points_a.size(); ++i) {
    mean_a += points_a[i];
    mean_b += points_b[i];
  }
  mean_a /= n;
  mean_b /= n;
  Rigid3 a_from_b = Rigid3::Identity();
  if (points_a.size() < 3) {
    a_from_b.translation() = mean_a - mean_b;
    return a_from_b;
  }
  // Cross-covariance H = sum (b_i - mb)(a_i - ma)^T; R = V diag(1, 1, det) U^T (Umeyama).
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < points_a.size(); ++i)
    h += (points_a[i] - mean_a) * (points_b[i] - mean_b).transpose();
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d s = Eigen::Matrix3d::Identity();
  if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0) s(2, 2) = -1;
  const Eigen::Matrix3d r = svd.matrixU() * s * svd.matrixV().transpose();
  a_from_b.linear() = r;
  a_from_b.translation() = mean_a - r * mean_b;
  return a_from_b;
}

}  // namespace mcmt
