// SE(3) helpers on Eigen. A transform is named a_from_b: p_a = a_from_b * p_b.
// Parameter vectors are (rx, ry, rz, tx, ty, tz): rotation vector (axis * angle, radians) then
// translation (metres), the 6-vector the paper and the optimisers use.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <random>

namespace mcmt {

using Rigid3 = Eigen::Isometry3d;
using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

// Rotation vector <-> rotation matrix (Rodrigues), stable near zero and near pi.
Eigen::Matrix3d RotationFromVector(const Eigen::Vector3d& rotation_vector);
Eigen::Vector3d VectorFromRotation(const Eigen::Matrix3d& rotation);

// Transform from (rx, ry, rz, tx, ty, tz) and back.
Rigid3 RigidFromParams(const double* params);
Rigid3 RigidFromParams(const Vector6d& params);
Vector6d ParamsFromRigid(const Rigid3& a_from_b);

// Transform from a rotation vector and a translation (as OpenCV's rvec, tvec).
Rigid3 RigidFromRvecTvec(const Eigen::Vector3d& rvec, const Eigen::Vector3d& tvec);

// Quaternions in the order w, x, y, z (messages and files). Not required to be normalised on input.
Rigid3 RigidFromQuaternion(const std::array<double, 4>& wxyz, const Eigen::Vector3d& translation);
std::array<double, 4> QuaternionWxyz(const Rigid3& a_from_b);  // w >= 0

// Inverse of a rigid transform (exact: R^T, -R^T t), keeping the result orthonormal.
Rigid3 Inverse(const Rigid3& a_from_b);

// Re-orthonormalises the rotation part (after products or parsing).
Rigid3 Normalized(const Rigid3& a_from_b);

// Angle of the relative rotation between two transforms, radians (0..pi).
double RotationAngle(const Rigid3& a, const Rigid3& b);
double RotationAngle(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b);
// Distance between the translations of two transforms, metres.
double TranslationDistance(const Rigid3& a, const Rigid3& b);

// SO(3)/SE(3) exponential on the left: Exp(delta) * pose with delta = (rx, ry, rz, tx, ty, tz),
// rotation about the rig-frame origin then a translation.
Rigid3 PerturbLeft(const Rigid3& pose, const Vector6d& delta);

// The adjoint of a_from_b in core's order (rx, ry, rz, tx, ty, tz): a perturbation delta_b in frame b is
// the perturbation Ad(a_from_b) * delta_b in frame a,
//   a_from_b * Exp(delta_b) * b_from_a = Exp(Ad(a_from_b) * delta_b)   (to first order),
//   Ad = [   R     0 ]
//        [ [t]x R  R ]   with R, t the rotation and translation of a_from_b.
Matrix6d Adjoint(const Rigid3& a_from_b);

// Covariance of a body's origin (its position t in the rig) from a pose covariance in object_pose_t's
// convention. Exp(delta) * pose moves the origin to Exp(w) t + v ~= t + v - [t]x w, so
//   Sigma_t = A Sigma A^T,  A = [ I  -[t]x ].
// The translation block alone also holds the rotation's lever arm about the rig origin (1 mrad at 1 m
// is 1 mm), several times the position's own uncertainty.
Eigen::Matrix3d PositionCovariance(const Rigid3& rig_from_object, const Matrix6d& covariance);

// The pose dt seconds on along a constant twist (wx, wy, wz rad/s, vx, vy, vz m/s, in the frame the pose
// maps into): (Exp(dt w) R, t + dt v) (the mapper's frame velocities with time offsets).
Rigid3 MovedAlong(const Rigid3& pose, const std::array<double, 6>& twist, double dt);

// That twist re-expressed for new_from_old * pose: both parts rotated, so that
// MovedAlong(new_from_old * pose, TwistIn(new_from_old, twist), dt) = new_from_old * MovedAlong(pose, twist,
// dt).
std::array<double, 6> TwistIn(const Rigid3& new_from_old, const std::array<double, 6>& twist);

// A random transform: rotation uniform on SO(3), translation uniform in [-max_translation,
// max_translation]^3.
Rigid3 RandomRigid(std::mt19937_64& rng, double max_translation);

// Rigid (no scale) least-squares alignment (Horn / Umeyama): returns a_from_b minimising
// sum |a_i - a_from_b * b_i|^2. Needs >= 3 non-collinear points (or 1-2 points: translation only).
Rigid3 AlignRigid(const std::vector<Eigen::Vector3d>& points_b, const std::vector<Eigen::Vector3d>& points_a);

}  // namespace mcmt
