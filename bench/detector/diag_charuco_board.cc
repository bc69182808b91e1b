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
// PairWidth); MCMT_BOARD_SAVE=PREFIX: each render as PREFIX<pose>.png.
// A quad's skew is the mean over its corners of |angle - 90| (deg); a skew error is the detected or
// predicted skew minus the true one.
#include <cstdio>
#include <cstdlib>
#include <opencv2/imgcodecs.hpp>

#include "tests/detector/accuracy.h"
#include "tests/detector/chessboard_truth.h"

using namespace mcmt;

namespace {

constexpr double kSquareM = 0.054;  // the board's squares

// A random pose of the board: centred in front of the camera at depth `z`, tilted by view_deg about an
// in-plane axis at a random angle, rolled at random. Returns K [r1 r2 t] (board metres -> pixels).
cv::Matx33d RandomBoardPose(const cv::Matx33d& K, double z, double view_deg, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> uni(0, 1);
  const double axis = 2 * M_PI * uni(rng), roll = 2 * M_PI * uni(rng);
  cv::Mat r_roll, r_tilt;
  cv::Rodrigues(cv::Mat(cv::Vec3d(0, 0, roll)), r_roll);
  cv::Rodrigues(cv::Mat(cv::Vec3d(std::cos(axis), std::sin(axis), 0) * (view_deg * M_PI / 180)), r_tilt);
  const cv::Matx33d R = cv::Matx33d(r_tilt) * cv::Matx33d(r_roll);
  const cv::Vec3d centre(2 * kSquareM, 2.5 * kSquareM, 0);  // the board's centre, board metres
  const cv::Vec3d t = cv::Vec3d(0.02 * (uni(rng) - 0.5), 0.02 * (uni(rng) - 0.5), z) - R * centre;
  return K * cv::Matx33d(R(0, 0), R(0, 1), t[0], R(1, 0), R(1, 1), t[1], R(2, 0), R(2, 1), t[2]);
}

// The board's quads in the image, in painting order: a dark frame 3 cm around the board, the squares
// (those with a marker dark), the markers (inverted: a white square, black cells where the dictionary's
// bit is 1).
std::vector<testing::reference::Quad> BoardQuads(const cv::aruco::CharucoBoard& board,
                                                 const cv::Matx33d& image_from_board,
                                                 const testing::Imaging& im) {
  auto at = [&](const cv::Point2d& p) { return testing::reference::Apply(image_from_board, p.x, p.y); };
  auto quad = [&](const cv::Point2d& a, const cv::Point2d& b, const cv::Point2d& c, const cv::Point2d& d,
                  double reflectance) {
    testing::reference::Quad q;
    q.p = {at(a), at(b), at(c), at(d)};
    q.level = reflectance * im.exposure;
    return q;
  };
  auto rect = [&](double x0, double y0, double x1, double y1, double reflectance) {
    return quad({x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}, reflectance);
  };
  std::vector<testing::reference::Quad> quads;
  quads.push_back(rect(-0.03, -0.03, 4 * kSquareM + 0.03, 5 * kSquareM + 0.03, im.ink));
  std::vector<bool> has_marker(20, false);
  for (const std::vector<cv::Point3f>& c : board.objPoints)
    has_marker[static_cast<int>(0.5 * (c[0].y + c[2].y) / kSquareM) * 4 +
               static_cast<int>(0.5 * (c[0].x + c[2].x) / kSquareM)] = true;
  for (int sy = 0; sy < 5; ++sy)
    for (int sx = 0; sx < 4; ++sx)
      quads.push_back(rect(sx * kSquareM, sy * kSquareM, (sx + 1) * kSquareM, (sy + 1) * kSquareM,
                           has_marker[sy * 4 + sx] ? im.ink : im.paper));
  for (size_t i = 0; i < board.ids.size(); ++i) {
    const std::vector<cv::Point3f>& c = board.objPoints[i];
    const cv::Mat bits = cv::aruco::Dictionary::getBitsFromByteList(
        board.dictionary->bytesList.rowRange(board.ids[i], board.ids[i] + 1), 4);
    auto cell = [&](double u, double v) {  // marker cell coordinates (0..6) -> board metres
      return cv::Point2d(c[0].x + (c[1].x - c[0].x) * u / 6 + (c[3].x - c[0].x) * v / 6,
                         c[0].y + (c[1].y - c[0].y) * u / 6 + (c[3].y - c[0].y) * v / 6);
    };
    auto cells = [&](double u0, double v0, double u1, double v1, double reflectance) {
      return quad(cell(u0, v0), cell(u1, v0), cell(u1, v1), cell(u0, v1), reflectance);
    };
    quads.push_back(cells(0, 0, 6, 6, im.paper));
    for (int r = 0; r < 4; ++r)
      for (int col = 0; col < 4; ++col)
        if (bits.at<uint8_t>(r, col)) quads.push_back(cells(col + 1, r + 1, col + 2, r + 2, im.ink));
  }
  return quads;
}

// Marker i's corners by `h` (board metres -> pixels).
template <typename H>
std::array<cv::Point2d, 4> MarkerCorners(const cv::aruco::CharucoBoard& board, size_t i, const H& h) {
  std::array<cv::Point2d, 4> out;
  for (int k = 0; k < 4; ++k) {
    const cv::Point3f& p = board.objPoints[i][k];
    const auto q = h(p.x, p.y);
    out[k] = {q[0], q[1]};
  }
  return out;
}

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
  const double focal = 900, width = 1280, height = 720;
  const cv::Matx33d K(focal, 0, width / 2, 0, focal, height / 2, 0, 0, 1);
  MarkerConfig mc;
  mc.dictionary = "DICT_4X4_1000", mc.inverted = true;
  DetectorOptions o;
  o.inverted = true, o.gamma = im.gamma;
  MarkerDetector detector(mc, o);
  std::mt19937_64 rng(5);
  double sum_truth = 0, sum_mcmt = 0, sum_mcmt_chess = 0, sum_xerr = 0;
  int n_truth = 0, n_mcmt = 0, n_x = 0;
  for (int pose = 0; pose < poses; ++pose) {
    // z: the depth at which a 4.05 cm marker is marker_px wide head-on
    const cv::Matx33d image_from_board = RandomBoardPose(K, focal * 0.0405 / marker_px, view_deg, rng);
    auto truth = [&](double x, double y) {
      const cv::Point2d p = testing::reference::Apply(image_from_board, x, y);
      return cv::Vec2d(p.x, p.y);
    };
    cv::Mat linear(static_cast<int>(height), static_cast<int>(width), CV_64F, cv::Scalar(0.3 * im.exposure));
    testing::reference::Paint(BoardQuads(*board, image_from_board, im),
                              cv::Rect(0, 0, linear.cols, linear.rows), image_from_board.inv(), &linear);
    const cv::Mat image = testing::reference::CameraPipeline(linear, im, rng);
    if (save) cv::imwrite(std::string(save) + std::to_string(pose) + ".png", image);
    // The truth's way: X-corners, a homography through them, each marker's predicted perimeter.
    const testing::CharucoDetection d = testing::DetectCharuco(image, board, cv::Mat(K), cv::Mat());
    if (d.corners.size() < 6) {
      std::printf("pose %2d: %zu X-corners\n", pose, d.corners.size());
      continue;
    }
    std::vector<cv::Point2d> plane, found;
    double xerr = 0;
    for (size_t i = 0; i < d.corners.size(); ++i) {
      const cv::Point3f p = board->chessboardCorners[d.corner_ids[i]];
      plane.emplace_back(p.x, p.y), found.emplace_back(d.corners[i].x, d.corners[i].y);
      xerr += cv::norm(cv::Vec2d(found.back().x, found.back().y) - truth(p.x, p.y)) / d.corners.size();
    }
    const testing::BoardHomography chess_h(plane, found);
    auto chess = [&](double x, double y) {
      const Eigen::Vector2d p = chess_h(x, y);
      return cv::Vec2d(p.x(), p.y());
    };
    double pose_truth = 0, pose_mcmt = 0, pose_mcmt_chess = 0;
    int pn = 0, pm = 0;
    for (size_t i = 0; i < board->ids.size(); ++i) {
      const std::array<cv::Point2d, 4> want_q = MarkerCorners(*board, i, chess),
                                       real_q = MarkerCorners(*board, i, truth);
      const double want = testing::QuadPerimeter(want_q), real = testing::QuadPerimeter(real_q);
      pose_truth += 100 * (want / real - 1), ++pn;
      if (per_marker)
        std::fprintf(stderr, "truth,%d,%d,%.3f,%.4f,%.4f\n", pose, board->ids[i], real / 4,
                     100 * (want / real - 1), testing::QuadSkewDeg(want_q) - testing::QuadSkewDeg(real_q));
    }
    for (const marker_t& m : detector.Detect(image))
      for (size_t i = 0; i < board->ids.size(); ++i) {
        if (board->ids[i] != m.id) continue;
        std::array<cv::Point2d, 4> got;
        for (int k = 0; k < 4; ++k) got[k] = {m.corners[k][0], m.corners[k][1]};
        const std::array<cv::Point2d, 4> want_q = MarkerCorners(*board, i, chess),
                                         real_q = MarkerCorners(*board, i, truth);
        const double want = testing::QuadPerimeter(want_q), real = testing::QuadPerimeter(real_q),
                     perimeter = testing::QuadPerimeter(got);
        pose_mcmt += 100 * (perimeter / real - 1);
        if (per_marker) {
          std::fprintf(stderr, "mcmt,%d,%d,%.3f,%.4f,%.4f,%.4f,%.4f", pose, m.id, real / 4,
                       100 * (perimeter / real - 1), testing::QuadSkewDeg(got) - testing::QuadSkewDeg(real_q),
                       100 * (perimeter / want - 1),
                       testing::QuadSkewDeg(got) - testing::QuadSkewDeg(want_q));
          for (int p = 0; p < 2; ++p)
            std::fprintf(stderr, ",%.4f,%.5f,%.5f", PairWidth(real_q, p) / 6,
                         0.5 * (PairWidth(got, p) - PairWidth(real_q, p)),
                         0.5 * (PairWidth(want_q, p) - PairWidth(real_q, p)));
          std::fprintf(stderr, "\n");
        }
        pose_mcmt_chess += 100 * (perimeter / want - 1), ++pm;
      }
    std::printf(
        "pose %2d: %2zu X-corners (mean error %.3f px), chessboard truth's size error %+.3f %%; mcmt %2d "
        "markers %+.3f %% against the truth, %+.3f %% against the chessboard\n",
        pose, d.corners.size(), xerr, pose_truth / pn, pm, pm ? pose_mcmt / pm : 0,
        pm ? pose_mcmt_chess / pm : 0);
    sum_truth += pose_truth, n_truth += pn, sum_mcmt += pose_mcmt, sum_mcmt_chess += pose_mcmt_chess;
    n_mcmt += pm, sum_xerr += xerr, ++n_x;
  }
  std::printf(
      "mean: X-corner error %.3f px; chessboard truth's size error %+.3f %% (%d markers); mcmt %+.3f %% "
      "against the truth, %+.3f %% against the chessboard (%d markers)\n",
      n_x ? sum_xerr / n_x : 0, sum_truth / std::max(n_truth, 1), n_truth, sum_mcmt / std::max(n_mcmt, 1),
      sum_mcmt_chess / std::max(n_mcmt, 1), n_mcmt);
  return 0;
}
