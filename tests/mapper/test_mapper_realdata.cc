// The mapper on real footage (caliscope sessions, ../shared/data/caliscope): detections by the project's
// detector (DetectRecording), mapped, compared with caliscope's own calibration (camera_array.toml)
// and with the ChArUco board's known geometry.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <set>

#include "core/config.h"
#include "detector/detector.h"
#include "mapper/mapper.h"
#include "sim/peer_calibration.h"
#include "tests/detector/chessboard_truth.h"

namespace mcmt {
namespace {

namespace fs = std::filesystem;
const std::string kData = std::string(MCMT_SOURCE_DIR) + "/../shared/data/caliscope";

// Our map against caliscope's own calibration (camera centres rigidly aligned).
sim::PeerAgreement CompareWithCaliscope(const RigMap& map, const std::string& camera_array) {
  return sim::CompareWithPeer(map, sim::ReadCaliscopeCameras(camera_array));
}

// Detected once per rig file for all the tests of this binary.
std::vector<detections_t> DetectAll(const RigConfig& rig) {
  static std::map<std::string, std::vector<detections_t>> cache;
  auto it = cache.find(rig.path);
  if (it != cache.end()) return it->second;
  std::vector<detections_t> all;
  for (const CameraConfig& c : rig.cameras) {
    std::vector<detections_t> d = DetectRecording(rig, c.name);
    all.insert(all.end(), d.begin(), d.end());
  }
  cache[rig.path] = all;
  return all;
}

class MapperRealData : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(kData + "/charuco_calibration/cam_0.mp4"))
      GTEST_SKIP() << "real data not found at " << kData << " (the caliscope sessions of ../shared/data)";
  }
};

TEST_F(MapperRealData, CharucoCalibrationAgreesWithCaliscope) {
  const RigConfig rig = LoadRigConfig(std::string(MCMT_SOURCE_DIR) + "/configs/caliscope_charuco.yaml");
  const std::vector<detections_t> detections = DetectAll(rig);
  // Without the id whitelist, to exercise the mapper's own rejection of ids that are not on the board.
  MapperOptions options = MapperOptions::FromConfig(rig);
  options.marker_ids.clear();
  Mapper mapper(options);
  for (const auto& d : detections) mapper.Add(d);
  const MapResult result = mapper.Solve();
  ASSERT_EQ(result.map.cameras.size(), 4u);
  const sim::PeerAgreement a =
      CompareWithCaliscope(result.map, kData + "/charuco_calibration/camera_array.toml");
  EXPECT_LT(a.max_position_mm, 30.0);
  EXPECT_LT(a.max_rotation_deg, 2.0);
  RecordProperty("camera_agreement",
                 std::to_string(a.max_position_mm) + " mm, " + std::to_string(a.max_rotation_deg) + " deg");
  // The board: all 10 markers, no other id, coplanar on a 5.4 cm grid (the reference marker's axes are
  // the board's axes).
  std::set<int> ids;
  for (const MapMarker& m : result.map.markers) ids.insert(m.id);
  EXPECT_EQ(ids, (std::set<int>{0, 1, 2, 3, 4, 5, 6, 7, 8, 9}));
  // Ideal grid point of each marker centre (nearest 5.4 cm grid point in the reference marker's frame,
  // z = 0), then a rigid fit of the measured centres to those points: residuals within 1 mm.
  std::vector<Eigen::Vector3d> measured, ideal;
  for (const MapMarker& m : result.map.markers) {
    const Eigen::Vector3d p = m.object_from_marker.translation();
    measured.push_back(p);
    ideal.emplace_back(0.054 * std::round(p.x() / 0.054), 0.054 * std::round(p.y() / 0.054), 0.0);
  }
  const Rigid3 grid_from_object = AlignRigid(measured, ideal);
  double worst = 0;
  for (size_t i = 0; i < measured.size(); ++i) {
    const double off = (grid_from_object * measured[i] - ideal[i]).norm();
    worst = std::max(worst, off);
    EXPECT_LT(off, 0.001) << "marker " << result.map.markers[i].id << " at " << measured[i].transpose();
  }
  RecordProperty("grid_max_offset_mm", std::to_string(worst * 1000));
  // The map's scale comes from the markers' corners (their size, 4.05 cm): a corner bias is a scale
  // error. The board's nearest-neighbour marker spacing (diagonal squares: 5.4 cm * sqrt(2)) relative
  // to the marker size is 1.8856; the map's, from the least-squares scale of all centre distances
  // against the grid's. The target is 0.1 %: with the per-side gamma fit (gamma: 0) the detector gave
  // +0.158 % (-0.41 % before the side model); with the webcams' tone and sharpening in the config
  // (gamma 2, unsharp 0.5 / 1 px in linear light) +0.000 %.
  const double spacing_over_size = testing::BoardSpacingOverSize(result.map);
  std::printf("board: marker spacing / marker size %.5f (board 1.88562, %+.3f %%)\n", spacing_over_size,
              100.0 * (spacing_over_size / 1.885618 - 1.0));
  RecordProperty("spacing_over_size", std::to_string(spacing_over_size));
  EXPECT_NEAR(spacing_over_size, 1.885618, 0.001 * 1.885618);
  // Every other id the detector reported is rejected (reported), not mapped.
  for (const RejectedMarker& r : result.report.rejected_markers) EXPECT_GT(r.id, 9) << r.reason;
}

// The same session with the webcams' tone and sharpening estimated per camera from its own markers
// (configs/caliscope_charuco_tone_auto.yaml: detector.tone auto with 120 markers, detector/tone.h)
// instead of one tone for all four (the values measured on the board's edge profiles: gamma 2, unsharp
// 0.5 / 1 px of linear light), DetectRecording using each camera's estimate on every frame. The webcams
// differ (cam0 / cam1 soft, cam2 / cam3 sharpened: bench/results/2026-12-04-calib3.md); estimated on
// 2026-12-04: gamma 2.62 / 1.85 / 1.81 / 1.63 (cam0-3), amount 0.75 (linear light) / 0 / 0.42 / 0.35,
// sigma 0.72 / - / 1.42 / 1.55 px. Measured: spacing / size +0.086 % (issue 15's 0.1 % met, with each
// camera's corners within 0.17 % of the chessboard's, test_detector_realdata; the estimate used only from
// the frame after it, as live: +0.111 %; 60 markers: +0.177 %, cam0's order not identified).
TEST_F(MapperRealData, CharucoCalibrationWithAutoTone) {
  const RigConfig rig =
      LoadRigConfig(std::string(MCMT_SOURCE_DIR) + "/configs/caliscope_charuco_tone_auto.yaml");
  Mapper mapper(MapperOptions::FromConfig(rig));
  for (const auto& d : DetectAll(rig)) mapper.Add(d);
  const MapResult result = mapper.Solve();
  ASSERT_EQ(result.map.cameras.size(), 4u);
  const double spacing_over_size = testing::BoardSpacingOverSize(result.map);
  std::printf("board (tone auto): marker spacing / marker size %.5f (board 1.88562, %+.3f %%)\n",
              spacing_over_size, 100.0 * (spacing_over_size / 1.885618 - 1.0));
  RecordProperty("spacing_over_size_tone_auto", std::to_string(spacing_over_size));
  EXPECT_NEAR(spacing_over_size, 1.885618, 0.001 * 1.885618);
}

// The same session with every marker's corners replaced by the board's chessboard corners' prediction
// (tests/detector/chessboard_truth.h): the mapper meets the 0.1 % target on unbiased corners
// (-0.016 % measured on 2026-12-03, against +0.148 % from the detected corners), so what is left of
// the detected corners' error is the detector's.
TEST_F(MapperRealData, CharucoCalibrationFromChessboardCornersHasTheBoardsScale) {
  const RigConfig rig = LoadRigConfig(std::string(MCMT_SOURCE_DIR) + "/configs/caliscope_charuco.yaml");
  const testing::ChessboardComparison c = testing::CompareWithChessboard(rig);
  Mapper mapper(MapperOptions::FromConfig(rig));
  for (const auto& d : c.predicted) mapper.Add(d);
  const MapResult result = mapper.Solve();
  ASSERT_EQ(result.map.cameras.size(), 4u);
  ASSERT_EQ(result.map.markers.size(), 10u);
  const double spacing_over_size = testing::BoardSpacingOverSize(result.map);
  std::printf("board from chessboard-predicted corners: spacing / size %.5f (%+.3f %%)\n", spacing_over_size,
              100.0 * (spacing_over_size / 1.885618 - 1.0));
  EXPECT_NEAR(spacing_over_size, 1.885618, 0.001 * 1.885618);
}

// Why corner_weights stays equal by default (core/marker.h CornerSqrtInformation; sides halves the steep
// views' scale error on the reference renderer's maps). On this board, against the chessboard's prediction
// (build/bench/diag_corner_weights, bench/results/2026-12-05-weights.md), the corners' errors do grow
// along the sides where they meet at a narrow angle as sides assumes (whitened rms along / across 0.95),
// but that part moves the board's scale by -0.02 % whichever the weights; the part across the sides (the
// webcams' edge offsets) moves it +0.04 % with equal weights and +0.06 % with sides, which weighs it more.
// Measured on 2026-12-05: spacing / size -0.002 % (equal) -> +0.025 % (sides), tone auto +0.082 ->
// +0.119 % (over the 0.1 % target); with the skewed quads' sides turned (detector.cc TurnSkewedSides)
// +0.006 -> +0.029 %, tone auto +0.092 -> +0.126 %; on random halves of the frames sides - equal is +0.036 +-
// 0.012 % and +0.045 +- 0.013 % (the scale's own spread over the halves: 0.04 %). If a detector change makes
// sides map this board closer to its geometry than equal, revisit the default.
TEST_F(MapperRealData, CornerWeightsBySidesDoNotBringTheBoardsScaleCloser) {
  for (const std::string name : {"caliscope_charuco.yaml", "caliscope_charuco_tone_auto.yaml"}) {
    const RigConfig rig = LoadRigConfig(std::string(MCMT_SOURCE_DIR) + "/configs/" + name);
    double error_pct[2];
    for (int sides = 0; sides < 2; ++sides) {
      MapperOptions options = MapperOptions::FromConfig(rig);
      options.corner_weighting.mode = sides ? "sides" : "equal";
      Mapper mapper(options);
      for (const auto& d : DetectAll(rig)) mapper.Add(d);
      const MapResult result = mapper.Solve();
      ASSERT_EQ(result.map.markers.size(), 10u) << name;
      error_pct[sides] = 100.0 * (testing::BoardSpacingOverSize(result.map) / 1.885618 - 1.0);
    }
    std::printf("%s: spacing / size %+.3f %% (equal), %+.3f %% (sides)\n", name.c_str(), error_pct[0],
                error_pct[1]);
    RecordProperty(name + "_equal_sides_pct",
                   std::to_string(error_pct[0]) + " " + std::to_string(error_pct[1]));
    EXPECT_GE(std::abs(error_pct[1]), std::abs(error_pct[0]))
        << name << ": sides now maps the board closer than equal; revisit corner_weights' default";
  }
}

TEST_F(MapperRealData, FourCamRecordingPlacesAllOrNamesTheCamera) {
  const RigConfig rig = LoadRigConfig(std::string(MCMT_SOURCE_DIR) + "/configs/caliscope_4cam.yaml");
  const std::vector<detections_t> detections = DetectAll(rig);
  Mapper mapper(MapperOptions::FromConfig(rig));
  for (const auto& d : detections) mapper.Add(d);
  try {
    const MapResult result = mapper.Solve();
    ASSERT_EQ(result.map.cameras.size(), 4u);
    const sim::PeerAgreement a =
        CompareWithCaliscope(result.map, kData + "/4_cam_recording/camera_array.toml");
    EXPECT_LT(a.max_position_mm, 30.0);
    EXPECT_LT(a.max_rotation_deg, 2.0);
    RecordProperty("camera_agreement",
                   std::to_string(a.max_position_mm) + " mm, " + std::to_string(a.max_rotation_deg) + " deg");
  } catch (const MapperError& e) {
    const std::string what = e.what();
    // The data's README: camera 1 sees the board rarely and at grazing angles.
    EXPECT_NE(what.find("camera 'cam1'"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    RecordProperty("error", what);
  }
}

// Issue 14 item 7: with --allow-partial the best-connected camera, chosen as the reference, was one that
// does not fit after refinement, and the reference branch indexed the problems with the address of a copy
// (a crash). The reference must be a camera that can be placed: the others are mapped relative to it, the
// cameras left out are named.
TEST_F(MapperRealData, FourCamRecordingWithAllowPartialKeepsAPlaceableReference) {
  const RigConfig rig = LoadRigConfig(std::string(MCMT_SOURCE_DIR) + "/configs/caliscope_4cam.yaml");
  MapperOptions options = MapperOptions::FromConfig(rig);
  options.allow_partial = true;
  Mapper mapper(options);
  for (const auto& d : DetectAll(rig)) mapper.Add(d);
  const MapResult result = mapper.Solve();
  ASSERT_GE(result.map.cameras.size(), 2u);
  const std::vector<std::string>& dropped = result.report.dropped_cameras;
  EXPECT_EQ(std::count(dropped.begin(), dropped.end(), result.map.reference_camera), 0)
      << "reference " << result.map.reference_camera << " was left out";
  const MapCamera* reference = result.map.FindCamera(result.map.reference_camera);
  ASSERT_NE(reference, nullptr) << result.map.reference_camera;
  EXPECT_LT((reference->rig_from_cam.matrix() - Eigen::Matrix4d::Identity()).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_EQ(result.map.cameras.size() + dropped.size(), 4u);
  for (const std::string& name : dropped) {
    bool named = false;
    for (const std::string& w : result.report.warnings) named = named || w.find("'" + name + "'") != w.npos;
    EXPECT_TRUE(named) << name << " left out without a warning naming it";
  }
  RecordProperty("mapped_cameras", static_cast<int>(result.map.cameras.size()));
  RecordProperty("reference_camera", result.map.reference_camera);
}

}  // namespace
}  // namespace mcmt
