// Relative poses between tracked bodies (tracker.relative: [{of: tool, in: patient}]): the pose of one
// body in another's frame, in_from_of, with its covariance from both bodies' covariances.
#pragma once

#include "core/se3.h"

namespace mcmt {

// core's Adjoint (core/se3.h) for perturbations in object_pose_t's order (tx, ty, tz, rx, ry, rz) and core's
// left perturbation Exp(delta) * pose = rotation about the origin then a translation (PerturbLeft): the
// same matrix with its blocks swapped,
//   Ad = [ R  [t]x R ]
//        [ 0    R    ]   with R, t the rotation and translation of a_from_b.
Matrix6d AdjointTranslationFirst(const Rigid3& a_from_b);

struct RelativePose {
  Rigid3 in_from_of = Rigid3::Identity();
  // For in_from_of = Exp(delta) * estimate, delta in the `in` body's frame (as a body's covariance is for
  // a perturbation in the rig frame), order (tx, ty, tz, rx, ry, rz).
  Matrix6d covariance = Matrix6d::Zero();
};

// in_from_of = inv(rig_from_in) * rig_from_of. Each pose's covariance is for a perturbation in the rig
// frame, rig_from_x = Exp(delta_x) * estimate (object_pose_t), and the two are independent (disjoint
// markers; the cameras are the map's, held fixed). With A = rig_from_of, B = rig_from_in:
//   (Exp(db) B)^-1 Exp(da) A = B^-1 Exp(-db) Exp(da) A
//                           ~= B^-1 Exp(da - db) B B^-1 A = Exp(Ad(B^-1) (da - db)) in_from_of,
// so delta_rel = Ad(B^-1) (da - db) and
//   Sigma_rel = Ad(B^-1) (Sigma_a + Sigma_b) Ad(B^-1)^T.
// A static body (its one pose from the map) has Sigma_b = 0.
RelativePose ComposeRelative(const Rigid3& rig_from_of, const Matrix6d& covariance_of,
                             const Rigid3& rig_from_in, const Matrix6d& covariance_in);

// The covariance of the body's origin alone is core's PositionCovariance (core/se3.h).

}  // namespace mcmt
