// The real caliscope recordings (../shared/data/caliscope): inverted ChArUco board, DICT_4X4_1000,
// 1280x720 MPEG-4 at 6 fps, ids 0..9. Skipped with a message when the data is absent.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "core/config.h"
#include "detector/detector.h"
#include "tests/detector/chessboard_truth.h"

namespace mcmt {
namespace {
namespace fs = std::filesystem;

const std::string kData = std::string(MCMT_SOURCE_DIR) + "/../shared/data/caliscope";

// sync_index-ordered frame_time of one cam_id (the k-th is frame k of its video).
std::vector<double> CsvTimes(const std::string& path, int cam) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  std::map<long long, double> by_sync;
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    std::vector<std::string> cells;
    std::string c;
    while (std::getline(ss, c, ',')) cells.push_back(c);
    if (std::stoi(cells[1]) == cam) by_sync[std::stoll(cells[0])] = std::stod(cells.back());
  }
  std::vector<double> out;
  for (const auto& [s, t] : by_sync) out.push_back(t);
  return out;
}

TEST(DetectorRealData, CaliscopeCharucoEveryCameraSeesTheBoard) {
  if (!fs::exists(kData + "/charuco_calibration/cam_0.mp4")) GTEST_SKIP() << "no real data in " << kData;
  const RigConfig rig = LoadRigConfig(std::string(MCMT_SOURCE_DIR) + "/configs/caliscope_charuco.yaml");
  ASSERT_EQ(rig.cameras.size(), 4u);
  for (const auto& cam : rig.cameras) {
    const std::vector<detections_t> frames = DetectRecording(rig, cam.name);
    ASSERT_EQ(frames.size(), 111u) << cam.name;
    int detections = 0;
    std::set<int> ids;
    for (size_t k = 0; k < frames.size(); ++k) {
      EXPECT_EQ(frames[k].seq, static_cast<int64_t>(k));
      EXPECT_EQ(frames[k].camera, cam.name);
      EXPECT_EQ(frames[k].camera_model.width, 1280);
      for (const auto& m : frames[k].markers) {
        EXPECT_GE(m.id, 0);
        EXPECT_LE(m.id, 9);
        ids.insert(m.id);
        ++detections;
      }
    }
    std::printf("%s: %d detections of ids 0..9 in 111 frames (%zu distinct ids)\n", cam.name.c_str(),
                detections, ids.size());
    EXPECT_GE(detections, 350) << cam.name;
    EXPECT_EQ(ids.size(), 10u) << cam.name;
  }
}

TEST(DetectorRealData, CaliscopeTimestampsFollowTheCsv) {
  if (!fs::exists(kData + "/charuco_calibration/cam_0.mp4")) GTEST_SKIP() << "no real data in " << kData;
  const RigConfig rig = LoadRigConfig(std::string(MCMT_SOURCE_DIR) + "/configs/caliscope_charuco.yaml");
  const std::string csv = kData + "/charuco_calibration/timestamps.csv";
  std::vector<std::vector<double>> times;
  for (int c = 0; c < 4; ++c) times.push_back(CsvTimes(csv, c));
  for (int c = 0; c < 4; ++c) {
    const std::vector<detections_t> frames = DetectRecording(rig, "cam" + std::to_string(c), 20);
    ASSERT_EQ(frames.size(), 20u);
    for (size_t k = 0; k < frames.size(); ++k) {
      // Default caliscope_time "sync": the earliest camera's frame_time of the same sync_index, shared.
      double earliest = times[0][k];
      for (int o = 1; o < 4; ++o) earliest = std::min(earliest, times[o][k]);
      EXPECT_EQ(frames[k].utime, std::llround(earliest * 1e6)) << "cam" << c << " frame " << k;
      EXPECT_LE(std::abs(frames[k].utime - std::llround(times[c][k] * 1e6)), 60000);
    }
  }
}

// The board's marker corners against its chessboard corners (tests/detector/chessboard_truth.h, an
// independent truth on the same frames): unbiased on average, and within 0.05 px in every camera and
// every size band of 100 markers or more. Measured (2026-12-03): all -0.006 px (+0.015 % of size);
// cameras -0.034..+0.025 px; 10-20 px +0.028, 20-30 px +0.009, 30-40 px -0.038, 40-50 px -0.019 px.
// Stock OpenCV on the same frames: -0.386 px (the check can tell a biased detector).
// Each camera's marker size error (detected perimeter / predicted - 1), the quantity issue 15's 0.1 %
// target is about: NOT met per camera. Measured (2026-12-04, configs/caliscope_charuco.yaml as is) cam0-3
// +0.047 / -0.208 / +0.240 / +0.259 %; the bound 0.30 % is that measured shortfall plus a margin, a
// regression guard, not the target. The map meets 0.1 % (test_mapper_realdata) by cancellation between
// cameras (bench/results/2026-12-04-caliscope-corners.md).
TEST(DetectorRealData, CaliscopeCornersAgreeWithTheChessboard) {
  if (!fs::exists(kData + "/charuco_calibration/cam_0.mp4")) GTEST_SKIP() << "no real data in " << kData;
  const RigConfig rig = LoadRigConfig(std::string(MCMT_SOURCE_DIR) + "/configs/caliscope_charuco.yaml");
  const testing::ChessboardComparison c = testing::CompareWithChessboard(rig);
  std::printf("chessboard homographies: %d frames, rms %.3f px\n", c.frames, c.homography_rms_px);
  ASSERT_GT(c.frames, 100);
  EXPECT_LT(c.homography_rms_px, 0.25);
  ASSERT_GT(c.mcmt.size(), 1000u);
  const testing::ChessboardMean all = testing::CameraMean(c.mcmt, ""),
                                stock = testing::CameraMean(c.stock, "");
  std::printf("offset along the edge normals: mcmt %+.4f px (%d markers), stock %+.4f px (%d)\n",
              all.offset_px, all.n, stock.offset_px, stock.n);
  EXPECT_LE(std::abs(all.offset_px), 0.02);
  EXPECT_LT(stock.offset_px, -0.2);
  for (const CameraConfig& cam : rig.cameras) {
    const testing::ChessboardMean m = testing::CameraMean(c.mcmt, cam.name);
    std::printf("  %s: %+.4f px, size %+.3f %% (%d markers)\n", cam.name.c_str(), m.offset_px,
                100 * m.size_rel, m.n);
    EXPECT_GE(m.n, 200) << cam.name;
    EXPECT_LE(std::abs(m.offset_px), 0.05) << cam.name;
    EXPECT_LE(std::abs(m.size_rel), 0.0030) << cam.name << " (target 0.1 %, measured shortfall)";
    RecordProperty("size_error_percent_" + cam.name, std::to_string(100 * m.size_rel));
  }
  for (int band = 1; band < 8; ++band) {
    const testing::ChessboardMean m = testing::MeanOf(
        c.mcmt, [&](const testing::ChessboardMarker& k) { return static_cast<int>(k.side_px / 10) == band; });
    std::printf("  %d-%d px: %+.4f px (%d markers)\n", 10 * band, 10 * band + 10, m.offset_px, m.n);
    if (m.n >= 100) {
      EXPECT_LE(std::abs(m.offset_px), 0.05) << 10 * band << " px";
    }
  }
}

// The same comparison with detector.tone auto (configs/caliscope_charuco_tone_auto.yaml, 120 markers):
// each camera's gamma and sharpening estimated from its own markers, then (DetectRecording's first pass)
// used on every frame. The four webcams differ (cam0 and cam1 soft, cam2 and cam3 sharpened;
// bench/results/2026-12-04-calib3.md), so one tone for all cannot be right. Measured (2026-12-04):
// cam0-3 -0.046 / +0.171 / -0.061 / +0.039 %, mean |size| 0.079 % (the estimate used only from the frame
// after it, as live: -0.123 / +0.167 / -0.005 / +0.132 %, mean 0.107 %; the config's one tone for all:
// 0.189 %). Bounds: the mean 0.09 % and each camera 0.2 % (cam1 misses the 0.1 % target; the chessboard
// truth itself is good to about 0.1 % per camera on cams 1-3).
TEST(DetectorRealData, CaliscopeCornersWithAutoToneAgreeWithTheChessboardPerCamera) {
  if (!fs::exists(kData + "/charuco_calibration/cam_0.mp4")) GTEST_SKIP() << "no real data in " << kData;
  RigConfig rig = LoadRigConfig(std::string(MCMT_SOURCE_DIR) + "/configs/caliscope_charuco_tone_auto.yaml");
  const testing::ChessboardComparison c = testing::CompareWithChessboard(rig);
  double mean_abs = 0;
  for (const CameraConfig& cam : rig.cameras) {
    const testing::ChessboardMean m = testing::CameraMean(c.mcmt, cam.name);
    std::printf("  %s: size %+.3f %% (%d markers)\n", cam.name.c_str(), 100 * m.size_rel, m.n);
    EXPECT_GE(m.n, 200) << cam.name;
    EXPECT_LE(std::abs(m.size_rel), 0.002) << cam.name;
    mean_abs += std::abs(m.size_rel) / rig.cameras.size();
  }
  std::printf("mean |size error| %.3f %%\n", 100 * mean_abs);
  EXPECT_LE(mean_abs, 0.0009);
}

TEST(DetectorRealData, Caliscope4CamRecordingOpens) {
  if (!fs::exists(kData + "/4_cam_recording/cam_0.mp4")) GTEST_SKIP() << "no real data in " << kData;
  const RigConfig rig = LoadRigConfig(std::string(MCMT_SOURCE_DIR) + "/configs/caliscope_4cam.yaml");
  const std::vector<detections_t> frames = DetectRecording(rig, "cam0");
  EXPECT_EQ(frames.size(), 48u);
  int detections = 0;
  for (const auto& f : frames) detections += f.num_markers;
  std::printf("4_cam_recording cam0: %d detections in %zu frames\n", detections, frames.size());
  EXPECT_GT(detections, 0);
}

}  // namespace
}  // namespace mcmt
