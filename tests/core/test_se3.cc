#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/se3.h"

namespace mcmt {
namespace {

constexpr double kPi = 3.14159265358979323846;

TEST(Se3, RotationVectorKnownValues) {
  // 90 degrees about z maps x to y.
  const Eigen::Matrix3d r = RotationFromVector(Eigen::Vector3d(0, 0, kPi / 2));
  EXPECT_NEAR((r * Eigen::Vector3d::UnitX() - Eigen::Vector3d::UnitY()).norm(), 0.0, 1e-15);
  EXPECT_NEAR((RotationFromVector(Eigen::Vector3d::Zero()) - Eigen::Matrix3d::Identity()).norm(), 0.0, 0.0);
  // Agrees with Eigen's AngleAxis.
  const Eigen::Vector3d axis = Eigen::Vector3d(1, -2, 0.5).normalized();
  const Eigen::Matrix3d expected = Eigen::AngleAxisd(1.3, axis).toRotationMatrix();
  EXPECT_LT((RotationFromVector(1.3 * axis) - expected).norm(), 1e-15);
}

TEST(Se3, RotationVectorRoundTripIncludingNearZeroAndPi) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal;
  for (double angle : {0.0, 1e-12, 1e-8, 1e-4, 0.3, 1.0, 2.5, kPi - 1e-3, kPi - 1e-7, kPi - 1e-10}) {
    for (int k = 0; k < 20; ++k) {
      const Eigen::Vector3d axis = Eigen::Vector3d(normal(rng), normal(rng), normal(rng)).normalized();
      const Eigen::Vector3d v = angle * axis;
      const Eigen::Vector3d back = VectorFromRotation(RotationFromVector(v));
      // Near pi, v and -v describe nearly the same rotation: compare rotations and the angle.
      EXPECT_NEAR(back.norm(), angle, 1e-9 * std::max(1.0, angle)) << "angle " << angle;
      EXPECT_LT((RotationFromVector(back) - RotationFromVector(v)).norm(), 1e-14) << "angle " << angle;
      if (angle < kPi - 1e-3 && angle > 0) {
        EXPECT_LT((back - v).norm(), 1e-12 * std::max(angle, 1e-3)) << "angle " << angle;
      }
    }
  }
  // Exactly pi about x.
  Eigen::Matrix3d r = Eigen::Vector3d(1, -1, -1).asDiagonal();
  const Eigen::Vector3d v = VectorFromRotation(r);
  EXPECT_NEAR(v.norm(), kPi, 1e-12);
  EXPECT_NEAR(std::abs(v.x()), kPi, 1e-12);
}

TEST(Se3, SmallAngleRelativePrecision) {
  const Eigen::Vector3d v(3e-10, -1e-10, 2e-10);
  const Eigen::Vector3d back = VectorFromRotation(RotationFromVector(v));
  EXPECT_LT((back - v).norm(), 1e-6 * v.norm());
}

TEST(Se3, ParamsRoundTrip) {
  std::mt19937_64 rng(3);
  for (int i = 0; i < 100; ++i) {
    const Rigid3 t = RandomRigid(rng, 5.0);
    const Vector6d p = ParamsFromRigid(t);
    const Rigid3 back = RigidFromParams(p);
    EXPECT_LT(RotationAngle(t, back), 1e-12);
    EXPECT_LT(TranslationDistance(t, back), 1e-15);
    EXPECT_LE(p.head<3>().norm(), kPi + 1e-12);
    const Rigid3 back2 = RigidFromParams(p.data());
    EXPECT_TRUE(back2.isApprox(back, 0.0) || (back2.matrix() - back.matrix()).norm() == 0.0);
  }
  // Known: (0, 0, pi/2, 1, 2, 3) maps (1, 0, 0) to (1, 3, 3).
  Vector6d p;
  p << 0, 0, kPi / 2, 1, 2, 3;
  EXPECT_LT((RigidFromParams(p) * Eigen::Vector3d(1, 0, 0) - Eigen::Vector3d(1, 3, 3)).norm(), 1e-15);
  const Rigid3 rt = RigidFromRvecTvec(Eigen::Vector3d(0, 0, kPi / 2), Eigen::Vector3d(1, 2, 3));
  EXPECT_LT((rt.matrix() - RigidFromParams(p).matrix()).norm(), 1e-15);
}

TEST(Se3, QuaternionRoundTripAndConvention) {
  // 90 degrees about z: w = cos 45, z = sin 45.
  const Rigid3 t = RigidFromQuaternion({std::sqrt(0.5), 0, 0, std::sqrt(0.5)}, Eigen::Vector3d(1, 2, 3));
  EXPECT_LT((t * Eigen::Vector3d::UnitX() - Eigen::Vector3d(1, 3, 3)).norm(), 1e-15);
  // Not normalised on input.
  const Rigid3 t2 =
      RigidFromQuaternion({2 * std::sqrt(0.5), 0, 0, 2 * std::sqrt(0.5)}, Eigen::Vector3d(1, 2, 3));
  EXPECT_LT((t.matrix() - t2.matrix()).norm(), 1e-15);
  EXPECT_THROW(RigidFromQuaternion({0, 0, 0, 0}, Eigen::Vector3d::Zero()), std::invalid_argument);
  std::mt19937_64 rng(5);
  for (int i = 0; i < 100; ++i) {
    const Rigid3 r = RandomRigid(rng, 1.0);
    const auto q = QuaternionWxyz(r);
    EXPECT_GE(q[0], 0.0);
    EXPECT_NEAR(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3], 1.0, 1e-15);
    const Rigid3 back = RigidFromQuaternion(q, r.translation());
    EXPECT_LT(RotationAngle(r, back), 1e-14);
  }
}

TEST(Se3, InverseComposeAndNormalized) {
  std::mt19937_64 rng(11);
  for (int i = 0; i < 50; ++i) {
    const Rigid3 a_from_b = RandomRigid(rng, 3.0);
    const Rigid3 b_from_a = Inverse(a_from_b);
    EXPECT_LT(((a_from_b * b_from_a).matrix() - Eigen::Matrix4d::Identity()).norm(), 1e-14);
    EXPECT_LT(((b_from_a * a_from_b).matrix() - Eigen::Matrix4d::Identity()).norm(), 1e-14);
    const Eigen::Vector3d p(0.3, -1, 2);
    EXPECT_LT((b_from_a * (a_from_b * p) - p).norm(), 1e-14);
    EXPECT_EQ(b_from_a.matrix().row(3), Eigen::RowVector4d(0, 0, 0, 1));
  }
  // Normalized repairs a slightly non-orthonormal rotation.
  Rigid3 t = RandomRigid(rng, 1.0);
  const Rigid3 original = t;
  t.linear() *= 1.0 + 1e-7;
  t.linear()(0, 1) += 1e-7;
  const Rigid3 n = Normalized(t);
  EXPECT_LT((n.linear().transpose() * n.linear() - Eigen::Matrix3d::Identity()).norm(), 1e-15);
  EXPECT_NEAR(n.linear().determinant(), 1.0, 1e-15);
  EXPECT_LT(RotationAngle(n, original), 1e-6);
  EXPECT_EQ(n.translation(), original.translation());
}

TEST(Se3, AnglesAndDistances) {
  const Rigid3 a = RigidFromRvecTvec(Eigen::Vector3d(0.1, 0, 0), Eigen::Vector3d(1, 0, 0));
  const Rigid3 b = RigidFromRvecTvec(Eigen::Vector3d(0.4, 0, 0), Eigen::Vector3d(1, 3, 4));
  EXPECT_NEAR(RotationAngle(a, b), 0.3, 1e-15);
  EXPECT_NEAR(TranslationDistance(a, b), 5.0, 1e-15);
  const Rigid3 flip = RigidFromRvecTvec(Eigen::Vector3d(0, kPi, 0), Eigen::Vector3d::Zero());
  EXPECT_NEAR(RotationAngle(Rigid3::Identity(), flip), kPi, 1e-12);
}

TEST(Se3, PerturbLeft) {
  std::mt19937_64 rng(13);
  const Rigid3 pose = RandomRigid(rng, 2.0);
  Vector6d delta;
  delta << 0.01, -0.02, 0.03, 0.1, 0.2, -0.3;
  const Rigid3 perturbed = PerturbLeft(pose, delta);
  // Exp(delta) * pose: rotate about the rig origin, then translate.
  Rigid3 rotation = Rigid3::Identity();
  rotation.linear() = RotationFromVector(delta.head<3>());
  Rigid3 translation = Rigid3::Identity();
  translation.translation() = delta.tail<3>();
  const Rigid3 expected = translation * rotation * pose;
  EXPECT_LT((perturbed.matrix() - expected.matrix()).norm(), 1e-14);
  EXPECT_LT((PerturbLeft(pose, Vector6d::Zero()).matrix() - pose.matrix()).norm(), 1e-15);
}

// A twist re-expressed in another frame moves the re-expressed pose as the frame change moves the moved pose.
TEST(Se3, TwistInAnotherFrameMovesThePoseTheSameWay) {
  std::mt19937_64 rng(17);
  const Rigid3 pose = RandomRigid(rng, 2.0), new_from_old = RandomRigid(rng, 1.0);
  const std::array<double, 6> twist = {0.4, -1.1, 0.7, 0.3, -0.2, 0.5};
  for (double dt : {-0.05, 0.02, 0.3}) {
    const Rigid3 expected = new_from_old * MovedAlong(pose, twist, dt);
    const Rigid3 moved = MovedAlong(new_from_old * pose, TwistIn(new_from_old, twist), dt);
    EXPECT_LT((moved.matrix() - expected.matrix()).norm(), 1e-12) << dt;
  }
}

TEST(Se3, RandomRigidIsUniformEnough) {
  std::mt19937_64 rng(17);
  Eigen::Vector3d mean_z = Eigen::Vector3d::Zero();
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    const Rigid3 t = RandomRigid(rng, 2.0);
    EXPECT_LE(t.translation().cwiseAbs().maxCoeff(), 2.0);
    mean_z += t.linear().col(2);
  }
  // The image of the z axis is uniform on the sphere: its mean is near 0 (std ~ 1/sqrt(3n)).
  EXPECT_LT((mean_z / n).norm(), 0.03);
}

TEST(Se3, AlignRigidRecoversRandomTransform) {
  std::mt19937_64 rng(19);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (int trial = 0; trial < 30; ++trial) {
    const Rigid3 a_from_b = RandomRigid(rng, 10.0);
    std::vector<Eigen::Vector3d> b, a;
    for (int i = 0; i < 12; ++i) {
      b.emplace_back(noise(rng), noise(rng), noise(rng));
      a.push_back(a_from_b * b.back());
    }
    const Rigid3 est = AlignRigid(b, a);
    EXPECT_LT(RotationAngle(est, a_from_b), 1e-12);
    EXPECT_LT(TranslationDistance(est, a_from_b), 1e-12);
    EXPECT_NEAR(est.linear().determinant(), 1.0, 1e-12);
  }
  // Coplanar points (determinant correction must not produce a reflection).
  const Rigid3 a_from_b = RandomRigid(rng, 1.0);
  std::vector<Eigen::Vector3d> b = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}}, a;
  for (const auto& p : b) a.push_back(a_from_b * p);
  EXPECT_LT(RotationAngle(AlignRigid(b, a), a_from_b), 1e-12);
  // Two points: translation only.
  const Rigid3 tr = AlignRigid({{0, 0, 0}, {1, 0, 0}}, {{1, 2, 3}, {2, 2, 3}});
  EXPECT_LT((tr.translation() - Eigen::Vector3d(1, 2, 3)).norm(), 1e-15);
  EXPECT_THROW(AlignRigid({}, {}), std::invalid_argument);
  EXPECT_THROW(AlignRigid({{0, 0, 0}}, {}), std::invalid_argument);
}

}  // namespace
}  // namespace mcmt
