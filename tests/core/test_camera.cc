#include <gtest/gtest.h>

#include <opencv2/calib3d.hpp>
#include <random>

#include "core/camera.h"

namespace mcmt {
namespace {

CameraModel MakeCamera(DistortionModel model, std::vector<double> d) {
  CameraModel c;
  c.width = 1280;
  c.height = 960;
  c.fx = 910.5;
  c.fy = 905.25;
  c.cx = 641.3;
  c.cy = 478.9;
  c.model = model;
  c.distortion = std::move(d);
  c.Validate();
  return c;
}

std::vector<CameraModel> TestCameras() {
  return {
      MakeCamera(DistortionModel::kNone, {}),
      MakeCamera(DistortionModel::kRadTan, {-0.21, 0.08, 0.0012, -0.0008}),
      MakeCamera(DistortionModel::kRadTan, {-0.28, 0.11, 0.0009, -0.0011, -0.02}),
      MakeCamera(DistortionModel::kRadTan, {0.35, -0.12, 0.0007, 0.0004, 0.02, 0.71, -0.09, 0.05}),
      MakeCamera(DistortionModel::kFisheye, {0.031, -0.012, 0.004, -0.0009}),
  };
}

// Random points in front of the camera that land within the image (plus a margin outside).
std::vector<Eigen::Vector3d> RandomPoints(const CameraModel& c, int n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-0.6, 0.6), v(-0.45, 0.45), z(0.3, 8.0);
  std::vector<Eigen::Vector3d> out;
  for (int i = 0; i < n; ++i) {
    const double depth = z(rng);
    out.emplace_back(u(rng) * depth, v(rng) * depth, depth);
  }
  (void)c;
  return out;
}

TEST(Camera, ProjectMatchesOpenCv) {
  for (const CameraModel& cam : TestCameras()) {
    const auto points = RandomPoints(cam, 500, 42);
    std::vector<cv::Point3d> object;
    for (const auto& p : points) object.emplace_back(p.x(), p.y(), p.z());
    std::vector<cv::Point2d> expected;
    const cv::Mat zero = cv::Mat::zeros(3, 1, CV_64F);
    if (cam.model == DistortionModel::kFisheye) {
      cv::fisheye::projectPoints(object, expected, zero, zero, cam.CameraMatrix(), cam.DistortionCoeffs());
    } else {
      cv::projectPoints(object, zero, zero, cam.CameraMatrix(), cam.DistortionCoeffs(), expected);
    }
    double worst = 0;
    for (size_t i = 0; i < points.size(); ++i) {
      Eigen::Vector2d px;
      ASSERT_TRUE(cam.Project(points[i], &px));
      worst = std::max(worst, (px - Eigen::Vector2d(expected[i].x, expected[i].y)).norm());
      // The templated path (what Ceres uses) gives the same numbers.
      double p[3] = {points[i].x(), points[i].y(), points[i].z()}, t[2];
      ASSERT_TRUE(cam.Project(p, t));
      EXPECT_NEAR(t[0], px.x(), 1e-9);
      EXPECT_NEAR(t[1], px.y(), 1e-9);
    }
    EXPECT_LT(worst, 1e-9) << DistortionModelName(cam.model) << " with " << cam.distortion.size()
                           << " coefficients";
  }
}

TEST(Camera, AnalyticJacobianMatchesNumeric) {
  for (const CameraModel& cam : TestCameras()) {
    for (const auto& p : RandomPoints(cam, 200, 7)) {
      Eigen::Vector2d px;
      Eigen::Matrix<double, 2, 3> j;
      ASSERT_TRUE(cam.Project(p, &px, &j));
      Eigen::Matrix<double, 2, 3> numeric;
      for (int k = 0; k < 3; ++k) {
        const double h = 1e-6 * std::max(1.0, std::abs(p[k]));
        Eigen::Vector3d plus = p, minus = p;
        plus[k] += h;
        minus[k] -= h;
        numeric.col(k) = (cam.Project(plus) - cam.Project(minus)) / (2 * h);
      }
      const double scale = std::max(1.0, numeric.norm());
      EXPECT_LT((j - numeric).norm() / scale, 1e-6) << DistortionModelName(cam.model) << "\n"
                                                    << j << "\n"
                                                    << numeric;
    }
    // On the optical axis (fisheye's special case).
    Eigen::Vector2d px;
    Eigen::Matrix<double, 2, 3> j;
    ASSERT_TRUE(cam.Project(Eigen::Vector3d(0, 0, 2), &px, &j));
    EXPECT_NEAR(j(0, 0), cam.fx / 2, 1e-9);
    EXPECT_NEAR(j(1, 1), cam.fy / 2, 1e-9);
  }
}

TEST(Camera, UnprojectInvertsProject) {
  for (const CameraModel& cam : TestCameras()) {
    double worst = 0;
    for (const auto& p : RandomPoints(cam, 500, 9)) {
      const Eigen::Vector2d px = cam.Project(p);
      if (!cam.InImage(px)) continue;
      const Eigen::Vector2d n = cam.Unproject(px);
      worst = std::max(worst, (n - Eigen::Vector2d(p.x() / p.z(), p.y() / p.z())).norm());
      // Undistort: the same ray in the ideal pinhole camera.
      const Eigen::Vector2d ideal(cam.fx * p.x() / p.z() + cam.cx, cam.fy * p.y() / p.z() + cam.cy);
      EXPECT_LT((cam.Undistort(px) - ideal).norm(), 1e-8);
    }
    EXPECT_LT(worst, 1e-12) << DistortionModelName(cam.model) << " " << cam.distortion.size();
  }
}

TEST(Camera, UnprojectMatchesOpenCvUndistortPoints) {
  const CameraModel cam = TestCameras()[2];
  std::vector<cv::Point2d> pixels = {{10, 20}, {640, 480}, {1200, 900}, {100, 850}};
  std::vector<cv::Point2d> undistorted;
  cv::undistortPoints(pixels, undistorted, cam.CameraMatrix(), cam.DistortionCoeffs(), cv::noArray(),
                      cv::noArray(),
                      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 200, 1e-15));
  for (size_t i = 0; i < pixels.size(); ++i) {
    const Eigen::Vector2d n = cam.Unproject(Eigen::Vector2d(pixels[i].x, pixels[i].y));
    EXPECT_NEAR(n.x(), undistorted[i].x, 1e-6);
    EXPECT_NEAR(n.y(), undistorted[i].y, 1e-6);
  }
}

TEST(Camera, BehindCameraAndHelpers) {
  const CameraModel cam = TestCameras()[1];
  Eigen::Vector2d px;
  EXPECT_FALSE(cam.Project(Eigen::Vector3d(0, 0, -1), &px));
  EXPECT_FALSE(cam.Project(Eigen::Vector3d(0, 0, 0), &px));
  EXPECT_TRUE(cam.Project(Eigen::Vector3d(0, 0, -1)).hasNaN());
  EXPECT_TRUE(cam.InImage(Eigen::Vector2d(0, 0)));
  EXPECT_TRUE(cam.InImage(Eigen::Vector2d(-0.5, cam.height - 0.5)));
  EXPECT_FALSE(cam.InImage(Eigen::Vector2d(-0.6, 10)));
  EXPECT_FALSE(cam.InImage(Eigen::Vector2d(5, 5), 10));
  EXPECT_NEAR(cam.HorizontalFovRad(), 2 * std::atan(640 / 910.5), 1e-15);
  const cv::Mat k = cam.CameraMatrix();
  EXPECT_EQ(k.type(), CV_64F);
  EXPECT_EQ(k.at<double>(0, 0), cam.fx);
  EXPECT_EQ(k.at<double>(1, 2), cam.cy);
  EXPECT_EQ(cam.DistortionCoeffs().cols, 4);
  EXPECT_TRUE(TestCameras()[0].DistortionCoeffs().empty());
  EXPECT_TRUE(cam == TestCameras()[1]);
  CameraModel other = cam;
  other.distortion[3] += 1e-12;
  EXPECT_FALSE(cam == other);
}

TEST(Camera, ValidateAndNames) {
  CameraModel c = TestCameras()[1];
  c.fx = -1;
  EXPECT_THROW(c.Validate(), std::invalid_argument);
  c = TestCameras()[1];
  c.distortion.push_back(0.1);
  c.distortion.push_back(0.1);  // 6 radtan coefficients
  EXPECT_THROW(c.Validate(), std::invalid_argument);
  c = TestCameras()[4];
  c.distortion.pop_back();
  EXPECT_THROW(c.Validate(), std::invalid_argument);
  c = TestCameras()[0];
  c.width = 0;
  EXPECT_THROW(c.Validate(), std::invalid_argument);
  for (auto m : {DistortionModel::kNone, DistortionModel::kRadTan, DistortionModel::kFisheye})
    EXPECT_EQ(DistortionModelFromName(DistortionModelName(m)), m);
  EXPECT_EQ(DistortionModelFromName("plumb_bob"), DistortionModel::kRadTan);
  EXPECT_EQ(DistortionModelFromName("equidistant"), DistortionModel::kFisheye);
  try {
    DistortionModelFromName("brown");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("brown"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("radtan"), std::string::npos);
  }
}

}  // namespace
}  // namespace mcmt

namespace mcmt {
namespace {

// A real, strongly distorted wide-angle calibration (caliscope's 4-camera rig, cam0): every pixel of
// the image unprojects and projects back to itself.
TEST(Camera, StrongBarrelDistortionRoundTripOverWholeImage) {
  CameraModel cam;
  cam.width = 1280;
  cam.height = 720;
  cam.fx = 894.5288733178912;
  cam.fy = 896.877811780321;
  cam.cx = 624.011791468827;
  cam.cy = 361.28189843593503;
  cam.model = DistortionModel::kRadTan;
  cam.distortion = {-0.3383569013465177, 0.09672714756989992, -0.0013512226751077358, 0.003155760325647937,
                    -0.0037489346582201062};
  double worst = 0;
  for (double y = -0.5; y <= cam.height - 0.5; y += 15.5)
    for (double x = -0.5; x <= cam.width - 0.5; x += 15.5) {
      const Eigen::Vector2d px(x, y);
      const Eigen::Vector2d n = cam.Unproject(px);
      const Eigen::Vector2d back = cam.Project(Eigen::Vector3d(n.x(), n.y(), 1.0));
      worst = std::max(worst, (back - px).norm());
    }
  EXPECT_LT(worst, 1e-9);
}

}  // namespace
}  // namespace mcmt

#include <ceres/jet.h>

namespace mcmt {
namespace {

// The templated Project (what Ceres' automatic differentiation runs) gives the same derivatives as
// the analytic Jacobian, on the optical axis too.
TEST(Camera, JetDerivativesMatchAnalyticJacobian) {
  using Jet = ceres::Jet<double, 3>;
  for (const CameraModel& cam : TestCameras()) {
    auto points = RandomPoints(cam, 100, 5);
    points.emplace_back(0, 0, 1.5);
    for (const auto& p : points) {
      Jet pj[3] = {Jet(p.x(), 0), Jet(p.y(), 1), Jet(p.z(), 2)};
      Jet out[2];
      ASSERT_TRUE(cam.Project(pj, out));
      Eigen::Vector2d px;
      Eigen::Matrix<double, 2, 3> j;
      ASSERT_TRUE(cam.Project(p, &px, &j));
      EXPECT_NEAR(out[0].a, px.x(), 1e-9);
      EXPECT_NEAR(out[1].a, px.y(), 1e-9);
      for (int r = 0; r < 2; ++r)
        for (int c = 0; c < 3; ++c)
          EXPECT_NEAR(out[r].v[c], j(r, c), 1e-9 * std::max(1.0, std::abs(j(r, c))))
              << DistortionModelName(cam.model) << " " << r << "," << c;
    }
  }
}

}  // namespace
}  // namespace mcmt
