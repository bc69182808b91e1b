#include <gtest/gtest.h>

#include <random>

#include "core/ippe.h"
#include "tests/core/test_util.h"

namespace mcmt {
namespace {

constexpr double kPi = 3.14159265358979323846;

using testing_util::TestCamera;

MarkerCorners2d ProjectSquare(const CameraModel& cam, const Rigid3& cam_from_marker, double side,
                              double noise_px, std::mt19937_64* rng) {
  std::normal_distribution<double> noise(0.0, noise_px > 0 ? noise_px : 1.0);
  const MarkerCorners3d corners = MarkerCornersInMarker(side);
  MarkerCorners2d out;
  for (int i = 0; i < 4; ++i) {
    out[i] = cam.Project(cam_from_marker * corners[i]);
    if (noise_px > 0) out[i] += Eigen::Vector2d(noise(*rng), noise(*rng));
  }
  return out;
}

// Marker at `position` in the camera, facing the camera, tilted by `tilt` radians about an axis.
Rigid3 Facing(const Eigen::Vector3d& position, double tilt, const Eigen::Vector3d& tilt_axis) {
  // Face the camera: marker z (out of the face) points to -z of the camera; flip about x.
  const Rigid3 facing = RigidFromRvecTvec(Eigen::Vector3d(kPi, 0, 0), Eigen::Vector3d::Zero());
  const Rigid3 tilted = RigidFromRvecTvec(tilt * tilt_axis.normalized(), Eigen::Vector3d::Zero());
  Rigid3 t = facing * tilted;
  t.translation() = position;
  return t;
}

double MinPoseError(const SquarePose& pose, const Rigid3& truth, double* translation_error) {
  double best = 1e9;
  for (int i = 0; i < pose.num_hypotheses; ++i) {
    const double angle = RotationAngle(pose.hypotheses[i].cam_from_marker, truth);
    if (angle < best) {
      best = angle;
      *translation_error = TranslationDistance(pose.hypotheses[i].cam_from_marker, truth);
    }
  }
  return best;
}

TEST(Ippe, MarkerCornerOrder) {
  const MarkerCorners3d c = MarkerCornersInMarker(0.2);
  EXPECT_EQ(c[0], Eigen::Vector3d(-0.1, 0.1, 0));
  EXPECT_EQ(c[1], Eigen::Vector3d(0.1, 0.1, 0));
  EXPECT_EQ(c[2], Eigen::Vector3d(0.1, -0.1, 0));
  EXPECT_EQ(c[3], Eigen::Vector3d(-0.1, -0.1, 0));
  MarkerSizes sizes{0.05, {{7, 0.03}}};
  EXPECT_EQ(sizes.Get(7), 0.03);
  EXPECT_EQ(sizes.Get(8), 0.05);
}

TEST(Ippe, ExactCornersRecoverPoseWithLargeRatioWhenCloseAndTilted) {
  const CameraModel cam = TestCamera();
  std::mt19937_64 rng(1);
  const double side = 0.1;
  for (const Eigen::Vector3d& position :
       {Eigen::Vector3d(0, 0, 0.5), Eigen::Vector3d(0.15, -0.1, 0.6), Eigen::Vector3d(-0.2, 0.1, 0.45)}) {
    for (double tilt : {0.4, 0.7, 1.0}) {
      const Rigid3 truth = Facing(position, tilt, Eigen::Vector3d(1, 0.5, 0));
      const SquarePose pose = EstimateSquarePose(cam, ProjectSquare(cam, truth, side, 0, &rng), side);
      ASSERT_TRUE(pose.ok);
      ASSERT_EQ(pose.num_hypotheses, 2);
      EXPECT_LE(pose.hypotheses[0].error_px, pose.hypotheses[1].error_px);
      // The best hypothesis is the truth, to numerical precision.
      EXPECT_LT(RotationAngle(pose.best().cam_from_marker, truth), 1e-6);
      EXPECT_LT(TranslationDistance(pose.best().cam_from_marker, truth), 1e-7);
      EXPECT_LT(pose.best().error_px, 1e-6);
      EXPECT_GT(pose.ratio, 100.0) << "tilt " << tilt;
      EXPECT_EQ(NumKeptHypotheses(pose, 2.0), 1);
    }
  }
}

TEST(Ippe, NoisyCloseSquareKeepsTruthAmongHypothesesWithLargeRatio) {
  const CameraModel cam = TestCamera();
  std::mt19937_64 rng(2);
  const double side = 0.1;
  int large_ratio = 0;
  const int trials = 50;
  for (int trial = 0; trial < trials; ++trial) {
    const Rigid3 truth = Facing(Eigen::Vector3d(0.05, 0.02, 0.4), 0.6, Eigen::Vector3d(0, 1, 0));
    const SquarePose pose = EstimateSquarePose(cam, ProjectSquare(cam, truth, side, 0.3, &rng), side);
    ASSERT_TRUE(pose.ok);
    double terr = 0;
    EXPECT_LT(MinPoseError(pose, truth, &terr), 0.05);
    EXPECT_LT(terr, 0.01);
    if (pose.ratio > 4.0) ++large_ratio;
  }
  EXPECT_GE(large_ratio, trials * 9 / 10);
}

TEST(Ippe, FarFrontoParallelSquareIsAmbiguous) {
  const CameraModel cam = TestCamera();
  std::mt19937_64 rng(3);
  const double side = 0.05;
  int near_one = 0;
  const int trials = 50;
  for (int trial = 0; trial < trials; ++trial) {
    const Rigid3 truth = Facing(Eigen::Vector3d(0.3, -0.2, 6.0), 0.0, Eigen::Vector3d(1, 0, 0));
    const SquarePose pose = EstimateSquarePose(cam, ProjectSquare(cam, truth, side, 0.3, &rng), side);
    ASSERT_TRUE(pose.ok);
    EXPECT_GE(pose.ratio, 1.0);
    double terr = 0;
    // Orientation is poorly determined this far away, but one hypothesis is still near the truth.
    EXPECT_LT(MinPoseError(pose, truth, &terr), 0.6);
    if (pose.ratio < 2.0) {
      ++near_one;
      EXPECT_EQ(NumKeptHypotheses(pose, 2.0), 2);
    }
  }
  EXPECT_GE(near_one, trials * 8 / 10);
}

TEST(Ippe, FisheyeCamera) {
  CameraModel cam = TestCamera();
  cam.model = DistortionModel::kFisheye;
  cam.distortion = {0.05, -0.01, 0.002, -0.0005};
  std::mt19937_64 rng(4);
  const Rigid3 truth = Facing(Eigen::Vector3d(0.4, 0.3, 0.7), 0.5, Eigen::Vector3d(1, 1, 0));
  const SquarePose pose = EstimateSquarePose(cam, ProjectSquare(cam, truth, 0.08, 0, &rng), 0.08);
  ASSERT_TRUE(pose.ok);
  EXPECT_LT(RotationAngle(pose.best().cam_from_marker, truth), 1e-6);
  EXPECT_LT(pose.best().error_px, 1e-6);
}

TEST(Ippe, DegenerateCornersAreRejected) {
  const CameraModel cam = TestCamera();
  MarkerCorners2d same;
  for (auto& c : same) c = Eigen::Vector2d(100, 100);
  EXPECT_FALSE(EstimateSquarePose(cam, same, 0.1).ok);
  MarkerCorners2d line = {Eigen::Vector2d(0, 0), Eigen::Vector2d(10, 0), Eigen::Vector2d(20, 0),
                          Eigen::Vector2d(30, 0)};
  EXPECT_FALSE(EstimateSquarePose(cam, line, 0.1).ok);
  MarkerCorners2d nan = line;
  nan[2].x() = std::nan("");
  EXPECT_FALSE(EstimateSquarePose(cam, nan, 0.1).ok);
  std::mt19937_64 rng(5);
  const MarkerCorners2d good =
      ProjectSquare(cam, Facing(Eigen::Vector3d(0, 0, 1), 0.3, Eigen::Vector3d(1, 0, 0)), 0.1, 0, &rng);
  EXPECT_FALSE(EstimateSquarePose(cam, good, 0.0).ok);
  EXPECT_EQ(NumKeptHypotheses(SquarePose{}, 2.0), 0);
}

}  // namespace
}  // namespace mcmt

namespace mcmt {
namespace {

TEST(Ippe, CloseFrontalSquareHasLargeRatio) {
  // Close and frontal: perspective tells the two tilts apart (the "ratio large when close").
  const CameraModel cam = TestCamera();
  std::mt19937_64 rng(6);
  const double side = 0.1;
  int large = 0;
  const int trials = 50;
  for (int trial = 0; trial < trials; ++trial) {
    const Rigid3 truth = Facing(Eigen::Vector3d(0.02, -0.01, 0.25), 0.0, Eigen::Vector3d(1, 0, 0));
    const SquarePose pose = EstimateSquarePose(cam, ProjectSquare(cam, truth, side, 0.3, &rng), side);
    ASSERT_TRUE(pose.ok);
    double terr = 0;
    EXPECT_LT(MinPoseError(pose, truth, &terr), 0.05);
    if (pose.ratio > 2.0) ++large;
  }
  EXPECT_GE(large, trials * 8 / 10);
}

}  // namespace
}  // namespace mcmt
