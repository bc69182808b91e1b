// Is the caliscope board's chessboard truth (tests/detector/chessboard_truth.h) itself biased at steep
// views? The whole board (4 x 5 squares of 5.4 cm, inverted 4.05 cm DICT_4X4_1000 markers, on a dark
// frame) rendered by the reference renderer at known poses; its X-corners found as the truth finds them
// (DetectCharuco: ArUco markers, ChArUco interpolation, cornerSubPix), a homography fitted to them, and
// the markers' sizes it predicts compared with the true ones. Also mcmt's markers against the truth and
// against that prediction.
//   diag_charuco_board [poses (20)] [view deg (60)] [marker px head-on (25)] [blur px (0.7)] [gamma (1.85)]
// One line per pose, then means. MCMT_BOARD_MARKERS=1: one CSV line per marker on stderr (truth|mcmt, pose,
// id, true mean side px, size error %, skew error deg; mcmt lines then the size error % and skew error
// deg against the chessboard's prediction, then per pair of opposite sides p = 0, 1 (sides p and p + 2)
// its true cell depth px and the half width errors px of mcmt and of the chessboard's prediction, see
// PairWidth; "missed" lines: markers mcmt did not find, with whether stock
// OpenCV found them); MCMT_BOARD_SAVE=PREFIX: each render as PREFIX<pose>.png; MCMT_BOARD_REFINEMENT:
// mcmt's corner_refinement (default edges).
// A quad's skew is the mean over its corners of |angle - 90| (deg); a skew error is the detected or
// predicted skew minus the true one.
#include <cstdio>
#include <cstdlib>
#include <opencv2/imgcodecs.hpp>

#include "tests/detector/charuco_render.h"

using namespace mcmt;

namespace {

// The width of a quad across its pair of opposite sides p and p + 2: the mean distance of corners p + 2
// and p + 3 from the line through corners p and p + 1. Half its error is that pair's mean outward offset.
double PairWidth(const std::array<cv::Point2d, 4>& q, int p) {
  const cv::Point2d a = q[p], d = q[(p + 1) % 4] - a;
  double sum = 0;
  for (int k : {(p + 2) % 4, (p + 3) % 4}) sum += 0.5 * std::abs(d.cross(q[k] - a)) / cv::norm(d);
  return sum;
}

}  // namespace

int main(int argc, char** argv) {
  const int poses = argc > 1 ? std::atoi(argv[1]) : 20;
  const double view_deg = argc > 2 ? std::atof(argv[2]) : 60;
  const double marker_px = argc > 3 ? std::atof(argv[3]) : 25;
  testing::Imaging im;
  im.blur_sigma = argc > 4 ? std::atof(argv[4]) : 0.7;
  im.gamma = argc > 5 ? std::atof(argv[5]) : 1.85;
  const bool per_marker = std::getenv("MCMT_BOARD_MARKERS") != nullptr;
  const char* save = std::getenv("MCMT_BOARD_SAVE");
  const auto board = testing::CaliscopeCharucoBoard();
  MarkerConfig mc;
  mc.dictionary = "DICT_4X4_1000", mc.inverted = true;
  DetectorOptions o;
  o.inverted = true, o.gamma = im.gamma;
  if (const char* r = std::getenv("MCMT_BOARD_REFINEMENT")) o.corner_refinement = r;
  MarkerDetector detector(mc, o);
  std::mt19937_64 rng(5);
  double sum_truth = 0, sum_mcmt = 0, sum_mcmt_chess = 0, sum_xerr = 0;
  int n_truth = 0, n_mcmt = 0, n_x = 0;
  for (int pose = 0; pose < poses; ++pose) {
    cv::Mat image;
    const testing::RenderedBoardPose r =
        testing::RenderBoardPose(board, view_deg, marker_px, im, detector, rng, save ? &image : nullptr);
    if (save) cv::imwrite(std::string(save) + std::to_string(pose) + ".png", image);
    if (r.markers.empty()) {
      std::printf("pose %2d: %zu X-corners\n", pose, r.x_corners);
      continue;
    }
    double pose_truth = 0, pose_mcmt = 0, pose_mcmt_chess = 0;
    int pn = 0, pm = 0;
    for (const testing::RenderedBoardMarker& m : r.markers) {
      const double want = testing::QuadPerimeter(m.chess), real = testing::QuadPerimeter(m.real);
      pose_truth += 100 * (want / real - 1), ++pn;
      if (per_marker)
        std::fprintf(stderr, "truth,%d,%d,%.3f,%.4f,%.4f\n", pose, m.id, real / 4, 100 * (want / real - 1),
                     testing::QuadSkewDeg(m.chess) - testing::QuadSkewDeg(m.real));
    }
    for (const testing::RenderedBoardMarker& m : r.markers) {
      if (!m.found) {
        if (per_marker)
          std::fprintf(stderr, "missed,%d,%d,%.3f,%d\n", pose, m.id, testing::QuadPerimeter(m.real) / 4,
                       m.stock_found ? 1 : 0);
        continue;
      }
      const double want = testing::QuadPerimeter(m.chess), real = testing::QuadPerimeter(m.real),
                   perimeter = testing::QuadPerimeter(m.got);
      pose_mcmt += 100 * (perimeter / real - 1);
      if (per_marker) {
        std::fprintf(stderr, "mcmt,%d,%d,%.3f,%.4f,%.4f,%.4f,%.4f", pose, m.id, real / 4,
                     100 * (perimeter / real - 1), testing::QuadSkewDeg(m.got) - testing::QuadSkewDeg(m.real),
                     100 * (perimeter / want - 1),
                     testing::QuadSkewDeg(m.got) - testing::QuadSkewDeg(m.chess));
        for (int p = 0; p < 2; ++p)
          std::fprintf(stderr, ",%.4f,%.5f,%.5f", PairWidth(m.real, p) / 6,
                       0.5 * (PairWidth(m.got, p) - PairWidth(m.real, p)),
                       0.5 * (PairWidth(m.chess, p) - PairWidth(m.real, p)));
        std::fprintf(stderr, "\n");
      }
      pose_mcmt_chess += 100 * (perimeter / want - 1), ++pm;
    }
    std::printf(
        "pose %2d: %2zu X-corners (mean error %.3f px), chessboard truth's size error %+.3f %%; mcmt %2d "
        "markers %+.3f %% against the truth, %+.3f %% against the chessboard\n",
        pose, r.x_corners, r.x_corner_error_px, pose_truth / pn, pm, pm ? pose_mcmt / pm : 0,
        pm ? pose_mcmt_chess / pm : 0);
    sum_truth += pose_truth, n_truth += pn, sum_mcmt += pose_mcmt, sum_mcmt_chess += pose_mcmt_chess;
    n_mcmt += pm, sum_xerr += r.x_corner_error_px, ++n_x;
  }
  std::printf(
      "mean: X-corner error %.3f px; chessboard truth's size error %+.3f %% (%d markers); mcmt %+.3f %% "
      "against the truth, %+.3f %% against the chessboard (%d markers)\n",
      n_x ? sum_xerr / n_x : 0, sum_truth / std::max(n_truth, 1), n_truth, sum_mcmt / std::max(n_mcmt, 1),
      sum_mcmt_chess / std::max(n_mcmt, 1), n_mcmt);
  return 0;
}
