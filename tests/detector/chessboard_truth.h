// The caliscope board's ChArUco chessboard corners as an independent truth for its markers' corners.
// OpenCV locates the chessboard corners by their saddle points (cornerSubPix on the inverted image),
// which neither the print's margins nor the camera's transfer curve move. Per frame a homography from
// the board's plane to the undistorted image, fitted to them, predicts every marker's corners from the
// board's geometry (4 x 5 squares of 5.4 cm, 4.05 cm markers, DICT_4X4_1000). Used by
// test_detector_realdata and bench/detector/diag_charuco.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <opencv2/aruco/charuco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/files.h"
#include "detector/detector.h"
#include "detector/source.h"

namespace mcmt::testing {

// One marker detection against the chessboard's prediction.
struct ChessboardMarker {
  std::string camera;
  int id = 0;
  int frame = 0;
  double side_px = 0;    // predicted mean side, px
  double offset_px = 0;  // mean signed offset of the four sides along their outward normals, px
  double size_rel = 0;   // detected perimeter / predicted perimeter - 1
  // Per side (ArUco order: side s from corner s to s + 1): outward offset, px, and whether the side runs
  // closer to the image's x axis than to its y axis.
  std::array<double, 4> side_offset_px{};
  std::array<bool, 4> side_horizontal{};
  double x_px = 0, y_px = 0;  // predicted centre, raw pixels
  double view_deg = 0;        // angle between the board's normal and the camera's axis
  double white = 0;           // 95th percentile of the grey levels around the marker (its brightness)
  // size_rel against other predictions: a homography from the X-corners within 9 cm of the marker's
  // centre only (NaN below 4 of them or when they are collinear), and a homography in raw pixels
  // (no lens distortion model, raw corners compared).
  double size_rel_local = std::numeric_limits<double>::quiet_NaN();
  double size_rel_raw = 0;
  // size_rel against a homography fitted to the centres (diagonal crossings) of the frame's markers as
  // mcmt found them, and as stock OpenCV found them: the board's marker spacing, no chessboard corner
  // involved (NaN below 5 markers).
  double size_rel_centres = std::numeric_limits<double>::quiet_NaN();
  double size_rel_stock_centres = std::numeric_limits<double>::quiet_NaN();
  // Per side, the outward offset against the stock-centres homography's prediction (NaN: none).
  std::array<double, 4> side_offset_stock_px{NAN, NAN, NAN, NAN};
  std::array<Eigen::Vector2d, 4> got_ideal{}, want_ideal{};  // detected and predicted corners, ideal px
};

// Means over the markers `take` selects (NaN fields skipped per field).
struct ChessboardMean {
  int n = 0;
  double offset_px = 0, size_rel = 0, size_rel_local = 0, size_rel_raw = 0;
  int n_local = 0;
  double horizontal_px = 0, vertical_px = 0;  // mean outward offset of the horizontal / vertical sides
};

inline ChessboardMean MeanOf(const std::vector<ChessboardMarker>& markers,
                             const std::function<bool(const ChessboardMarker&)>& take) {
  ChessboardMean out;
  int n_h = 0, n_v = 0;
  for (const ChessboardMarker& m : markers) {
    if (!take(m)) continue;
    ++out.n, out.offset_px += m.offset_px, out.size_rel += m.size_rel, out.size_rel_raw += m.size_rel_raw;
    if (!std::isnan(m.size_rel_local)) out.size_rel_local += m.size_rel_local, ++out.n_local;
    for (int s = 0; s < 4; ++s) {
      (m.side_horizontal[s] ? out.horizontal_px : out.vertical_px) += m.side_offset_px[s];
      ++(m.side_horizontal[s] ? n_h : n_v);
    }
  }
  if (out.n) out.offset_px /= out.n, out.size_rel /= out.n, out.size_rel_raw /= out.n;
  if (out.n_local) out.size_rel_local /= out.n_local;
  if (n_h) out.horizontal_px /= n_h;
  if (n_v) out.vertical_px /= n_v;
  return out;
}

// The markers of camera `camera` (all cameras: "").
inline ChessboardMean CameraMean(const std::vector<ChessboardMarker>& markers, const std::string& camera) {
  return MeanOf(markers, [&](const ChessboardMarker& m) { return camera.empty() || m.camera == camera; });
}

struct ChessboardComparison {
  std::vector<ChessboardMarker> mcmt, stock;  // mcmt's detections (DetectRecording), stock OpenCV's
  double homography_rms_px = 0;               // mean over the frames used
  int frames = 0;                             // frames with a homography (rms <= 0.5 px)
  // Every frame's detections as DetectRecording gives them, and the same with each marker's corners
  // replaced by the chessboard's prediction (markers without one dropped, frames without any dropped).
  std::vector<detections_t> detected, predicted;
};

// The four sides' mean outward offset of `got` from `want` (corners in ArUco order) and the
// perimeter ratio - 1.
inline void SideOffsets(const std::array<Eigen::Vector2d, 4>& got, const std::array<Eigen::Vector2d, 4>& want,
                        ChessboardMarker* out) {
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  for (const auto& p : want) centre += p / 4;
  double got_len = 0, want_len = 0, offset = 0;
  for (int s = 0; s < 4; ++s) {
    const Eigen::Vector2d a = want[s], b = want[(s + 1) % 4];
    Eigen::Vector2d n((b - a).y(), -(b - a).x());
    n.normalize();
    if (n.dot(0.5 * (a + b) - centre) < 0) n = -n;
    out->side_offset_px[s] = 0.5 * (n.dot(got[s] - a) + n.dot(got[(s + 1) % 4] - b));
    out->side_horizontal[s] = std::abs((b - a).x()) > std::abs((b - a).y());
    offset += 0.25 * out->side_offset_px[s];
    got_len += (got[(s + 1) % 4] - got[s]).norm(), want_len += (b - a).norm();
  }
  out->side_px = want_len / 4, out->offset_px = offset, out->size_rel = got_len / want_len - 1.0;
}

// A frame with its board-to-image mapping: the raw image pixel of the board's point (x, y), m.
using ChessboardFrameHook =
    std::function<void(const std::string& camera, const cv::Mat& gray,
                       const std::function<Eigen::Vector2d(double, double)>& raw_from_board)>;

// A plane-to-image homography fitted to point pairs (empty: `ok` false).
struct BoardHomography {
  cv::Matx33d image_from_board;
  bool ok = false;
  BoardHomography(const std::vector<cv::Point2d>& plane, const std::vector<cv::Point2d>& image) {
    const cv::Mat H = plane.size() >= 4 ? cv::findHomography(plane, image, 0) : cv::Mat();
    ok = !H.empty();
    if (ok) image_from_board = cv::Matx33d(H);
  }
  Eigen::Vector2d operator()(double x, double y) const {
    const cv::Vec3d v = image_from_board * cv::Vec3d(x, y, 1);
    return Eigen::Vector2d(v[0] / v[2], v[1] / v[2]);
  }
  double Rms(const std::vector<cv::Point2d>& plane, const std::vector<cv::Point2d>& image) const {
    double sum = 0;
    for (size_t i = 0; i < plane.size(); ++i)
      sum += ((*this)(plane[i].x, plane[i].y) - Eigen::Vector2d(image[i].x, image[i].y)).squaredNorm();
    return std::sqrt(sum / std::max<size_t>(1, plane.size()));
  }
  // The angle (deg) between the board's normal and the optical axis, from undistorted pixels (K).
  double ViewDeg(const CameraModel& m) const {
    Eigen::Vector3d col[2];
    for (int c = 0; c < 2; ++c) {
      const cv::Vec3d h(image_from_board(0, c), image_from_board(1, c), image_from_board(2, c));
      col[c] = Eigen::Vector3d((h[0] - m.cx * h[2]) / m.fx, (h[1] - m.cy * h[2]) / m.fy, h[2]).normalized();
    }
    return std::acos(std::min(1.0, std::abs(col[0].cross(col[1]).normalized().z()))) * 180.0 / M_PI;
  }
};

// The homography of the point pairs whose plane point lies within `radius` (m) of `centre`, if there are
// at least 4 of them and they are not collinear.
inline BoardHomography LocalHomography(const std::vector<cv::Point2d>& plane,
                                       const std::vector<cv::Point2d>& image, const cv::Point2d& centre,
                                       double radius) {
  std::vector<cv::Point2d> p, q;
  for (size_t i = 0; i < plane.size(); ++i)
    if (cv::norm(plane[i] - centre) <= radius) p.push_back(plane[i]), q.push_back(image[i]);
  Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
  for (const cv::Point2d& a : p)
    for (const cv::Point2d& b : p) {
      const Eigen::Vector2d d(a.x - b.x, a.y - b.y);
      scatter += d * d.transpose();
    }
  const double n2 = static_cast<double>(p.size() * p.size());
  if (p.size() < 4 || scatter.determinant() < 1e-9 * n2 * n2) p.clear();  // collinear: det 0
  return BoardHomography(p, q);
}

// The 95th percentile of the grey levels in the bounding box of `quad` (raw pixels).
inline double WhiteLevel(const cv::Mat& gray, const std::array<Eigen::Vector2d, 4>& quad) {
  std::vector<cv::Point> pts;
  for (const auto& q : quad) pts.emplace_back(static_cast<int>(q.x()), static_cast<int>(q.y()));
  const cv::Rect box = cv::boundingRect(pts) & cv::Rect(0, 0, gray.cols, gray.rows);
  std::vector<uint8_t> v;
  for (int r = box.y; r < box.y + box.height; ++r)
    for (int c = box.x; c < box.x + box.width; ++c) v.push_back(gray.at<uint8_t>(r, c));
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + v.size() * 95 / 100, v.end());
  return v[v.size() * 95 / 100];
}

// One frame's chessboard corners (board plane, m; ideal and raw pixels), or none.
struct ChessboardCorners {
  std::vector<cv::Point2d> plane, ideal, raw;
};

// The caliscope recordings' ChArUco board: 4 x 5 squares of 5.4 cm, markers of 4.05 cm, DICT_4X4_1000.
inline cv::Ptr<cv::aruco::CharucoBoard> CaliscopeCharucoBoard() {
  return cv::aruco::CharucoBoard::create(4, 5, 0.054, 0.0405,
                                         cv::aruco::getPredefinedDictionary(cv::aruco::DICT_4X4_1000));
}

// OpenCV's detection of the board in `gray` (the print is inverted): its markers, and its chessboard
// corners by ChArUco interpolation with the camera's matrix and distortion where given (empty Mats:
// none); no corners where fewer than 3 markers are found.
struct CharucoDetection {
  std::vector<std::vector<cv::Point2f>> markers;
  std::vector<int> marker_ids;
  std::vector<cv::Point2f> corners;
  std::vector<int> corner_ids;
};
inline CharucoDetection DetectCharuco(const cv::Mat& gray, const cv::Ptr<cv::aruco::CharucoBoard>& board,
                                      const cv::Mat& K, const cv::Mat& dist) {
  CharucoDetection d;
  const cv::Mat inv = 255 - gray;
  cv::aruco::detectMarkers(inv, board->dictionary, d.markers, d.marker_ids);
  if (d.marker_ids.size() >= 3)
    cv::aruco::interpolateCornersCharuco(d.markers, d.marker_ids, inv, board, d.corners, d.corner_ids, K,
                                         dist);
  return d;
}

// A quad's centre: the crossing of its diagonals (the projection of a square's centre under any
// homography), in homogeneous coordinates x = (q0 x q2) x (q1 x q3).
inline Eigen::Vector2d DiagonalCrossing(const std::array<Eigen::Vector2d, 4>& q) {
  auto h = [](const Eigen::Vector2d& p) { return Eigen::Vector3d(p.x(), p.y(), 1.0); };
  const Eigen::Vector3d x = h(q[0]).cross(h(q[2])).cross(h(q[1]).cross(h(q[3])));
  return x.head<2>() / x.z();
}

// A board-to-image homography fitted to the centres of the markers `quads` (id, corners in ideal px)
// against their centres on `board`: no chessboard corner involved. Empty (`ok` false) below 5 markers.
inline BoardHomography CentresHomography(
    const cv::aruco::CharucoBoard& board, const std::map<int, int>& marker_index,
    const std::vector<std::pair<int, std::array<Eigen::Vector2d, 4>>>& quads) {
  std::vector<cv::Point2d> plane, image;
  for (const auto& [id, quad] : quads) {
    auto it = marker_index.find(id);
    if (it == marker_index.end()) continue;
    const cv::Point3f* obj = board.objPoints[it->second].data();
    plane.emplace_back(0.5 * (obj[0].x + obj[2].x), 0.5 * (obj[0].y + obj[2].y));
    const Eigen::Vector2d c = DiagonalCrossing(quad);
    image.emplace_back(c.x(), c.y());
  }
  if (plane.size() < 5) plane.clear();
  return BoardHomography(plane, image);
}

// Cameras of `rig` (all, or only `camera`), at most `max_frames` frames each (< 0: all). `hook` (optional)
// sees every frame with a homography.
inline ChessboardComparison CompareWithChessboard(const RigConfig& rig, int max_frames = -1,
                                                  const std::string& camera = "",
                                                  const ChessboardFrameHook& hook = nullptr) {
  const auto board = CaliscopeCharucoBoard();
  std::map<int, int> marker_index;
  for (size_t i = 0; i < board->ids.size(); ++i) marker_index[board->ids[i]] = static_cast<int>(i);
  ChessboardComparison out;
  double rms_sum = 0;
  for (const CameraConfig& cam : rig.cameras) {
    if (!camera.empty() && cam.name != camera) continue;
    SourceOptions so;
    so.source = cam.source, so.camera = cam.name;
    auto source = FrameSource::Open(so);
    const std::vector<detections_t> recorded = DetectRecording(rig, cam.name, max_frames);
    const CameraModel& m = cam.model;
    const cv::Mat K = (cv::Mat_<double>(3, 3) << m.fx, 0, m.cx, 0, m.fy, m.cy, 0, 0, 1);
    const cv::Mat dist(m.distortion, true);
    auto ideal = [&](double x, double y) {  // raw pixel -> undistorted pixel
      const Eigen::Vector2d n = m.Unproject(Eigen::Vector2d(x, y));
      return Eigen::Vector2d(m.fx * n.x() + m.cx, m.fy * n.y() + m.cy);
    };
    auto raw = [&](const Eigen::Vector2d& p) {  // undistorted pixel -> raw pixel
      double xd, yd;
      m.Distort((p.x() - m.cx) / m.fx, (p.y() - m.cy) / m.fy, &xd, &yd);
      return Eigen::Vector2d(m.fx * xd + m.cx, m.fy * yd + m.cy);
    };
    Frame frame;
    for (size_t f = 0; f < recorded.size() && source->Read(&frame); ++f) {
      out.detected.push_back(recorded[f]);
      cv::Mat gray;
      if (frame.image.channels() == 3)
        cv::cvtColor(frame.image, gray, cv::COLOR_BGR2GRAY);
      else
        gray = frame.image;
      const CharucoDetection detection = DetectCharuco(gray, board, K, dist);
      const std::vector<std::vector<cv::Point2f>>& corners = detection.markers;
      const std::vector<int>& ids = detection.marker_ids;
      const std::vector<cv::Point2f>& cc = detection.corners;
      const std::vector<int>& cids = detection.corner_ids;
      if (ids.size() < 3 || cc.size() < 6) continue;
      ChessboardCorners xc;
      for (size_t i = 0; i < cc.size(); ++i) {
        const cv::Point3f p = board->chessboardCorners[cids[i]];
        xc.plane.emplace_back(p.x, p.y);
        const Eigen::Vector2d q = ideal(cc[i].x, cc[i].y);
        xc.ideal.emplace_back(q.x(), q.y());
        xc.raw.emplace_back(cc[i].x, cc[i].y);
      }
      const BoardHomography apply(xc.plane, xc.ideal), apply_raw(xc.plane, xc.raw);
      if (!apply.ok || !apply_raw.ok) continue;
      const double rms = apply.Rms(xc.plane, xc.ideal);
      if (rms > 0.5) continue;
      rms_sum += rms, ++out.frames;
      if (hook) hook(cam.name, gray, [&](double x, double y) { return raw(apply(x, y)); });
      const double view_deg = apply.ViewDeg(m);
      // The prediction of marker `id` by `h`, if it is on the board and `first` (its detected corner 0, in
      // h's pixels) lies within 5 px of it.
      auto predict = [&](const BoardHomography& h, int id, const Eigen::Vector2d& first,
                         std::array<Eigen::Vector2d, 4>* want) {
        auto it = marker_index.find(id);
        if (it == marker_index.end() || !h.ok) return false;
        for (int k = 0; k < 4; ++k) {
          const cv::Point3f p = board->objPoints[it->second][k];
          (*want)[k] = h(p.x, p.y);
        }
        return (first - (*want)[0]).norm() <= 5.0;
      };
      // Homographies fitted to the centres of mcmt's markers and of stock OpenCV's.
      std::vector<std::pair<int, std::array<Eigen::Vector2d, 4>>> mcmt_quads, stock_quads;
      for (const marker_t& mk : recorded[f].markers) {
        std::array<Eigen::Vector2d, 4> q;
        for (int k = 0; k < 4; ++k) q[k] = ideal(mk.corners[k][0], mk.corners[k][1]);
        mcmt_quads.emplace_back(mk.id, q);
      }
      for (size_t i = 0; i < ids.size(); ++i) {
        std::array<Eigen::Vector2d, 4> q;
        for (int k = 0; k < 4; ++k) q[k] = ideal(corners[i][k].x, corners[i][k].y);
        stock_quads.emplace_back(ids[i], q);
      }
      const BoardHomography apply_centres = CentresHomography(*board, marker_index, mcmt_quads),
                            apply_stock_centres = CentresHomography(*board, marker_index, stock_quads);
      detections_t replaced = recorded[f];
      replaced.markers.clear();
      for (const marker_t& mk : recorded[f].markers) {
        std::array<Eigen::Vector2d, 4> want, got, got_raw, want_raw;
        for (int k = 0; k < 4; ++k) got_raw[k] = Eigen::Vector2d(mk.corners[k][0], mk.corners[k][1]);
        for (int k = 0; k < 4; ++k) got[k] = ideal(got_raw[k].x(), got_raw[k].y());
        if (!predict(apply, mk.id, got[0], &want)) continue;
        ChessboardMarker c, other;
        c.camera = cam.name, c.id = mk.id, c.frame = static_cast<int>(f), c.view_deg = view_deg;
        SideOffsets(got, want, &c);
        if (predict(apply_raw, mk.id, got_raw[0], &want_raw))
          SideOffsets(got_raw, want_raw, &other), c.size_rel_raw = other.size_rel;
        const cv::Point3f* obj = board->objPoints[marker_index[mk.id]].data();
        const cv::Point2d centre(0.5 * (obj[0].x + obj[2].x), 0.5 * (obj[0].y + obj[2].y));
        if (predict(LocalHomography(xc.plane, xc.ideal, centre, 0.09), mk.id, got[0], &want_raw))
          SideOffsets(got, want_raw, &other), c.size_rel_local = other.size_rel;
        if (predict(apply_centres, mk.id, got[0], &want_raw))
          SideOffsets(got, want_raw, &other), c.size_rel_centres = other.size_rel;
        if (predict(apply_stock_centres, mk.id, got[0], &want_raw))
          SideOffsets(got, want_raw, &other), c.size_rel_stock_centres = other.size_rel,
                                              c.side_offset_stock_px = other.side_offset_px;
        c.got_ideal = got, c.want_ideal = want;
        marker_t r = mk;
        for (int k = 0; k < 4; ++k) {
          want_raw[k] = raw(want[k]);
          r.corners[k][0] = want_raw[k].x(), r.corners[k][1] = want_raw[k].y();
          c.x_px += 0.25 * want_raw[k].x(), c.y_px += 0.25 * want_raw[k].y();
        }
        c.white = WhiteLevel(gray, want_raw);
        out.mcmt.push_back(c);
        replaced.markers.push_back(r);
      }
      replaced.num_markers = static_cast<int>(replaced.markers.size());
      if (replaced.num_markers > 0) out.predicted.push_back(replaced);
      for (size_t i = 0; i < ids.size(); ++i) {
        std::array<Eigen::Vector2d, 4> want, got;
        for (int k = 0; k < 4; ++k) got[k] = ideal(corners[i][k].x, corners[i][k].y);
        if (!predict(apply, ids[i], got[0], &want)) continue;
        ChessboardMarker c;
        c.camera = cam.name, c.id = ids[i], c.frame = static_cast<int>(f);
        SideOffsets(got, want, &c);
        out.stock.push_back(c);
      }
    }
  }
  out.homography_rms_px = out.frames ? rms_sum / out.frames : 0.0;
  return out;
}

// The board's marker spacing (diagonal squares, 5.4 cm * sqrt(2)) relative to the marker size (4.05 cm)
// in `map`: the least-squares scale of all marker centres' distances against those of the nearest
// 5.4 cm grid points (in the reference marker's frame, z = 0). The board's: 1.885618.
inline double BoardSpacingOverSize(const RigMap& map) {
  std::vector<Eigen::Vector3d> measured, ideal;
  for (const MapMarker& m : map.markers) {
    const Eigen::Vector3d p = m.object_from_marker.translation();
    measured.push_back(p);
    ideal.emplace_back(0.054 * std::round(p.x() / 0.054), 0.054 * std::round(p.y() / 0.054), 0.0);
  }
  double dot = 0, ideal_sq = 0;
  for (size_t i = 0; i < measured.size(); ++i)
    for (size_t j = i + 1; j < measured.size(); ++j) {
      const double d_ideal = (ideal[i] - ideal[j]).norm();
      dot += (measured[i] - measured[j]).norm() * d_ideal;
      ideal_sq += d_ideal * d_ideal;
    }
  return dot / ideal_sq * 0.054 * std::sqrt(2.0) / 0.0405;
}

}  // namespace mcmt::testing
