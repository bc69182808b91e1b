// mapper/diagnostics on the simulator's sessions (tests/support/mapper_sim.h) with known corner noise:
// residuals agree with the mapper's own statistics, verdicts follow the noise, and the pose covariance
// predicts the spread of camera poses over noise draws.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <tuple>

#include "mapper/diagnostics.h"
#include "tests/support/mapper_sim.h"

namespace mcmt {
namespace {

// Four cameras.
sim::Session Simulate(double noise_px, uint64_t seed, int frames = 60) {
  sim::SessionOptions o = test::MapperSession(frames, seed, noise_px);
  o.rig.num_cameras = 4;
  return sim::SimulateSession(o);
}

// The synthetic object stays near the image centres: judge by noise here (coverage has its own test).
DiagnosticsOptions NoCoverageRule() {
  DiagnosticsOptions o;
  o.poor_coverage = o.fair_coverage = 0.0;
  return o;
}

MapResult Map(const std::vector<detections_t>& messages, const sim::Session& session) {
  MapperOptions mo = test::MapperOptionsFor(session.Truth());
  mo.reference_camera = session.cameras[0].name;
  mo.threads = 1;
  return test::MapMessages(messages, mo);
}

MapResult Map(const sim::Session& session) { return Map(session.Messages(), session); }

TEST(Diagnostics, ResidualsAgreeWithTheMapperAndVerdictsFollowTheNoise) {
  const MapResult result = Map(Simulate(0.3, 3));
  const Diagnostics d = ComputeDiagnostics(result, NoCoverageRule());
  EXPECT_NEAR(d.residual_sigma_px, 0.3, 0.03);
  ASSERT_EQ(d.cameras.size(), result.map.cameras.size());
  for (size_t c = 0; c < d.cameras.size(); ++c) {
    EXPECT_EQ(d.cameras[c].inliers, result.map.cameras[c].observations) << d.cameras[c].name;
    EXPECT_NEAR(d.cameras[c].rms_px, result.map.cameras[c].rms_px, 1e-9) << d.cameras[c].name;
    EXPECT_EQ(d.cameras[c].verdict, "good") << d.cameras[c].reason;
  }
  for (const ObservationResidual& o : d.observations) {
    ASSERT_TRUE(o.inlier) << o.reason;
    double sq = 0;
    for (const Eigen::Vector2d& r : o.residual) sq += r.squaredNorm();
    EXPECT_NEAR(std::sqrt(sq / 4), o.rms_px, 1e-9);
  }
  const std::string csv = ResidualsCsv(d);
  EXPECT_EQ(csv.substr(0, csv.find('\n')), kResidualsHeader);
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 1 + 4 * static_cast<long>(d.observations.size()));
  EXPECT_NE(WithDiagnostics(ReportJson(result), d).find("\"diagnostics\": {"), std::string::npos);
}

TEST(Diagnostics, ANoisyCameraIsJudgedPoorWithTheReason) {
  const sim::Session session = Simulate(0.2, 4);
  const std::string noisy = session.cameras[2].name;
  std::vector<detections_t> messages = session.Messages();
  std::mt19937_64 rng(9);
  std::normal_distribution<double> noise(0.0, 2.0);
  for (detections_t& det : messages)
    if (det.camera == noisy)
      for (marker_t& m : det.markers)
        for (auto& c : m.corners) c[0] += noise(rng), c[1] += noise(rng);
  const MapResult result = Map(messages, session);
  const Diagnostics d = ComputeDiagnostics(result, NoCoverageRule());
  for (const CameraDiagnostics& c : d.cameras) {
    if (c.name == noisy) {
      EXPECT_EQ(c.verdict, "poor") << c.reason;
      EXPECT_NE(c.reason.find("x the"), std::string::npos) << c.reason;
    } else {
      EXPECT_NE(c.verdict, "poor") << c.name << ": " << c.reason;
    }
  }
  EXPECT_NE(VerdictLines(d).find("camera " + noisy + ": poor ("), std::string::npos);
  // With the default rules the small image area the object sweeps is itself a reason.
  for (const CameraDiagnostics& c : ComputeDiagnostics(result).cameras) {
    EXPECT_LT(c.coverage, 0.3) << c.name;
    EXPECT_NE(c.verdict, "good") << c.name;
    EXPECT_NE(c.reason.find("% of the image (move the object into the empty parts)"), std::string::npos)
        << c.reason;
  }
}

TEST(Diagnostics, PoseCovariancePredictsTheSpreadOverNoiseDraws) {
  constexpr int kDraws = 10;
  Eigen::Vector3d predicted = Eigen::Vector3d::Zero(), squared = Eigen::Vector3d::Zero();
  for (int k = 0; k < kDraws; ++k) {
    const sim::Session session = Simulate(0.5, 100 + k, 60);
    const MapResult result = Map(session);
    const Diagnostics d = ComputeDiagnostics(result);
    const MapCamera* cam = result.map.FindCamera(session.cameras[1].name);
    ASSERT_NE(cam, nullptr);
    const Rigid3 truth = Inverse(session.cameras[0].rig_from_cam) * session.cameras[1].rig_from_cam;
    const Eigen::Vector3d error_mm = 1000 * (cam->rig_from_cam.translation() - truth.translation());
    squared += error_mm.cwiseProduct(error_mm);
    ASSERT_TRUE(d.cameras[1].has_covariance) << d.cameras[1].covariance_note;
    predicted += d.cameras[1].sigma_position_mm / kDraws;
    EXPECT_TRUE(d.cameras[0].reference);
    EXPECT_FALSE(d.cameras[0].has_covariance);
  }
  const Eigen::Vector3d measured = (squared / kDraws).cwiseSqrt();
  std::printf(
      "camera position 1-sigma (mm): predicted %.3f %.3f %.3f, measured over %d draws %.3f %.3f %.3f\n",
      predicted.x(), predicted.y(), predicted.z(), kDraws, measured.x(), measured.y(), measured.z());
  // Ten draws estimate a standard deviation to about +-25%; allow a factor 2.
  EXPECT_LT(measured.norm(), 2.0 * predicted.norm());
  EXPECT_GT(measured.norm(), 0.5 * predicted.norm());
}

// Corner errors with a part every frame of a track shares (one camera seeing one marker: a constant
// offset per corner coordinate, as the detector's bias on rendered images is; diagnostics.cc
// TrackBiasTerm) do not average out over the frames. The covariance must hold the camera poses' error
// anyway. Bias sigma 0.2 px, independent noise 0.3 px, 60 frames, ten draws, per-axis rms over the three
// non-reference cameras: s^2 S^-1 alone (af08a72) predicts 4.07 mm where the cameras are 7.11 mm off
// (1.75 times), with the track bias term 6.29 mm (1.13 times; the bias estimated 0.167 px).
TEST(Diagnostics, PoseCovarianceHoldsACornerBiasSharedByATracksFrames) {
  constexpr int kDraws = 10;
  constexpr double kBiasPx = 0.2;
  double predicted = 0.0, squared = 0.0, bias_estimate = 0.0;
  for (int k = 0; k < kDraws; ++k) {
    const sim::Session session = Simulate(0.3, 200 + k, 60);
    std::vector<detections_t> messages = session.Messages();
    std::mt19937_64 rng(300 + k);
    std::normal_distribution<double> bias(0.0, kBiasPx);
    std::map<std::tuple<std::string, int, int, int>, double> offset;
    for (detections_t& det : messages)
      for (marker_t& m : det.markers)
        for (int c = 0; c < 4; ++c)
          for (int x = 0; x < 2; ++x) {
            auto it = offset.try_emplace({det.camera, m.id, c, x}, 0.0);
            if (it.second) it.first->second = bias(rng);
            m.corners[c][x] += it.first->second;
          }
    const MapResult result = Map(messages, session);
    const Diagnostics d = ComputeDiagnostics(result);
    bias_estimate += d.track_bias_sigma_px / kDraws;
    for (size_t c = 1; c < session.cameras.size(); ++c) {
      const MapCamera* cam = result.map.FindCamera(session.cameras[c].name);
      ASSERT_NE(cam, nullptr);
      ASSERT_TRUE(d.cameras[c].has_covariance) << d.cameras[c].covariance_note;
      const Rigid3 truth = Inverse(session.cameras[0].rig_from_cam) * session.cameras[c].rig_from_cam;
      squared += (1000 * (cam->rig_from_cam.translation() - truth.translation())).squaredNorm();
      predicted += d.cameras[c].sigma_position_mm.squaredNorm();
    }
  }
  const double measured_mm = std::sqrt(squared), predicted_mm = std::sqrt(predicted);
  std::printf(
      "camera position error (mm, rms over cameras and draws): predicted %.3f, measured %.3f; "
      "track bias estimated %.3f px (drawn %.3f)\n",
      predicted_mm / std::sqrt(3.0 * kDraws), measured_mm / std::sqrt(3.0 * kDraws), bias_estimate, kBiasPx);
  EXPECT_GT(bias_estimate, 0.5 * kBiasPx);
  EXPECT_LT(bias_estimate, 1.2 * kBiasPx);
  // Ninety coordinates estimate their spread to about +-8 % (the draws' cameras are not independent).
  EXPECT_LT(measured_mm, 1.3 * predicted_mm);
  EXPECT_GT(measured_mm, 0.7 * predicted_mm);
}

// A camera centre's covariance in the rig frame from its (dr, dt) covariance (diagnostics.cc FillPoseSigmas:
// dc = -R^T ([t]x dr + dt) for cam_from_rig (R, t)).
Eigen::Matrix3d CentreCovariance(const Rigid3& rig_from_cam, const Eigen::Matrix<double, 6, 6>& covariance) {
  const Rigid3 cam_from_rig = Inverse(rig_from_cam);
  const Eigen::Matrix3d rt = cam_from_rig.linear().transpose();
  const Eigen::Vector3d t = cam_from_rig.translation();
  Eigen::Matrix3d skew;
  skew << 0, -t.z(), t.y(), t.z(), 0, -t.x(), -t.y(), t.x(), 0;
  Eigen::Matrix<double, 3, 6> j;
  j << -rt * skew, -rt;
  return j * covariance * j.transpose();
}

// The printed marker size's sigma (DiagnosticsOptions::marker_size_sigma, mapper.marker_size_sigma_percent)
// is a scale every position shares about the reference camera (the rig frame's origin here) and the
// reference marker: a camera centre p's covariance gains sigma^2 p p^T, so its sigma along p grows to
// sqrt(before^2 + sigma^2 |p|^2) and across p not at all; rotations do not change; the cameras' and markers'
// translations are correlated through it. On 11dbc98 the option did not exist (the covariance did not move).
TEST(Diagnostics, MarkerSizeSigmaScalesEveryPositionAboutTheReference) {
  const sim::Session session = Simulate(0.3, 5);
  const MapResult result = Map(session);
  const Diagnostics before = ComputeDiagnostics(result);
  DiagnosticsOptions options;
  options.marker_size_sigma = 0.01;  // 1 %
  const Diagnostics after = ComputeDiagnostics(result, options);
  constexpr double s = 0.01;
  const MapCamera* reference = result.map.FindCamera(result.map.reference_camera);
  ASSERT_NE(reference, nullptr);
  EXPECT_LT(reference->rig_from_cam.translation().norm(), 1e-12);  // the rig frame is the reference's
  int checked = 0;
  for (size_t c = 0; c < after.cameras.size(); ++c) {
    if (after.cameras[c].reference) {
      EXPECT_FALSE(after.cameras[c].has_covariance);
      continue;
    }
    ASSERT_TRUE(after.cameras[c].has_covariance) << after.cameras[c].covariance_note;
    const Rigid3& rig_from_cam = result.map.cameras[c].rig_from_cam;
    const Eigen::Vector3d p = rig_from_cam.translation();
    const Eigen::Matrix3d c0 = CentreCovariance(rig_from_cam, before.cameras[c].covariance);
    const Eigen::Matrix3d c1 = CentreCovariance(rig_from_cam, after.cameras[c].covariance);
    const double scale = c0.norm() + s * s * p.squaredNorm();
    EXPECT_LT((c1 - c0 - s * s * p * p.transpose()).norm(), 1e-9 * scale) << after.cameras[c].name;
    const Eigen::Vector3d u = p.normalized();
    EXPECT_NEAR(std::sqrt(u.dot(c1 * u)), std::sqrt(u.dot(c0 * u) + s * s * p.squaredNorm()),
                1e-9 * p.norm());
    EXPECT_GT(std::sqrt(u.dot(c1 * u)), s * p.norm());
    const Eigen::Vector3d w = u.unitOrthogonal(), w2 = u.cross(w);
    EXPECT_NEAR(w.dot(c1 * w), w.dot(c0 * w), 1e-9 * scale);
    EXPECT_NEAR(w2.dot(c1 * w2), w2.dot(c0 * w2), 1e-9 * scale);
    EXPECT_LT((after.cameras[c].covariance.topLeftCorner<3, 3>() -
               before.cameras[c].covariance.topLeftCorner<3, 3>())
                  .norm(),
              1e-12 * before.cameras[c].covariance.norm());
    ++checked;
  }
  EXPECT_EQ(checked, 3);
  // The joint covariance: between two cameras' and a camera's and a marker's translations s^2 dt_a dt_b^T
  // (dt = t of cam_from_rig, dt_m = t_m - t_ref of object_from_marker).
  ASSERT_TRUE(before.map_covariance && after.map_covariance);
  const MapCovariance& j0 = *before.map_covariance;
  const MapCovariance& j1 = *after.map_covariance;
  ASSERT_FALSE(j1.markers.empty());
  const MapMarker* ref_marker = nullptr;
  for (const MapMarker& m : result.map.markers)
    if (m.id == result.map.reference_marker) ref_marker = &m;
  ASSERT_NE(ref_marker, nullptr);
  std::vector<Eigen::Vector3d> dt;
  for (const std::string& name : j1.cameras)
    dt.push_back(Inverse(result.map.FindCamera(name)->rig_from_cam).translation());
  for (int id : j1.markers)
    for (const MapMarker& m : result.map.markers)
      if (m.id == id)
        dt.push_back(m.object_from_marker.translation() - ref_marker->object_from_marker.translation());
  ASSERT_EQ(dt.size(), j1.Entries());
  const Eigen::MatrixXd delta = j1.matrix - j0.matrix;
  for (size_t a = 0; a < dt.size(); ++a)
    for (size_t b = 0; b < dt.size(); ++b) {
      Eigen::Matrix<double, 6, 6> expected = Eigen::Matrix<double, 6, 6>::Zero();
      expected.bottomRightCorner<3, 3>() = s * s * dt[a] * dt[b].transpose();
      EXPECT_LT((delta.block<6, 6>(6 * a, 6 * b) - expected).norm(), 1e-9 * (j0.matrix.norm() + s * s))
          << a << " " << b;
    }
  EXPECT_NE(DiagnosticsJson(after).find("\"marker_size_sigma_percent\": 1,"), std::string::npos);
  EXPECT_NE(DiagnosticsJson(before).find("\"marker_size_sigma_percent\": 0,"), std::string::npos);
}

// A print 0.5 % larger than the rig states (every marker 0.5 % larger: the map is 0.5 % small, whole, and
// its residuals are those of an exact print): without the option the covariance holds nothing of it and
// the camera centres are far beyond 3 sigma; with marker_size_sigma = the applied error they are within.
// Three draws of 4 cameras (9 non-reference centres), 0.1 px noise, 60 frames; 3-D Mahalanobis distance
// of each centre's error with its covariance (P(chi2(3) > 9) = 2.9 % for a right covariance). On 11dbc98:
// the option did not exist; the option at 0 is 11dbc98's covariance (the test's first half).
TEST(Diagnostics, MarkerSizeSigmaHoldsAPrintScaleError) {
  constexpr double kPrintError = 0.005;
  int beyond_without = 0, beyond_with = 0, centres = 0;
  double worst_with = 0.0;
  for (int k = 0; k < 3; ++k) {
    const sim::Session session = Simulate(0.1, 400 + k, 60);
    MapperOptions mo = test::MapperOptionsFor(session.Truth());
    mo.reference_camera = session.cameras[0].name;
    mo.threads = 1;
    // The rig says the markers are 1 / (1 + e) of their printed size.
    mo.sizes.default_size /= 1 + kPrintError;
    for (auto& [id, size] : mo.sizes.overrides) size /= 1 + kPrintError;
    const MapResult result = test::MapMessages(session.Messages(), mo);
    DiagnosticsOptions with;
    with.marker_size_sigma = kPrintError;
    const Diagnostics d0 = ComputeDiagnostics(result), d1 = ComputeDiagnostics(result, with);
    for (size_t c = 1; c < session.cameras.size(); ++c) {
      const MapCamera* cam = result.map.FindCamera(session.cameras[c].name);
      ASSERT_NE(cam, nullptr);
      ASSERT_TRUE(d0.cameras[c].has_covariance && d1.cameras[c].has_covariance);
      const Rigid3 truth = Inverse(session.cameras[0].rig_from_cam) * session.cameras[c].rig_from_cam;
      const Eigen::Vector3d error = cam->rig_from_cam.translation() - truth.translation();
      const double m0 = std::sqrt(
          error.dot(CentreCovariance(cam->rig_from_cam, d0.cameras[c].covariance).ldlt().solve(error)));
      const double m1 = std::sqrt(
          error.dot(CentreCovariance(cam->rig_from_cam, d1.cameras[c].covariance).ldlt().solve(error)));
      std::printf("draw %d %s: error %.3f mm (%.4f %% of %.3f m), Mahalanobis %.2f without, %.2f with\n", k,
                  cam->name.c_str(), 1000 * error.norm(), 100 * error.norm() / truth.translation().norm(),
                  truth.translation().norm(), m0, m1);
      beyond_without += m0 > 3;
      beyond_with += m1 > 3;
      worst_with = std::max(worst_with, m1);
      ++centres;
    }
  }
  std::printf("beyond 3 sigma: %d of %d without the option, %d with (worst %.2f)\n", beyond_without, centres,
              beyond_with, worst_with);
  EXPECT_EQ(centres, 9);
  EXPECT_GE(beyond_without, 7);
  EXPECT_LE(beyond_with, 1);  // 9 x 2.9 % expected of a right covariance (here 0, worst 2.75)
}

}  // namespace
}  // namespace mcmt
