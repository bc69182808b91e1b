// Relative poses and their covariance (the math is in tracker/relative.h).
#include "tracker/relative.h"

#include "core/math.h"

namespace mcmt {

Matrix6d AdjointTranslationFirst(const Rigid3& a_from_b) {
  const Matrix6d ad = Adjoint(a_from_b);  // (rotation, translation)
  Matrix6d swapped;
  swapped << ad.bottomRightCorner<3, 3>(), ad.bottomLeftCorner<3, 3>(), ad.topRightCorner<3, 3>(),
      ad.topLeftCorner<3, 3>();
  return swapped;
}

RelativePose ComposeRelative(const Rigid3& rig_from_of, const Matrix6d& covariance_of,
                             const Rigid3& rig_from_in, const Matrix6d& covariance_in) {
  RelativePose out;
  const Rigid3 in_from_rig = Inverse(rig_from_in);
  out.in_from_of = Normalized(in_from_rig * rig_from_of);
  const Matrix6d ad = AdjointTranslationFirst(in_from_rig);
  out.covariance = ad * (covariance_of + covariance_in) * ad.transpose();
  out.covariance = 0.5 * (out.covariance + out.covariance.transpose());  // exactly symmetric
  return out;
}

}  // namespace mcmt
