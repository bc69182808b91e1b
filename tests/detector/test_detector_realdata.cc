// The real caliscope recordings (../shared/data/caliscope): inverted ChArUco board, DICT_4X4_1000,
// 1280x720 MPEG-4 at 6 fps, ids 0..9. Skipped with a message when the data is absent.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "core/config.h"
#include "detector/detector.h"
#include "tests/detector/charuco_render.h"
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

std::array<cv::Point2d, 4> CvQuad(const std::array<Eigen::Vector2d, 4>& q) {
  return {cv::Point2d(q[0].x(), q[0].y()), cv::Point2d(q[1].x(), q[1].y()), cv::Point2d(q[2].x(), q[2].y()),
          cv::Point2d(q[3].x(), q[3].y())};
}
std::array<Eigen::Vector2d, 4> EigenQuad(const std::array<cv::Point2d, 4>& q) {
  return {Eigen::Vector2d(q[0].x, q[0].y), Eigen::Vector2d(q[1].x, q[1].y), Eigen::Vector2d(q[2].x, q[2].y),
          Eigen::Vector2d(q[3].x, q[3].y)};
}

// The detected minus the predicted skew (testing::QuadSkewDeg: mean |corner angle - 90|, deg) over the
// markers `take` selects: mean, standard error, count.
struct SkewError {
  double mean_deg = 0, se_deg = 0;
  int n = 0;
};
SkewError SkewErrorOf(const std::vector<testing::ChessboardMarker>& markers,
                      const std::function<bool(const testing::ChessboardMarker&)>& take) {
  SkewError e;
  double sq = 0;
  for (const testing::ChessboardMarker& m : markers) {
    if (!take(m)) continue;
    const double d = testing::QuadSkewDeg(CvQuad(m.got_ideal)) - testing::QuadSkewDeg(CvQuad(m.want_ideal));
    e.mean_deg += d, sq += d * d, ++e.n;
  }
  if (e.n) e.mean_deg /= e.n, e.se_deg = std::sqrt(std::max(0.0, sq / e.n - e.mean_deg * e.mean_deg) / e.n);
  return e;
}

// The same comparison with detector.tone auto (configs/caliscope_charuco_tone_auto.yaml, 120 markers):
// each camera's gamma and sharpening estimated from its own markers, then (DetectRecording's first pass)
// used on every frame. The four webcams differ (cam0 and cam1 soft, cam2 and cam3 sharpened;
// bench/results/2026-12-04-calib3.md), so one tone for all cannot be right.
// Judged on the frames seen at most 55 deg from the board's normal: up to there the chessboard truth is
// sound on renders of this board (RenderedBoardTruthIsSoundUpTo55Deg), beyond it it reads sizes about
// 0.1 % small and angles 0.15 deg too skewed at 24 px (2026-12-06; bench/results/2026-12-05-truthtest.md:
// -0.07..-0.09 % at 58-65 deg), as much as the bound. cam1 films the board steeply (149 of its 270 markers
// beyond 55 deg), so each camera needs 100 markers there, not 200. Measured (2026-12-06, inverted prints
// searched in the negated image), <= 55 deg: cam0-3 -0.040 / +0.176 / -0.096 / -0.034 % (404 / 124 / 419 /
// 421 markers), mean 0.086 %; all views (printed beside, not asserted): -0.044 / +0.191 / -0.096 / -0.044 %
// (before that search, main 29430f8: <= 55 deg mean 0.080 %, all views 0.081 %). Bounds: the
// mean 0.09 % and each camera 0.2 % (the truth itself is good to about 0.1 % per camera on cams 1-3: its two
// independent versions differ by 0.05-0.12 %).
// Each camera's angle error by marker size is printed (not asserted: main's small markers come out too
// square on cams 2 and 3, -0.315 / -0.300 deg at < 28 px, se 0.09; the truth's angles are sound to
// 0.05 deg up to 55 deg on renders).
TEST(DetectorRealData, CaliscopeCornersWithAutoToneAgreeWithTheChessboardPerCamera) {
  if (!fs::exists(kData + "/charuco_calibration/cam_0.mp4")) GTEST_SKIP() << "no real data in " << kData;
  RigConfig rig = LoadRigConfig(std::string(MCMT_SOURCE_DIR) + "/configs/caliscope_charuco_tone_auto.yaml");
  const testing::ChessboardComparison c = testing::CompareWithChessboard(rig);
  constexpr double kTruthSoundDeg = 55;
  double mean_abs = 0;
  for (const CameraConfig& cam : rig.cameras) {
    const testing::ChessboardMean all = testing::CameraMean(c.mcmt, cam.name);
    const testing::ChessboardMean m = testing::MeanOf(c.mcmt, [&](const testing::ChessboardMarker& k) {
      return k.camera == cam.name && k.view_deg <= kTruthSoundDeg;
    });
    std::printf("  %s: size %+.3f %% (%d markers at <= %.0f deg); all views %+.3f %% (%d)\n",
                cam.name.c_str(), 100 * m.size_rel, m.n, kTruthSoundDeg, 100 * all.size_rel, all.n);
    for (const bool large : {false, true}) {
      const SkewError e = SkewErrorOf(c.mcmt, [&](const testing::ChessboardMarker& k) {
        return k.camera == cam.name && k.view_deg <= kTruthSoundDeg && (k.side_px >= 28) == large;
      });
      if (e.n == 0) continue;
      std::printf("    markers %s 28 px: skew %+.3f deg (se %.3f, %d markers)\n", large ? ">=" : "< ",
                  e.mean_deg, e.se_deg, e.n);
    }
    EXPECT_GE(m.n, 100) << cam.name;
    EXPECT_LE(std::abs(m.size_rel), 0.002) << cam.name;
    mean_abs += std::abs(m.size_rel) / rig.cameras.size();
  }
  std::printf("mean |size error| %.3f %% (<= %.0f deg)\n", 100 * mean_abs, kTruthSoundDeg);
  EXPECT_LE(mean_abs, 0.0009);
}

// The caliscope board rendered whole at known poses (tests/detector/charuco_render.h; blur 0.7 px, gamma
// 1.85, noise 2 grey levels): the chessboard truth's own error, and mcmt's markers against the true
// corners, at one tilt and head-on marker size.
struct RenderedBoardFigures {
  int markers = 0, found = 0;
  double truth_size_rel = 0, truth_skew_deg = 0;     // the chessboard truth against the true corners
  double offset_px = 0, size_rel = 0, skew_deg = 0;  // mcmt against the true corners
  double truth_size_rel_se = 0;                      // standard error of truth_size_rel
};

RenderedBoardFigures MeasureRenderedBoard(int poses, double view_deg, double marker_px, uint64_t seed) {
  const auto board = testing::CaliscopeCharucoBoard();
  testing::Imaging im;
  im.blur_sigma = 0.7, im.gamma = 1.85;
  MarkerConfig mc;
  mc.dictionary = "DICT_4X4_1000", mc.inverted = true;
  DetectorOptions o;
  o.inverted = true, o.gamma = im.gamma;
  MarkerDetector detector(mc, o);
  std::mt19937_64 rng(seed);
  RenderedBoardFigures f;
  double truth_sq = 0;
  for (int pose = 0; pose < poses; ++pose) {
    const testing::RenderedBoardPose r =
        testing::RenderBoardPose(board, view_deg, marker_px, im, detector, rng);
    for (const testing::RenderedBoardMarker& m : r.markers) {
      const double truth = testing::QuadPerimeter(m.chess) / testing::QuadPerimeter(m.real) - 1;
      f.truth_size_rel += truth, truth_sq += truth * truth, ++f.markers;
      f.truth_skew_deg += testing::QuadSkewDeg(m.chess) - testing::QuadSkewDeg(m.real);
      if (!m.found) continue;
      testing::ChessboardMarker against_real;
      testing::SideOffsets(EigenQuad(m.got), EigenQuad(m.real), &against_real);
      f.offset_px += against_real.offset_px, f.size_rel += against_real.size_rel, ++f.found;
      f.skew_deg += testing::QuadSkewDeg(m.got) - testing::QuadSkewDeg(m.real);
    }
  }
  if (f.markers) {
    f.truth_size_rel /= f.markers, f.truth_skew_deg /= f.markers;
    f.truth_size_rel_se =
        std::sqrt(std::max(0.0, truth_sq / f.markers - f.truth_size_rel * f.truth_size_rel) / f.markers);
  }
  if (f.found) f.offset_px /= f.found, f.size_rel /= f.found, f.skew_deg /= f.found;
  std::printf(
      "rendered board, %d poses at %.0f deg, %.0f px markers: chessboard truth %+.3f %% (se %.3f) skew %+.3f "
      "deg (%d markers); mcmt %+.4f px, size %+.3f %%, skew %+.3f deg (%d found)\n",
      poses, view_deg, marker_px, 100 * f.truth_size_rel, 100 * f.truth_size_rel_se, f.truth_skew_deg,
      f.markers, f.offset_px, 100 * f.size_rel, f.skew_deg, f.found);
  return f;
}

// The chessboard truth the tests above rest on, judged on renders of the same board with known corners
// (no real data needed): at 55 deg and 24 px markers, its sizes within 0.1 % and its angles within
// 0.1 deg, so the per-camera test above may use every view up to 55 deg. Measured (2026-12-06, 30 poses,
// seeds 5-8): sizes -0.013 / -0.067 / -0.067 / -0.047 % (standard errors 0.03-0.04), angles +0.003..+0.050
// deg; at 62 deg -0.108..+0.027 % (se 0.04-0.08) and -0.10..+0.15 deg (truthtest, 100 poses: -0.07..-0.09 %
// at 58-65 deg). mcmt on the same renders, against the true corners: its sides in place (-0.007..-0.009 px
// along their normals; the target 0.02 px), but small skewed markers come out too square (angles
// -0.10..-0.28 deg), which makes them -0.14..-0.19 % small (at 62 deg -0.41..-0.59 deg, -0.24..-0.34 %):
// bounded at that measured shortfall plus a margin (0.25 %, 0.35 deg) as a regression guard; the target is
// 0.1 % and 0.1 deg.
TEST(DetectorRealData, RenderedBoardTruthIsSoundUpTo55Deg) {
  const RenderedBoardFigures f = MeasureRenderedBoard(30, 55, 24, 5);
  ASSERT_GE(f.markers, 250);
  EXPECT_LE(std::abs(f.truth_size_rel), 0.001);
  EXPECT_LE(std::abs(f.truth_skew_deg), 0.1);
  ASSERT_GE(f.found, 0.8 * f.markers);
  EXPECT_LE(std::abs(f.offset_px), 0.02);
  EXPECT_LE(std::abs(f.size_rel), 0.0025) << "(target 0.1 %, measured shortfall)";
  EXPECT_LE(std::abs(f.skew_deg), 0.35) << "(target 0.1 deg, measured shortfall)";
}

// The same board at 62 deg, markers 30 px head-on (their mean sides 20-25 px on the image): found. OpenCV's
// detectInvertedMarker saw a white-bordered marker only as the hole of the board's dark one-cell ring,
// whose contour breaks at steep views: 254 of the 290 markers the truth located were found (0.876, under
// the 0.90 for markers >= 20 px below 75 deg; stock OpenCV on the negated image 268 of all 300).
// Inverted prints are now searched as dark-bordered markers of the negated image: 284 of 290 (0.979).
TEST(DetectorRealData, RenderedBoardMarkersAreFoundAtSteepViews) {
  const RenderedBoardFigures f = MeasureRenderedBoard(30, 62, 30, 5);
  ASSERT_GE(f.markers, 250);
  EXPECT_GE(f.found, 0.95 * f.markers);
  EXPECT_LE(std::abs(f.offset_px), 0.02);
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
