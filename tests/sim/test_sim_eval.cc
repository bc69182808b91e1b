// sim::Evaluate against analytically known errors, ReadTrajectoryAny, ground_truth.yaml I/O.
#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <random>
#include <sstream>

#include "core/files.h"
#include "core/lcm_util.h"
#include "core/se3.h"
#include "mcmt/object_pose_t.hpp"
#include "sim/eval.h"
#include "sim/sim.h"
#include "tests/support/temp_dir.h"

namespace fs = std::filesystem;
using namespace mcmt;
using namespace mcmt::sim;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kTol = 1e-9;

using mcmt::test::TempDir;

GroundTruth MakeTruth(int cameras, int frames, ObjectKind kind = ObjectKind::kFourSided, uint64_t seed = 3) {
  RigOptions ro;
  ro.num_cameras = cameras;
  ro.seed = seed;
  ro.distortion = DistortionModel::kRadTan;
  ro.intrinsics_spread = 0.05;
  ObjectOptions oo;
  oo.kind = kind;
  oo.seed = seed;
  TrajectoryOptions to;
  to.frames = frames;
  to.seed = seed;
  const SimObject object = MakeObject(oo);
  GroundTruth t;
  t.object = object.name;
  t.cameras = MakeRig(ro);
  t.markers = object.markers;
  t.frames = MakeTrajectory(to);
  t.marker_size = object.Sizes().default_size;
  for (const auto& m : object.markers) t.marker_sizes[m.id] = m.size;
  t.fps = to.fps;
  return t;
}

// What an estimator would produce from perfect data: the rig frame is camera `ref_cam`'s frame, the
// object frame marker `ref_marker`'s frame (as the mapper chooses them).
struct Estimate {
  RigMap map;
  std::vector<TrajectoryRow> trajectory;
  Rigid3 gt_rig_from_est = Rigid3::Identity();
  Rigid3 gt_object_from_est = Rigid3::Identity();
};

Estimate ToEstimate(const GroundTruth& t, size_t ref_cam = 0, size_t ref_marker = 0) {
  Estimate e;
  e.gt_rig_from_est = t.cameras[ref_cam].rig_from_cam;
  e.gt_object_from_est = t.markers[ref_marker].object_from_marker;
  e.map = MapFromGroundTruth(t, ref_cam, ref_marker, &e.trajectory);
  for (TrajectoryRow& r : e.trajectory) {
    r.cameras = static_cast<int>(t.cameras.size());
    r.markers = 2;
  }
  return e;
}

void ExpectStatsZero(const Stats& s, const char* what) {
  EXPECT_GT(s.count, 0) << what;
  EXPECT_NEAR(s.mean, 0.0, kTol) << what;
  EXPECT_NEAR(s.max, 0.0, kTol) << what;
  EXPECT_NEAR(s.rms, 0.0, kTol) << what;
}

void ExpectStatsNear(const Stats& a, const Stats& b, const std::string& what, double tol = kTol) {
  EXPECT_EQ(a.count, b.count) << what;
  EXPECT_NEAR(a.mean, b.mean, tol) << what;
  EXPECT_NEAR(a.median, b.median, tol) << what;
  EXPECT_NEAR(a.max, b.max, tol) << what;
  EXPECT_NEAR(a.rms, b.rms, tol) << what;
}

void ExpectResultsNear(const EvalResult& a, const EvalResult& b, double tol = kTol) {
  ExpectStatsNear(a.camera_position_mm, b.camera_position_mm, "camera position", tol);
  ExpectStatsNear(a.camera_rotation_deg, b.camera_rotation_deg, "camera rotation", tol);
  ExpectStatsNear(a.configuration_mm, b.configuration_mm, "configuration", tol);
  ExpectStatsNear(a.object_translation_mm, b.object_translation_mm, "object translation", tol);
  ExpectStatsNear(a.object_rotation_deg, b.object_rotation_deg, "object rotation", tol);
  ExpectStatsNear(a.object_translation_aligned_mm, b.object_translation_aligned_mm, "aligned translation",
                  tol);
  ASSERT_EQ(a.cameras.size(), b.cameras.size());
  for (size_t i = 0; i < a.cameras.size(); ++i) {
    EXPECT_EQ(a.cameras[i].name, b.cameras[i].name);
    EXPECT_NEAR(a.cameras[i].position_mm, b.cameras[i].position_mm, tol) << a.cameras[i].name;
    EXPECT_NEAR(a.cameras[i].rotation_deg, b.cameras[i].rotation_deg, tol) << a.cameras[i].name;
  }
  ASSERT_EQ(a.markers.size(), b.markers.size());
  for (size_t i = 0; i < a.markers.size(); ++i) {
    EXPECT_EQ(a.markers[i].id, b.markers[i].id);
    EXPECT_NEAR(a.markers[i].corner_mm, b.markers[i].corner_mm, tol) << a.markers[i].id;
    EXPECT_NEAR(a.markers[i].size_mm, b.markers[i].size_mm, tol) << a.markers[i].id;
  }
}

// Small random errors everywhere, so invariance checks compare non-trivial figures.
Estimate Perturbed(const GroundTruth& t, uint64_t seed) {
  Estimate e = ToEstimate(t, 1, 2);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  auto small = [&](double rot, double trans) {
    Vector6d d;
    for (int i = 0; i < 3; ++i) d[i] = rot * g(rng);
    for (int i = 3; i < 6; ++i) d[i] = trans * g(rng);
    return d;
  };
  for (auto& c : e.map.cameras) c.rig_from_cam = PerturbLeft(c.rig_from_cam, small(0.002, 0.003));
  for (auto& m : e.map.markers) {
    m.object_from_marker = PerturbLeft(m.object_from_marker, small(0.003, 0.001));
    m.size += 0.0005 * g(rng);
  }
  for (auto& r : e.trajectory) r.rig_from_object = PerturbLeft(r.rig_from_object, small(0.01, 0.002));
  return e;
}

double AngleDeg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a.transpose() * b).angle() * 180.0 / kPi;
}

}  // namespace

// ---------------------------------------------------------------------------------------------

TEST(SimEval, GroundTruthAgainstItselfIsExactlyZero) {
  for (ObjectKind kind : {ObjectKind::kFourSided, ObjectKind::kBox, ObjectKind::kPentagon}) {
    const GroundTruth t = MakeTruth(5, 40, kind);
    for (size_t ref_cam : {size_t(0), size_t(3)}) {
      const Estimate e = ToEstimate(t, ref_cam, t.markers.size() - 1);
      const EvalResult r = Evaluate(t, &e.map, &e.trajectory);
      SCOPED_TRACE(t.object + " ref cam " + std::to_string(ref_cam));
      EXPECT_TRUE(r.has_map);
      EXPECT_TRUE(r.has_trajectory);
      ExpectStatsZero(r.camera_position_mm, "camera position");
      ExpectStatsZero(r.camera_rotation_deg, "camera rotation");
      ExpectStatsZero(r.configuration_mm, "configuration");
      ExpectStatsZero(r.object_translation_mm, "object translation");
      ExpectStatsZero(r.object_rotation_deg, "object rotation");
      ExpectStatsZero(r.object_translation_aligned_mm, "aligned translation");
      EXPECT_EQ(r.camera_position_mm.count, 5);
      EXPECT_EQ(r.configuration_mm.count, 4 * static_cast<int>(t.markers.size()));
      EXPECT_EQ(r.object_rotation_deg.count, 40);
      EXPECT_EQ(r.gt_cameras, 5);
      EXPECT_EQ(r.mapped_cameras, 5);
      EXPECT_EQ(r.gt_markers, static_cast<int>(t.markers.size()));
      EXPECT_EQ(r.mapped_markers, r.gt_markers);
      EXPECT_EQ(r.frames_with_pose, 40);
      EXPECT_TRUE(r.missing_cameras.empty());
      EXPECT_TRUE(r.missing_markers.empty());
      // The recovered alignments are the frames the estimate was expressed in.
      EXPECT_LT((r.gt_rig_from_est_rig.matrix() - e.gt_rig_from_est.matrix()).norm(), 1e-9);
      EXPECT_LT((r.gt_object_from_est_object.matrix() - e.gt_object_from_est.matrix()).norm(), 1e-9);
    }
  }
}

TEST(SimEval, GeneratedDatasetRoundTripsThroughFilesWithZeroError) {
  TempDir dir("dataset");
  DatasetOptions o;
  o.out_dir = dir.str();
  o.detections_only = true;
  o.trajectory.frames = 30;
  o.rig.num_cameras = 4;
  o.object.kind = ObjectKind::kCube;
  const DatasetSummary s = GenerateDataset(o);
  const GroundTruth read = ReadGroundTruth(dir / "ground_truth.yaml");
  ASSERT_EQ(read.frames.size(), 30u);
  // The estimate goes through map.yaml and trajectory.csv as the mapper / tracker write them.
  const Estimate e = ToEstimate(s.truth, 2, 1);
  WriteMap(dir / "map.yaml", e.map);
  WriteTrajectory(dir / "trajectory.csv", e.trajectory);
  const RigMap map = ReadMap(dir / "map.yaml");
  const std::vector<TrajectoryRow> traj = ReadTrajectoryAny(dir / "trajectory.csv");
  const EvalResult r = Evaluate(read, &map, &traj);
  ExpectStatsZero(r.camera_position_mm, "camera position");
  ExpectStatsZero(r.camera_rotation_deg, "camera rotation");
  ExpectStatsZero(r.configuration_mm, "configuration");
  ExpectStatsZero(r.object_translation_mm, "object translation");
  ExpectStatsZero(r.object_rotation_deg, "object rotation");
  EXPECT_EQ(r.frames_with_pose, 30);
  EXPECT_EQ(r.mapped_markers, 6);
}

// A 1 mm shift of one camera's centre, radially (away from the circle's centre, horizontal): the
// cross-covariance of the centres stays symmetric positive semi-definite, so the Umeyama alignment is a
// pure translation by -shift/N. The shifted camera is then off by (N-1)/N mm, every other by 1/N mm,
// no camera rotation error; every object position is off by 1/N mm (the rig alignment moved), with no
// rotation error.
TEST(SimEval, OneMillimetreRadialShiftOfOneCamera) {
  for (int n : {3, 5, 8}) {
    SCOPED_TRACE("cameras " + std::to_string(n));
    const GroundTruth t = MakeTruth(n, 20);
    Estimate e = ToEstimate(t, 0, 0);
    const int j = n - 1;
    Eigen::Vector3d radial = t.cameras[j].rig_from_cam.translation();
    radial.z() = 0;  // the circle's centre is the rig origin; cameras all share one height
    radial.normalize();
    const Eigen::Vector3d shift_est = Inverse(e.gt_rig_from_est).linear() * (0.001 * radial);
    e.map.cameras[j].rig_from_cam.translation() += shift_est;
    const EvalResult r = Evaluate(t, &e.map, &e.trajectory);
    ASSERT_EQ(r.cameras.size(), static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) {
      const double expected = i == j ? (n - 1.0) / n : 1.0 / n;
      EXPECT_NEAR(r.cameras[i].position_mm, expected, 1e-9) << r.cameras[i].name;
      EXPECT_NEAR(r.cameras[i].rotation_deg, 0.0, 1e-9) << r.cameras[i].name;
    }
    EXPECT_NEAR(r.camera_position_mm.max, (n - 1.0) / n, 1e-9);
    EXPECT_NEAR(r.camera_position_mm.mean, ((n - 1.0) / n + (n - 1) * (1.0 / n)) / n, 1e-9);
    EXPECT_NEAR(r.camera_position_mm.median, 1.0 / n, 1e-9);
    EXPECT_NEAR(r.object_translation_mm.max, 1.0 / n, 1e-9);
    EXPECT_NEAR(r.object_translation_mm.mean, 1.0 / n, 1e-9);
    EXPECT_NEAR(r.object_rotation_deg.max, 0.0, 1e-9);
    // The trajectory's own alignment absorbs a constant offset.
    EXPECT_NEAR(r.object_translation_aligned_mm.max, 0.0, 1e-9);
    ExpectStatsZero(r.configuration_mm, "configuration");
  }
}

// The metric scale error: every camera position of the estimate scaled 1.002 about its rig origin reads
// +0.2 % (whatever the estimate's frames), in the table and the JSON; the truth against itself reads 0.
TEST(SimEval, ScaledCameraPositionsGiveTheScaleError) {
  const GroundTruth t = MakeTruth(5, 10);
  Estimate e = ToEstimate(t, 2, 1);
  EXPECT_NEAR(Evaluate(t, &e.map, &e.trajectory).scale_error, 0.0, 1e-12);
  for (MapCamera& c : e.map.cameras) c.rig_from_cam.translation() *= 1.002;
  const EvalResult r = Evaluate(t, &e.map, &e.trajectory);
  EXPECT_NEAR(r.scale_error, 0.002, 1e-12);
  EXPECT_NE(FormatTable(r).find("metric scale error +0.200 %"), std::string::npos) << FormatTable(r);
  EXPECT_NE(FormatJson(r).find("\"scale_error_pct\": 0.2"), std::string::npos) << FormatJson(r);
}

// A shift in a random direction: the alignment rotates too; compare with Eigen's own Umeyama.
TEST(SimEval, CameraShiftInAnyDirectionMatchesAnIndependentUmeyama) {
  const int n = 5;
  const GroundTruth t = MakeTruth(n, 10);
  std::mt19937_64 rng(11);
  std::normal_distribution<double> g(0.0, 1.0);
  for (int trial = 0; trial < 5; ++trial) {
    Estimate e = ToEstimate(t, 1, 0);
    const int j = trial % n;
    const Eigen::Vector3d shift = 0.001 * Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
    e.map.cameras[j].rig_from_cam.translation() += shift;
    Eigen::Matrix3Xd src(3, n), dst(3, n);
    for (int i = 0; i < n; ++i) {
      src.col(i) = e.map.cameras[i].rig_from_cam.translation();
      dst.col(i) = t.cameras[i].rig_from_cam.translation();
    }
    const Eigen::Matrix4d a = Eigen::umeyama(src, dst, false);
    const EvalResult r = Evaluate(t, &e.map, &e.trajectory);
    double max_mm = 0;
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d p = a.topLeftCorner<3, 3>() * src.col(i) + a.topRightCorner<3, 1>();
      const double mm = 1000.0 * (p - dst.col(i)).norm();
      max_mm = std::max(max_mm, mm);
      EXPECT_NEAR(r.cameras[i].position_mm, mm, 1e-7) << "trial " << trial << " camera " << i;
      const Eigen::Matrix3d rot = a.topLeftCorner<3, 3>() * e.map.cameras[i].rig_from_cam.linear();
      EXPECT_NEAR(r.cameras[i].rotation_deg, AngleDeg(rot, t.cameras[i].rig_from_cam.linear()), 1e-7);
    }
    EXPECT_GT(max_mm, 0.3);
    EXPECT_LT(max_mm, 1.0);
  }
}

// Rotating the estimated object by 1 degree about its own origin on every frame (about any axis): a
// rotation error of exactly 1 degree and no translation error on every frame.
TEST(SimEval, OneDegreeObjectRotationOnEveryFrame) {
  const GroundTruth t = MakeTruth(4, 25, ObjectKind::kBox);
  Estimate e = ToEstimate(t, 2, 3);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> g(0.0, 1.0);
  for (size_t i = 0; i < e.trajectory.size(); ++i) {
    const Eigen::Vector3d axis = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
    // The rotation about the ground-truth object's origin, expressed for the estimate's object frame.
    Rigid3 rot = Rigid3::Identity();
    rot.linear() = Eigen::AngleAxisd(kPi / 180.0, axis).toRotationMatrix();
    const Rigid3 gt_est = e.gt_rig_from_est * e.trajectory[i].rig_from_object * Inverse(e.gt_object_from_est);
    e.trajectory[i].rig_from_object = Inverse(e.gt_rig_from_est) * (gt_est * rot) * e.gt_object_from_est;
  }
  const EvalResult r = Evaluate(t, &e.map, &e.trajectory);
  EXPECT_EQ(r.object_rotation_deg.count, 25);
  EXPECT_NEAR(r.object_rotation_deg.mean, 1.0, 1e-9);
  EXPECT_NEAR(r.object_rotation_deg.max, 1.0, 1e-9);
  EXPECT_NEAR(r.object_rotation_deg.median, 1.0, 1e-9);
  EXPECT_NEAR(r.object_translation_mm.max, 0.0, 1e-9);
  ExpectStatsZero(r.camera_position_mm, "camera position");
  ExpectStatsZero(r.configuration_mm, "configuration");
}

// A translation error of 2 mm along a fixed direction on half the frames.
TEST(SimEval, ObjectTranslationErrorOnSomeFrames) {
  const GroundTruth t = MakeTruth(3, 20);
  Estimate e = ToEstimate(t, 0, 1);
  const Eigen::Vector3d d_gt(0.0, 0.002, 0.0);
  for (size_t i = 0; i < e.trajectory.size(); i += 2)
    e.trajectory[i].rig_from_object.pretranslate(Inverse(e.gt_rig_from_est).linear() * d_gt);
  const EvalResult r = Evaluate(t, &e.map, &e.trajectory);
  EXPECT_EQ(r.object_translation_mm.count, 20);
  EXPECT_NEAR(r.object_translation_mm.max, 2.0, 1e-9);
  EXPECT_NEAR(r.object_translation_mm.mean, 1.0, 1e-9);
  EXPECT_NEAR(r.object_translation_mm.median, 1.0, 1e-9);  // 10 zeros, 10 twos
  EXPECT_NEAR(r.object_translation_mm.rms, std::sqrt(2.0), 1e-9);
  EXPECT_NEAR(r.object_rotation_deg.max, 0.0, 1e-9);
  // The trajectory-aligned variant re-fits the positions: errors are smaller than the raw ones.
  EXPECT_LT(r.object_translation_aligned_mm.max, 2.0);
  EXPECT_GT(r.object_translation_aligned_mm.max, 0.5);
}

// A tracker's poses (with a status and sigmas) are reported by status too, and checked against their
// sigmas: 5 ambiguous frames 10 mm off with a 1 mm sigma (beyond 3 sigma), one tracking frame 2 mm off
// (within), one without a finite sigma (left out of the fraction).
TEST(SimEval, AmbiguousPosesAndSigmasAreReportedApart) {
  const GroundTruth t = MakeTruth(3, 20);
  Estimate e = ToEstimate(t, 0, 1);
  auto shift = [&](TrajectoryRow* row, double metres) {
    row->rig_from_object.pretranslate(Inverse(e.gt_rig_from_est).linear() * Eigen::Vector3d(metres, 0, 0));
  };
  const EvalResult plain = Evaluate(t, &e.map, &e.trajectory);
  EXPECT_EQ(plain.frames_with_quality, 0);
  EXPECT_EQ(FormatTable(plain).find("poses with a status"), std::string::npos);
  for (size_t i = 0; i < e.trajectory.size(); ++i) {
    TrajectoryRow& row = e.trajectory[i];
    row.quality = PoseQuality{i % 4 == 0, 1e-3, 0.01};
    if (i % 4 == 0) shift(&row, 0.010);
  }
  shift(&e.trajectory[2], 0.002);
  e.trajectory[3].quality->sigma_position_m = NAN;
  const EvalResult r = Evaluate(t, &e.map, &e.trajectory);
  EXPECT_EQ(r.frames_with_quality, 20);
  EXPECT_EQ(r.ambiguous_frames, 5);
  EXPECT_EQ(r.frames_with_sigma, 19);
  EXPECT_EQ(r.ambiguous_translation_mm.count, 5);
  EXPECT_NEAR(r.ambiguous_translation_mm.mean, 10.0, 1e-9);
  EXPECT_EQ(r.tracking_translation_mm.count, 15);
  EXPECT_NEAR(r.tracking_translation_mm.max, 2.0, 1e-9);
  EXPECT_NEAR(r.tracking_rotation_deg.max, 0.0, 1e-9);
  EXPECT_NEAR(r.beyond_3sigma_position, 5.0 / 19.0, 1e-12);
  EXPECT_EQ(r.beyond_3sigma_rotation, 0.0);
  const std::string table = FormatTable(r);
  EXPECT_NE(table.find("ambiguous: translation (mm)"), std::string::npos) << table;
  EXPECT_NE(table.find("poses with a status: 20 (5 ambiguous); error beyond 3 sigma: position 26.3 %"),
            std::string::npos)
      << table;
  const std::string json = FormatJson(r);
  EXPECT_NE(json.find("\"ambiguous_frames\": 5"), std::string::npos) << json;
  EXPECT_NE(json.find("\"beyond_3_sigma\": {\"frames\": 19, \"position\": 0.263157"), std::string::npos)
      << json;

  // An error every pose shares (5 mm, as a map's error is) is beyond 3 sigma in every frame, and after the
  // trajectory's own alignment in none.
  Estimate shared = ToEstimate(t, 0, 1);
  for (TrajectoryRow& row : shared.trajectory) {
    row.quality = PoseQuality{false, 1e-3, 0.01};
    row.rig_from_object.pretranslate(Inverse(shared.gt_rig_from_est).linear() * Eigen::Vector3d(0, 0.005, 0));
  }
  const EvalResult rs = Evaluate(t, &shared.map, &shared.trajectory);
  EXPECT_EQ(rs.beyond_3sigma_position, 1.0);
  EXPECT_EQ(rs.beyond_3sigma_position_aligned, 0.0);
  EXPECT_LT(rs.object_translation_aligned_mm.max, 1e-6);
}

// The estimate's choice of frames does not matter: any rigid change of its rig frame and of its object
// frame, applied consistently to map and trajectory, gives the same figures.
TEST(SimEval, InvariantToTheEstimatesRigAndObjectFrames) {
  const GroundTruth t = MakeTruth(6, 30, ObjectKind::kPentagon);
  const Estimate e = Perturbed(t, 21);
  const EvalResult base = Evaluate(t, &e.map, &e.trajectory);
  // The perturbation is visible, so the comparison is meaningful.
  EXPECT_GT(base.camera_position_mm.max, 0.5);
  EXPECT_GT(base.camera_rotation_deg.max, 0.01);
  EXPECT_GT(base.configuration_mm.max, 0.1);
  EXPECT_GT(base.object_rotation_deg.max, 0.1);
  EXPECT_GT(base.object_translation_mm.max, 0.5);
  std::mt19937_64 rng(99);
  for (int trial = 0; trial < 5; ++trial) {
    const Rigid3 x = RandomRigid(rng, 3.0);  // new_rig_from_est_rig
    const Rigid3 y = RandomRigid(rng, 0.5);  // new_object_from_est_object
    Estimate f = e;
    for (auto& c : f.map.cameras) c.rig_from_cam = x * c.rig_from_cam;
    for (auto& m : f.map.markers) m.object_from_marker = y * m.object_from_marker;
    for (auto& r : f.trajectory) r.rig_from_object = x * r.rig_from_object * Inverse(y);
    SCOPED_TRACE("trial " + std::to_string(trial));
    ExpectResultsNear(Evaluate(t, &f.map, &f.trajectory), base);
  }
}

// One marker's size wrong by ds: its corners move by ds/2 along both in-plane axes (|d| = ds/sqrt 2);
// the cross-covariance stays symmetric so the object alignment does not move and the other markers
// have no error.
TEST(SimEval, MarkerSizeErrorShowsInTheConfigurationError) {
  const GroundTruth t = MakeTruth(3, 5);
  const int m_count = static_cast<int>(t.markers.size());
  for (double ds : {0.001, -0.002}) {
    for (int j : {0, 2}) {
      Estimate e = ToEstimate(t, 0, 0);
      e.map.markers[j].size += ds;
      const EvalResult r = Evaluate(t, &e.map, &e.trajectory);
      const double corner = 1000.0 * std::abs(ds) / std::sqrt(2.0);
      SCOPED_TRACE("ds " + std::to_string(ds) + " marker " + std::to_string(j));
      ASSERT_EQ(r.markers.size(), static_cast<size_t>(m_count));
      for (int i = 0; i < m_count; ++i) {
        EXPECT_NEAR(r.markers[i].corner_mm, i == j ? corner : 0.0, 1e-9) << "marker " << r.markers[i].id;
        EXPECT_NEAR(r.markers[i].size_mm, i == j ? 1000.0 * ds : 0.0, 1e-9) << "marker " << r.markers[i].id;
      }
      EXPECT_EQ(r.configuration_mm.count, 4 * m_count);
      EXPECT_NEAR(r.configuration_mm.max, corner, 1e-9);
      EXPECT_NEAR(r.configuration_mm.mean, corner / m_count, 1e-9);
      EXPECT_NEAR(r.configuration_mm.rms, corner / std::sqrt(double(m_count)), 1e-9);
      EXPECT_NEAR(r.object_translation_mm.max, 0.0, 1e-9);
      EXPECT_NEAR(r.object_rotation_deg.max, 0.0, 1e-9);
    }
  }
}

TEST(SimEval, MissingCamerasMarkersAndFramesAreCounted) {
  const GroundTruth t = MakeTruth(5, 30, ObjectKind::kBox);
  Estimate e = ToEstimate(t, 0, 0);
  e.map.cameras.erase(e.map.cameras.begin() + 2);  // cam2
  const int dropped_id = e.map.markers[4].id;
  e.map.markers.erase(e.map.markers.begin() + 4);
  std::vector<TrajectoryRow> rows;
  for (const auto& r : e.trajectory)
    if (r.seq % 3 != 0) rows.push_back(r);  // 20 of 30 frames
  rows.push_back(rows.front());             // a duplicate counts once
  const EvalResult r = Evaluate(t, &e.map, &rows);
  EXPECT_EQ(r.gt_cameras, 5);
  EXPECT_EQ(r.mapped_cameras, 4);
  EXPECT_EQ(r.missing_cameras, std::vector<std::string>{"cam2"});
  EXPECT_EQ(r.camera_position_mm.count, 4);
  EXPECT_EQ(r.gt_markers, static_cast<int>(t.markers.size()));
  EXPECT_EQ(r.mapped_markers, r.gt_markers - 1);
  EXPECT_EQ(r.missing_markers, std::vector<int>{dropped_id});
  EXPECT_EQ(r.gt_frames, 30);
  EXPECT_EQ(r.frames_with_pose, 20);
  EXPECT_EQ(r.object_rotation_deg.count, 20);
  ExpectStatsZero(r.camera_position_mm, "camera position");
  ExpectStatsZero(r.object_translation_mm, "object translation");
  const std::string json = FormatJson(r);
  EXPECT_NE(json.find("\"missing\": [\"cam2\"]"), std::string::npos) << json;
  EXPECT_NE(json.find("\"frames_with_pose\": 20"), std::string::npos) << json;
  const std::string table = FormatTable(r);
  EXPECT_NE(table.find("cameras mapped: 4 / 5 (missing: cam2)"), std::string::npos) << table;
  EXPECT_NE(table.find("frames with a pose: 20 / 30"), std::string::npos) << table;

  // Two cameras: the first common camera's full pose is the alignment; still exact.
  Estimate two = ToEstimate(t, 3, 0);
  two.map.cameras = {two.map.cameras[3], two.map.cameras[1]};
  const EvalResult r2 = Evaluate(t, &two.map, nullptr);
  EXPECT_FALSE(r2.has_trajectory);
  EXPECT_EQ(r2.mapped_cameras, 2);
  ExpectStatsZero(r2.camera_position_mm, "camera position (2 cameras)");
  ExpectStatsZero(r2.camera_rotation_deg, "camera rotation (2 cameras)");
}

TEST(SimEval, JsonEscapesControlCharactersInCameraNames) {
  // A camera named with a tab (or any control character) must still give valid JSON: no raw byte below
  // 0x20 inside a string (FormatJson itself indents with spaces only).
  const GroundTruth t = MakeTruth(3, 5, ObjectKind::kBox);
  Estimate e = ToEstimate(t, 0, 0);
  e.map.cameras.erase(e.map.cameras.begin() + 1);
  EvalResult r = Evaluate(t, &e.map, &e.trajectory);
  ASSERT_FALSE(r.cameras.empty());
  r.cameras[0].name = "cam\t0\x01";
  r.missing_cameras = {"cam\n1"};
  const std::string json = FormatJson(r);
  for (const char c : json) {
    if (c == '\n') continue;
    EXPECT_GE(static_cast<unsigned char>(c), 0x20u) << "raw control byte " << int(c) << " in " << json;
  }
  EXPECT_NE(json.find("\"cam\\t0\\u0001\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"cam\\n1\""), std::string::npos) << json;
}

template <typename F>
std::string ThrownEvalInputError(F f) {
  try {
    f();
  } catch (const EvalInputError& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("WRONG EXCEPTION TYPE: ") + e.what();
  }
  return "NO EXCEPTION";
}

TEST(SimEval, MismatchedInputsThrowNamingTheCulprit) {
  const GroundTruth t = MakeTruth(4, 10);
  {
    Estimate e = ToEstimate(t);
    e.map.cameras[1].name = "cam9";
    const std::string m = ThrownEvalInputError([&] { Evaluate(t, &e.map, &e.trajectory); });
    EXPECT_NE(m.find("'cam9'"), std::string::npos) << m;
  }
  {
    Estimate e = ToEstimate(t);
    e.map.markers[2].id = 77;
    const std::string m = ThrownEvalInputError([&] { Evaluate(t, &e.map, &e.trajectory); });
    EXPECT_NE(m.find("77"), std::string::npos) << m;
    EXPECT_NE(m.find("marker"), std::string::npos) << m;
  }
  {
    Estimate e = ToEstimate(t);
    e.trajectory[5].seq = 12345;
    const std::string m = ThrownEvalInputError([&] { Evaluate(t, &e.map, &e.trajectory); });
    EXPECT_NE(m.find("12345"), std::string::npos) << m;
  }
  {
    Estimate e = ToEstimate(t);
    e.map.cameras.clear();
    EXPECT_NE(ThrownEvalInputError([&] { Evaluate(t, &e.map, nullptr); }).find("no camera"),
              std::string::npos);
  }
  {
    Estimate e = ToEstimate(t);
    e.map.markers.clear();
    EXPECT_NE(ThrownEvalInputError([&] { Evaluate(t, &e.map, nullptr); }).find("no marker"),
              std::string::npos);
  }
  EXPECT_NE(ThrownEvalInputError([&] { Evaluate(t, nullptr, nullptr); }).find("map"), std::string::npos);
  {
    // Ids of another dictionary are other markers.
    Estimate e = ToEstimate(t);
    e.map.dictionary = "DICT_4X4_50";
    const std::string m = ThrownEvalInputError([&] { Evaluate(t, &e.map, nullptr); });
    EXPECT_NE(m.find("DICT_4X4_50"), std::string::npos) << m;
    // A dictionary file (named by a path) or no name at all is not compared.
    e.map.dictionary = "/some/where/dict.yml";
    EXPECT_NO_THROW(Evaluate(t, &e.map, nullptr));
    e.map.dictionary = "";
    EXPECT_NO_THROW(Evaluate(t, &e.map, nullptr));
  }
}

// ---------------------------------------------------------------------------------------------
// ReadTrajectoryAny

TEST(SimEval, ReadTrajectoryAnyReadsCsvAndPoseLogToTheSameRows) {
  TempDir dir("traj");
  const GroundTruth t = MakeTruth(3, 12);
  Estimate e = ToEstimate(t, 1, 1);
  for (size_t i = 0; i < e.trajectory.size(); ++i) {
    e.trajectory[i].rms_px = 0.25 * i;
    e.trajectory[i].cameras = 1 + static_cast<int>(i % 3);
    e.trajectory[i].markers = 2 + static_cast<int>(i % 2);
  }
  WriteTrajectory(dir / "trajectory.csv", e.trajectory);
  {
    lcm::LogFile log(dir / "poses.lcmlog", "w");
    ASSERT_TRUE(log.good());
    int64_t eventnum = 0;
    auto write = [&](const std::string& channel, const std::vector<uint8_t>& bytes, int64_t utime) {
      lcm::LogEvent ev;
      ev.eventnum = eventnum++;
      ev.timestamp = utime;
      ev.channel = channel;
      ev.datalen = static_cast<int32_t>(bytes.size());
      ev.data = const_cast<uint8_t*>(bytes.data());
      ASSERT_EQ(log.writeEvent(&ev), 0);
    };
    for (size_t i = 0; i < e.trajectory.size(); ++i) {
      const TrajectoryRow& row = e.trajectory[i];
      object_pose_t msg;
      msg.utime = row.utime;
      msg.seq = row.seq;
      msg.object = t.object;
      msg.rig_from_object = ToPose3d(row.rig_from_object);
      for (auto& r : msg.covariance)
        for (double& v : r) v = 0;
      msg.rms_px = row.rms_px;
      msg.num_cameras = row.cameras;
      for (int k = 0; k < row.cameras; ++k) msg.cameras.push_back("cam" + std::to_string(k));
      msg.num_markers = row.markers;
      for (int k = 0; k < row.markers; ++k) msg.markers.push_back(k);
      msg.num_rejected = 0;
      msg.status = i % 4 == 1 ? object_pose_t::STATUS_AMBIGUOUS : object_pose_t::STATUS_TRACKING;
      msg.latency_ms = 1.0;
      std::vector<uint8_t> bytes(msg.getEncodedSize());
      msg.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
      write(kPoseChannel, bytes, row.utime);
      // Noise the reader must skip: a LOST pose and a message on another channel.
      object_pose_t lost = msg;
      lost.status = object_pose_t::STATUS_LOST;
      lost.seq = 100000 + row.seq;
      std::vector<uint8_t> lost_bytes(lost.getEncodedSize());
      lost.encode(lost_bytes.data(), 0, static_cast<int>(lost_bytes.size()));
      write(kPoseChannel, lost_bytes, row.utime);
      write("MCMT_DETECTIONS_cam0", std::vector<uint8_t>(16, 7), row.utime);
    }
  }
  const auto csv = ReadTrajectoryAny(dir / "trajectory.csv");
  const auto log = ReadTrajectoryAny(dir / "poses.lcmlog");
  ASSERT_EQ(csv.size(), e.trajectory.size());
  ASSERT_EQ(log.size(), e.trajectory.size());
  for (size_t i = 0; i < csv.size(); ++i) {
    SCOPED_TRACE("row " + std::to_string(i));
    EXPECT_EQ(csv[i].seq, e.trajectory[i].seq);
    EXPECT_EQ(log[i].seq, csv[i].seq);
    EXPECT_EQ(log[i].utime, csv[i].utime);
    EXPECT_EQ(log[i].cameras, csv[i].cameras);
    EXPECT_EQ(log[i].markers, csv[i].markers);
    EXPECT_DOUBLE_EQ(log[i].rms_px, csv[i].rms_px);
    EXPECT_EQ(csv[i].cameras, e.trajectory[i].cameras);
    EXPECT_LT((csv[i].rig_from_object.matrix() - e.trajectory[i].rig_from_object.matrix()).norm(), 1e-14);
    EXPECT_LT((log[i].rig_from_object.matrix() - csv[i].rig_from_object.matrix()).norm(), 1e-14);
    // The log's poses carry their status (the CSV written from rows without one has none).
    ASSERT_TRUE(log[i].quality.has_value());
    EXPECT_EQ(log[i].quality->ambiguous, i % 4 == 1);
    EXPECT_FALSE(csv[i].quality.has_value());
  }
  // Both evaluate to zero error.
  const EvalResult r = Evaluate(t, &e.map, &log);
  ExpectStatsZero(r.object_translation_mm, "object translation (log)");
  ExpectStatsZero(r.object_rotation_deg, "object rotation (log)");

  // A log with undecodable poses only is an error naming the file; a missing file too.
  {
    lcm::LogFile bad(dir / "bad.lcmlog", "w");
    std::vector<uint8_t> junk(40, 3);
    lcm::LogEvent ev;
    ev.eventnum = 0;
    ev.timestamp = 1;
    ev.channel = kPoseChannel;
    ev.datalen = static_cast<int32_t>(junk.size());
    ev.data = junk.data();
    ASSERT_EQ(bad.writeEvent(&ev), 0);
  }
  try {
    ReadTrajectoryAny(dir / "bad.lcmlog");
    ADD_FAILURE() << "no exception for undecodable poses";
  } catch (const std::exception& ex) {
    EXPECT_NE(std::string(ex.what()).find("bad.lcmlog"), std::string::npos) << ex.what();
  }
  try {
    ReadTrajectoryAny(dir / "absent.csv");
    ADD_FAILURE() << "no exception for a missing file";
  } catch (const std::exception& ex) {
    EXPECT_NE(std::string(ex.what()).find("absent.csv"), std::string::npos) << ex.what();
  }
}

// ---------------------------------------------------------------------------------------------
// ground_truth.yaml

TEST(SimEval, GroundTruthFileRoundTripsExactly) {
  TempDir dir("gt");
  GroundTruth t = MakeTruth(4, 15, ObjectKind::kBox);
  t.cameras[1].model.model = DistortionModel::kFisheye;
  t.cameras[1].model.distortion = {0.1, -0.01, 0.001, 1.0 / 3.0};
  t.markers[2].size = 0.0321;  // an odd size
  t.marker_sizes[t.markers[2].id] = 0.0321;
  t.fps = 29.97;
  WriteGroundTruth(dir / "a.yaml", t);
  const GroundTruth r = ReadGroundTruth(dir / "a.yaml");
  EXPECT_EQ(r.object, t.object);
  EXPECT_EQ(r.dictionary, t.dictionary);
  EXPECT_EQ(r.marker_size, t.marker_size);
  EXPECT_EQ(r.fps, t.fps);
  ASSERT_EQ(r.cameras.size(), t.cameras.size());
  for (size_t i = 0; i < t.cameras.size(); ++i) {
    const CameraModel &a = t.cameras[i].model, &b = r.cameras[i].model;
    EXPECT_EQ(r.cameras[i].name, t.cameras[i].name);
    EXPECT_EQ(b.width, a.width);
    EXPECT_EQ(b.height, a.height);
    EXPECT_EQ(b.fx, a.fx);
    EXPECT_EQ(b.fy, a.fy);
    EXPECT_EQ(b.cx, a.cx);
    EXPECT_EQ(b.cy, a.cy);
    EXPECT_EQ(b.model, a.model);
    EXPECT_EQ(b.distortion, a.distortion);
    EXPECT_EQ(r.cameras[i].rig_from_cam.translation(), t.cameras[i].rig_from_cam.translation());
    EXPECT_LT((r.cameras[i].rig_from_cam.linear() - t.cameras[i].rig_from_cam.linear()).norm(), 1e-15);
  }
  ASSERT_EQ(r.markers.size(), t.markers.size());
  for (size_t i = 0; i < t.markers.size(); ++i) {
    EXPECT_EQ(r.markers[i].id, t.markers[i].id);
    EXPECT_EQ(r.markers[i].size, t.markers[i].size);
    EXPECT_EQ(r.marker_sizes.at(t.markers[i].id), t.markers[i].size);
    EXPECT_EQ(r.markers[i].object_from_marker.translation(), t.markers[i].object_from_marker.translation());
    EXPECT_LT((r.markers[i].object_from_marker.linear() - t.markers[i].object_from_marker.linear()).norm(),
              1e-15);
  }
  ASSERT_EQ(r.frames.size(), t.frames.size());
  for (size_t i = 0; i < t.frames.size(); ++i) {
    EXPECT_EQ(r.frames[i].seq, t.frames[i].seq);
    EXPECT_EQ(r.frames[i].utime, t.frames[i].utime);
    EXPECT_EQ(r.frames[i].rig_from_object.translation(), t.frames[i].rig_from_object.translation());
    EXPECT_LT((r.frames[i].rig_from_object.linear() - t.frames[i].rig_from_object.linear()).norm(), 1e-15);
  }
  // Rotations go through a quaternion (written with 17 digits), so they come back to rounding, not
  // bit-exact; a second write / read cycle does not drift further, everything else stays bit-exact.
  WriteGroundTruth(dir / "b.yaml", r);
  const GroundTruth r2 = ReadGroundTruth(dir / "b.yaml");
  for (size_t i = 0; i < t.frames.size(); ++i) {
    EXPECT_EQ(r2.frames[i].rig_from_object.translation(), t.frames[i].rig_from_object.translation());
    EXPECT_LT((r2.frames[i].rig_from_object.linear() - t.frames[i].rig_from_object.linear()).norm(), 1e-15);
  }
  const std::string a_text = ReadFile(dir / "a.yaml"), b_text = ReadFile(dir / "b.yaml");
  EXPECT_EQ(a_text.size() > 0, true);
  EXPECT_EQ(a_text.substr(0, a_text.find("cameras:")), b_text.substr(0, b_text.find("cameras:")));
}

// Edits one line of a valid ground_truth.yaml and expects ReadGroundTruth to fail naming `key`.
TEST(SimEval, MalformedGroundTruthNamesTheKey) {
  TempDir dir("bad");
  const GroundTruth t = MakeTruth(2, 3);
  WriteGroundTruth(dir / "good.yaml", t);
  const std::string good = ReadFile(dir / "good.yaml");
  ASSERT_NO_THROW(ReadGroundTruth(dir / "good.yaml"));
  struct Case {
    std::string from, to, key;
  };
  // Substrings present once in the good file (checked below).
  const std::vector<Case> cases = {
      {"marker_size: ", "marker_sizes: ", "marker_size"},
      {"\nfps: ", "\nfps: fast #", "fps"},
      {"version: 1", "version: 2", "version"},
      {"    fx: ", "    fx: abc #", "cameras.cam0.fx"},
      {"    height: 480\n    fx", "    fx", "cameras.cam0.height"},
      {"distortion_model: radtan", "distortion_model: wobbly", "cameras.cam0.distortion_model"},
      {"  0: {size: ", "  zero: {size: ", "markers.zero"},
      {"  1: {size: 0.040000000000000001,", "  1: {size: big,", "markers.1.size"},
      {"seq: 1, utime: 1000000033333, rig_from_object: {translation: [",
       "seq: 1, utime: 1000000033333, rig_from_object: {translation: [9, ",
       "frames[1].rig_from_object.translation"},
      {"seq: 2, utime: 1000000066667", "seq: 2, utime: soon", "frames[2].utime"},
      {"seq: 0, ", "", "frames[0].seq"},
      {"seq: 2, ", "seq: 2.5, ", "frames[2].seq"},
      {"    width: 640", "    width: 640.5", "cameras.cam0.width"},
      {"cameras:\n", "cameras: []\nunused:\n", "cameras"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.key);
    const size_t at = good.find(c.from);
    ASSERT_NE(at, std::string::npos) << "'" << c.from << "' not in\n" << good;
    // The first occurrence is the one meant (cam0, marker 0, frame k ...).
    std::string bad = good;
    bad.replace(at, c.from.size(), c.to);
    const std::string path = dir / "bad.yaml";
    {
      std::ofstream out(path, std::ios::binary | std::ios::trunc);
      out << bad;
    }
    try {
      ReadGroundTruth(path);
      ADD_FAILURE() << "no error for:\n" << bad.substr(0, 2000);
    } catch (const std::exception& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find(c.key), std::string::npos) << m;
      EXPECT_NE(m.find("bad.yaml"), std::string::npos) << m;
      EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    }
  }
  try {
    ReadGroundTruth(dir / "nonexistent.yaml");
    ADD_FAILURE() << "no error for a missing file";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("nonexistent.yaml"), std::string::npos) << e.what();
  }
}
