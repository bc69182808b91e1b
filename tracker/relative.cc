// Relative poses and their covariance (the math is in tracker/relative.h).
#include "tracker/relative.h"

#include "core/math.h"

namespace mcmt {

Matrix6d Adjoint(const Rigid3& a_from_b) {
  const Eigen::Matrix3d r = a_from_b.linear();
  Matrix6d ad = Matrix6d::Zero();
  ad.topLeftCorner<3, 3>() = r;
  ad.topRightCorner<3, 3>() = Skew(a_from_b.translation()) * r;
  ad.bottomRightCorner<3, 3>() = r;
  return ad;
}

RelativePose ComposeRelative(const Rigid3& rig_from_of, const Matrix6d& covariance_of,
                             const Rigid3& rig_from_in, const Matrix6d& covariance_in) {
  RelativePose out;
  const Rigid3 in_from_rig = Inverse(rig_from_in);
  out.in_from_of = Normalized(in_from_rig * rig_from_of);
  const Matrix6d ad = Adjoint(in_from_rig);
  out.covariance = ad * (covariance_of + covariance_in) * ad.transpose();
  out.covariance = 0.5 * (out.covariance + out.covariance.transpose());  // exactly symmetric
  return out;
}

Eigen::Matrix3d PositionCovariance(const Rigid3& rig_from_object, const Matrix6d& covariance) {
  Eigen::Matrix<double, 3, 6> a;
  a << Eigen::Matrix3d::Identity(), -Skew(rig_from_object.translation());
  const Eigen::Matrix3d c = a * covariance * a.transpose();
  return 0.5 * (c + c.transpose());
}

}  // namespace mcmt
