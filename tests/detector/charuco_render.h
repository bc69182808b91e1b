// The caliscope ChArUco board (tests/detector/chessboard_truth.h) rendered whole by the reference renderer
// at known poses: the board's true marker corners beside the chessboard truth's prediction (the real-data
// tests' truth, found on the render as on the real frames) and mcmt's corners. Judges the chessboard
// truth itself, and mcmt's sizes and angles on that board's geometry, against corners known exactly.
#pragma once

#include <array>
#include <random>
#include <vector>

#include "tests/detector/accuracy.h"
#include "tests/detector/chessboard_truth.h"

namespace mcmt::testing {

constexpr double kCaliscopeSquareM = 0.054;  // the board's squares

// A random pose of the board: centred in front of the camera at depth `z`, tilted by view_deg about an
// in-plane axis at a random angle, rolled at random. Returns K [r1 r2 t] (board metres -> pixels).
inline cv::Matx33d RandomBoardPose(const cv::Matx33d& K, double z, double view_deg, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> uni(0, 1);
  const double axis = 2 * M_PI * uni(rng), roll = 2 * M_PI * uni(rng);
  cv::Mat r_roll, r_tilt;
  cv::Rodrigues(cv::Mat(cv::Vec3d(0, 0, roll)), r_roll);
  cv::Rodrigues(cv::Mat(cv::Vec3d(std::cos(axis), std::sin(axis), 0) * (view_deg * M_PI / 180)), r_tilt);
  const cv::Matx33d R = cv::Matx33d(r_tilt) * cv::Matx33d(r_roll);
  const cv::Vec3d centre(2 * kCaliscopeSquareM, 2.5 * kCaliscopeSquareM, 0);  // board metres
  const cv::Vec3d t = cv::Vec3d(0.02 * (uni(rng) - 0.5), 0.02 * (uni(rng) - 0.5), z) - R * centre;
  return K * cv::Matx33d(R(0, 0), R(0, 1), t[0], R(1, 0), R(1, 1), t[1], R(2, 0), R(2, 1), t[2]);
}

// The board's quads in the image, in painting order: a dark frame 3 cm around the board, the squares
// (those with a marker dark), the markers (inverted: a white square, black cells where the dictionary's
// bit is 1).
inline std::vector<reference::Quad> BoardQuads(const cv::aruco::CharucoBoard& board,
                                               const cv::Matx33d& image_from_board, const Imaging& im) {
  const double s = kCaliscopeSquareM;
  auto at = [&](const cv::Point2d& p) { return reference::Apply(image_from_board, p.x, p.y); };
  auto quad = [&](const cv::Point2d& a, const cv::Point2d& b, const cv::Point2d& c, const cv::Point2d& d,
                  double reflectance) {
    reference::Quad q;
    q.p = {at(a), at(b), at(c), at(d)};
    q.level = reflectance * im.exposure;
    return q;
  };
  auto rect = [&](double x0, double y0, double x1, double y1, double reflectance) {
    return quad({x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}, reflectance);
  };
  std::vector<reference::Quad> quads;
  quads.push_back(rect(-0.03, -0.03, 4 * s + 0.03, 5 * s + 0.03, im.ink));
  std::vector<bool> has_marker(20, false);
  for (const std::vector<cv::Point3f>& c : board.objPoints)
    has_marker[static_cast<int>(0.5 * (c[0].y + c[2].y) / s) * 4 +
               static_cast<int>(0.5 * (c[0].x + c[2].x) / s)] = true;
  for (int sy = 0; sy < 5; ++sy)
    for (int sx = 0; sx < 4; ++sx)
      quads.push_back(
          rect(sx * s, sy * s, (sx + 1) * s, (sy + 1) * s, has_marker[sy * 4 + sx] ? im.ink : im.paper));
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

// One board marker in one rendered pose: its true corners, the chessboard truth's prediction, and mcmt's
// corners where mcmt found it (ArUco order, px).
struct RenderedBoardMarker {
  int id = 0;
  std::array<cv::Point2d, 4> real{}, chess{}, got{};
  bool found = false;        // by mcmt
  bool stock_found = false;  // by stock OpenCV (the truth's detectMarkers)
};

// One rendered pose: how many X-corners the truth found and their mean distance from the true ones (px),
// and the board's markers (none when the truth found fewer than 6 X-corners).
struct RenderedBoardPose {
  size_t x_corners = 0;
  double x_corner_error_px = 0;
  std::vector<RenderedBoardMarker> markers;
};

// Renders the caliscope board at a random pose (RandomBoardPose, depth such that a marker is
// `marker_px` wide head-on, 1280x720, focal 900 px) under `im`, finds its X-corners as the chessboard
// truth does (DetectCharuco, homography through them) and runs `detector` on the image. `image` (optional)
// receives the render.
inline RenderedBoardPose RenderBoardPose(const cv::Ptr<cv::aruco::CharucoBoard>& board_ptr, double view_deg,
                                         double marker_px, const Imaging& im, MarkerDetector& detector,
                                         std::mt19937_64& rng, cv::Mat* image = nullptr) {
  const cv::aruco::CharucoBoard& board = *board_ptr;
  const double focal = 900, width = 1280, height = 720;
  const cv::Matx33d K(focal, 0, width / 2, 0, focal, height / 2, 0, 0, 1);
  const cv::Matx33d image_from_board = RandomBoardPose(K, focal * 0.0405 / marker_px, view_deg, rng);
  cv::Mat linear(static_cast<int>(height), static_cast<int>(width), CV_64F, cv::Scalar(0.3 * im.exposure));
  reference::Paint(BoardQuads(board, image_from_board, im), cv::Rect(0, 0, linear.cols, linear.rows),
                   image_from_board.inv(), &linear);
  const cv::Mat gray = reference::CameraPipeline(linear, im, rng);
  if (image) *image = gray;
  auto truth = [&](double x, double y) { return reference::Apply(image_from_board, x, y); };
  RenderedBoardPose out;
  const CharucoDetection d = DetectCharuco(gray, board_ptr, cv::Mat(K), cv::Mat());
  out.x_corners = d.corners.size();
  if (d.corners.size() < 6) return out;
  std::vector<cv::Point2d> plane, found;
  for (size_t i = 0; i < d.corners.size(); ++i) {
    const cv::Point3f p = board.chessboardCorners[d.corner_ids[i]];
    plane.emplace_back(p.x, p.y), found.emplace_back(d.corners[i].x, d.corners[i].y);
    out.x_corner_error_px += cv::norm(found.back() - truth(p.x, p.y)) / d.corners.size();
  }
  const BoardHomography chess_h(plane, found);
  for (size_t i = 0; i < board.ids.size(); ++i) {
    RenderedBoardMarker m;
    m.id = board.ids[i];
    m.stock_found = std::find(d.marker_ids.begin(), d.marker_ids.end(), m.id) != d.marker_ids.end();
    for (int k = 0; k < 4; ++k) {
      const cv::Point3f& p = board.objPoints[i][k];
      const Eigen::Vector2d c = chess_h(p.x, p.y);
      m.real[k] = truth(p.x, p.y), m.chess[k] = {c.x(), c.y()};
    }
    out.markers.push_back(m);
  }
  for (const marker_t& got : detector.Detect(gray))
    for (RenderedBoardMarker& m : out.markers)
      if (m.id == got.id) {
        for (int k = 0; k < 4; ++k) m.got[k] = {got.corners[k][0], got.corners[k][1]};
        m.found = true;
      }
  return out;
}

}  // namespace mcmt::testing
