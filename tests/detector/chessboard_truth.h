// The caliscope board's ChArUco chessboard corners as an independent truth for its markers' corners.
// OpenCV locates the chessboard corners by their saddle points (cornerSubPix on the inverted image),
// which neither the print's margins nor the camera's transfer curve move. Per frame a homography from
// the board's plane to the undistorted image, fitted to them, predicts every marker's corners from the
// board's geometry (4 x 5 squares of 5.4 cm, 4.05 cm markers, DICT_4X4_1000). Used by
// test_detector_realdata and bench/detector/diag_charuco.
#pragma once

#include <array>
#include <functional>
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
  double side_px = 0;    // predicted mean side, px
  double offset_px = 0;  // mean signed offset of the four sides along their outward normals, px
  double size_rel = 0;   // detected perimeter / predicted perimeter - 1
};

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
    offset += 0.125 * (n.dot(got[s] - a) + n.dot(got[(s + 1) % 4] - b));
    got_len += (got[(s + 1) % 4] - got[s]).norm(), want_len += (b - a).norm();
  }
  out->side_px = want_len / 4, out->offset_px = offset, out->size_rel = got_len / want_len - 1.0;
}

// A frame with its board-to-image mapping: the raw image pixel of the board's point (x, y), m.
using ChessboardFrameHook =
    std::function<void(const std::string& camera, const cv::Mat& gray,
                       const std::function<Eigen::Vector2d(double, double)>& raw_from_board)>;

// Cameras of `rig` (all, or only `camera`), at most `max_frames` frames each (< 0: all). `hook` (optional)
// sees every frame with a homography.
inline ChessboardComparison CompareWithChessboard(const RigConfig& rig, int max_frames = -1,
                                                  const std::string& camera = "",
                                                  const ChessboardFrameHook& hook = nullptr) {
  auto dict = cv::aruco::getPredefinedDictionary(cv::aruco::DICT_4X4_1000);
  auto board = cv::aruco::CharucoBoard::create(4, 5, 0.054, 0.0405, dict);
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
      const cv::Mat inv = 255 - gray;  // the print is inverted
      std::vector<std::vector<cv::Point2f>> corners;
      std::vector<int> ids;
      cv::aruco::detectMarkers(inv, dict, corners, ids);
      if (ids.size() < 3) continue;
      std::vector<cv::Point2f> cc;
      std::vector<int> cids;
      cv::aruco::interpolateCornersCharuco(corners, ids, inv, board, cc, cids, K, dist);
      if (cc.size() < 6) continue;
      std::vector<cv::Point2d> plane, image;
      for (size_t i = 0; i < cc.size(); ++i) {
        const cv::Point3f p = board->chessboardCorners[cids[i]];
        plane.emplace_back(p.x, p.y);
        const Eigen::Vector2d q = ideal(cc[i].x, cc[i].y);
        image.emplace_back(q.x(), q.y());
      }
      const cv::Mat H = cv::findHomography(plane, image, 0);
      if (H.empty()) continue;
      const cv::Matx33d image_from_board(H);
      auto apply = [&](double x, double y) {
        const cv::Vec3d v = image_from_board * cv::Vec3d(x, y, 1);
        return Eigen::Vector2d(v[0] / v[2], v[1] / v[2]);
      };
      double rms = 0;
      for (size_t i = 0; i < plane.size(); ++i)
        rms += (apply(plane[i].x, plane[i].y) - Eigen::Vector2d(image[i].x, image[i].y)).squaredNorm();
      rms = std::sqrt(rms / plane.size());
      if (rms > 0.5) continue;
      rms_sum += rms, ++out.frames;
      if (hook) hook(cam.name, gray, [&](double x, double y) { return raw(apply(x, y)); });
      // The prediction of marker `id` (undistorted pixels), if it is on the board and `first` (its
      // detected corner 0, undistorted) lies within 5 px of it.
      auto predict = [&](int id, const Eigen::Vector2d& first, std::array<Eigen::Vector2d, 4>* want) {
        auto it = marker_index.find(id);
        if (it == marker_index.end()) return false;
        for (int k = 0; k < 4; ++k) {
          const cv::Point3f p = board->objPoints[it->second][k];
          (*want)[k] = apply(p.x, p.y);
        }
        return (first - (*want)[0]).norm() <= 5.0;
      };
      detections_t replaced = recorded[f];
      replaced.markers.clear();
      for (const marker_t& mk : recorded[f].markers) {
        std::array<Eigen::Vector2d, 4> want, got;
        for (int k = 0; k < 4; ++k) got[k] = ideal(mk.corners[k][0], mk.corners[k][1]);
        if (!predict(mk.id, got[0], &want)) continue;
        ChessboardMarker c;
        c.camera = cam.name, c.id = mk.id;
        SideOffsets(got, want, &c);
        out.mcmt.push_back(c);
        marker_t r = mk;
        for (int k = 0; k < 4; ++k) {
          const Eigen::Vector2d q = raw(want[k]);
          r.corners[k][0] = q.x(), r.corners[k][1] = q.y();
        }
        replaced.markers.push_back(r);
      }
      replaced.num_markers = static_cast<int>(replaced.markers.size());
      if (replaced.num_markers > 0) out.predicted.push_back(replaced);
      for (size_t i = 0; i < ids.size(); ++i) {
        std::array<Eigen::Vector2d, 4> want, got;
        for (int k = 0; k < 4; ++k) got[k] = ideal(corners[i][k].x, corners[i][k].y);
        if (!predict(ids[i], got[0], &want)) continue;
        ChessboardMarker c;
        c.camera = cam.name, c.id = ids[i];
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
