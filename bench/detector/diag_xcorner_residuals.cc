// The caliscope board's chessboard truth (tests/detector/chessboard_truth.h) against its own X-corners:
// per X-corner, the mean and rms over frames of the detected corner minus the frame's homography
// prediction (raw px). A board that is not flat, or a lens model that is wrong, leaves a pattern in the
// means that the frames share; noise averages out (issue 15, bench/results/2026-12-06-cam1width.md).
//   diag_xcorner_residuals RIG_YAML CAMERA
#include <cstdio>
#include <map>

#include "tests/detector/chessboard_truth.h"

using namespace mcmt;

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: diag_xcorner_residuals RIG_YAML CAMERA\n");
    return 2;
  }
  const RigConfig rig = LoadRigConfig(argv[1]);
  const std::string camera = argv[2];
  const auto board = testing::CaliscopeCharucoBoard();
  cv::Mat K, dist;
  for (const CameraConfig& c : rig.cameras)
    if (c.name == camera) {
      const CameraModel& m = c.model;
      K = (cv::Mat_<double>(3, 3) << m.fx, 0, m.cx, 0, m.fy, m.cy, 0, 0, 1);
      dist = cv::Mat(m.distortion, true);
    }
  std::map<int, Eigen::Vector2d> sum;
  std::map<int, double> sum_sq;
  std::map<int, int> n;
  double rms_sum = 0;
  int frames = 0;
  testing::CompareWithChessboard(
      rig, -1, camera,
      [&](const std::string&, const cv::Mat& gray,
          const std::function<Eigen::Vector2d(double, double)>& raw_from_board) {
        const testing::CharucoDetection d = testing::DetectCharuco(gray, board, K, dist);
        double sq = 0;
        for (size_t i = 0; i < d.corners.size(); ++i) {
          const int id = d.corner_ids[i];
          const cv::Point3f p = board->chessboardCorners[id];
          const Eigen::Vector2d r =
              Eigen::Vector2d(d.corners[i].x, d.corners[i].y) - raw_from_board(p.x, p.y);
          sum.emplace(id, Eigen::Vector2d::Zero());
          sum[id] += r, sum_sq[id] += r.squaredNorm(), ++n[id], sq += r.squaredNorm();
        }
        rms_sum += std::sqrt(sq / std::max<size_t>(1, d.corners.size())), ++frames;
      });
  std::printf("%s: %d frames, mean rms %.3f px\n", camera.c_str(), frames, rms_sum / std::max(frames, 1));
  for (const auto& [id, s] : sum) {
    const cv::Point3f p = board->chessboardCorners[id];
    std::printf("X-corner %2d at (%.3f, %.3f) m: %3d frames, mean residual %+.3f %+.3f px, rms %.3f px\n", id,
                p.x, p.y, n[id], s.x() / n[id], s.y() / n[id], std::sqrt(sum_sq[id] / n[id]));
  }
  return 0;
}
