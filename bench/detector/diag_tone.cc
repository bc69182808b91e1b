// The caliscope board's edge profiles, to tell a camera's tone curve from its sharpening: profiles
// across the chessboard's edges between a solid square and a marker's square (white square | one cell of
// black margin | the marker's white border | code), located by the chessboard's homography
// (tests/detector/chessboard_truth.h), averaged per band of cell size (px). u in cells from the square's
// edge, positive into the solid square; the marker's outer edge is at u = -1. With `orientation`, the
// columns are the edges running closer to the image's x axis (profiles along y) and those closer to its
// y axis (profiles along x), cells of 3-9 px: webcams can sharpen rows and columns differently.
//   diag_tone RIG_YAML [max frames per camera (all)] [camera] [orientation]
#include <cstdio>
#include <cstdlib>
#include <set>
#include <string>

#include "tests/detector/chessboard_truth.h"

using namespace mcmt;

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: diag_tone RIG_YAML [max frames per camera] [camera] [orientation]\n");
    return 2;
  }
  const RigConfig rig = LoadRigConfig(argv[1]);
  const auto board = testing::CaliscopeCharucoBoard();
  const double sq = 0.054, cell = 0.0405 / 6;
  // Squares holding a marker (from the markers' centres).
  std::set<std::pair<int, int>> marked;
  for (const auto& obj : board->objPoints) {
    cv::Point3f c(0, 0, 0);
    for (const auto& p : obj) c += 0.25 * p;
    marked.insert({static_cast<int>(c.x / sq), static_cast<int>(c.y / sq)});
  }
  constexpr int kBands = 5, kSteps = 37;  // u = -2.5 .. +2 cells by 1/8
  const bool by_orientation = argc > 4 && std::string(argv[4]) == "orientation";
  const double band_lo = 3.0, band_step = 1.5;
  std::vector<std::vector<double>> sum(kBands, std::vector<double>(kSteps, 0.0)), n = sum;
  int calls = 0;
  auto hook = [&](const std::string&, const cv::Mat& gray,
                  const std::function<Eigen::Vector2d(double, double)>& raw_from_board) {
    ++calls;
    auto sample = [&](const Eigen::Vector2d& p, double* v) {
      const int x = static_cast<int>(std::floor(p.x())), y = static_cast<int>(std::floor(p.y()));
      if (x < 0 || y < 0 || x + 1 >= gray.cols || y + 1 >= gray.rows) return false;
      const double fx = p.x() - x, fy = p.y() - y;
      *v = (1 - fy) * ((1 - fx) * gray.at<uint8_t>(y, x) + fx * gray.at<uint8_t>(y, x + 1)) +
           fy * ((1 - fx) * gray.at<uint8_t>(y + 1, x) + fx * gray.at<uint8_t>(y + 1, x + 1));
      return true;
    };
    for (int sx = 0; sx < 4; ++sx)
      for (int sy = 0; sy < 5; ++sy) {
        if (!marked.count({sx, sy})) continue;
        const int dx[4] = {1, -1, 0, 0}, dy[4] = {0, 0, 1, -1};
        for (int k = 0; k < 4; ++k) {
          const int nx = sx + dx[k], ny = sy + dy[k];
          if (nx < 0 || ny < 0 || nx >= 4 || ny >= 5 || marked.count({nx, ny})) continue;
          // The shared edge: its middle half (away from the chessboard corners).
          const double cx = (sx + 0.5) * sq + dx[k] * 0.5 * sq, cy = (sy + 0.5) * sq + dy[k] * 0.5 * sq;
          for (int t = -8; t <= 8; ++t) {
            const double along = t / 16.0 * 0.5 * sq;
            const double px = cx + (dx[k] == 0 ? along : 0), py = cy + (dy[k] == 0 ? along : 0);
            const Eigen::Vector2d a = raw_from_board(px, py);
            const Eigen::Vector2d b = raw_from_board(px + dx[k] * cell, py + dy[k] * cell);
            const double cell_px = (b - a).norm();
            int band = static_cast<int>((cell_px - band_lo) / band_step);
            if (by_orientation)  // 0: the edge runs along x (its profile along y)
              band = band < 0 || band >= 4 ? -1 : std::abs((b - a).x()) < std::abs((b - a).y()) ? 0 : 1;
            if (band < 0 || band >= kBands) continue;
            for (int j = 0; j < kSteps; ++j) {
              const double u = (-2.5 + j / 8.0) * cell;
              double v;
              if (!sample(raw_from_board(px + dx[k] * u, py + dy[k] * u), &v)) continue;
              sum[band][j] += v, n[band][j] += 1;
            }
          }
        }
      }
  };
  testing::CompareWithChessboard(rig, argc > 2 ? std::atoi(argv[2]) : -1, argc > 3 ? argv[3] : "", hook);
  std::printf("u/cell");
  for (int b = 0; b < kBands; ++b)
    if (by_orientation)
      std::printf("  %9s", b == 0 ? "edge-x" : b == 1 ? "edge-y" : "-");
    else
      std::printf("  %4.1f-%4.1f", band_lo + b * band_step, band_lo + (b + 1) * band_step);
  std::printf("\n");
  for (int j = 0; j < kSteps; ++j) {
    std::printf("%+6.3f", -2.5 + j / 8.0);
    for (int b = 0; b < kBands; ++b) std::printf("  %9.1f", n[b][j] > 0 ? sum[b][j] / n[b][j] : NAN);
    std::printf("\n");
  }
  std::printf("frames %d\n", calls);
  std::printf("profiles");
  for (int b = 0; b < kBands; ++b) std::printf("  %9.0f", n[b][0]);
  std::printf("\n");
  return 0;
}
