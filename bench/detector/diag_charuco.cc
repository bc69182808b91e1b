// The caliscope board's marker corners against its ChArUco chessboard corners (OpenCV's saddle-point
// refinement, an independent truth on the same images): per frame a homography from the board's plane to
// the undistorted image, fitted to the chessboard corners, predicts every marker's corners from the
// board's geometry (5.4 cm squares, 4.05 cm markers). Prints the signed offsets (px, outward) of mcmt's
// corners and of stock OpenCV's, per marker id and in all, and the relative size error.
// Then maps the detections as test_mapper_realdata does, once as detected and once with every marker's
// corners replaced by the chessboard's prediction (markers without one dropped), and prints the board's
// marker spacing / marker size of both maps (board: 1.88562).
//   diag_charuco RIG_YAML [max frames per camera (all)] [camera]
#include <cstdio>
#include <cstdlib>
#include <map>
#include <opencv2/aruco/charuco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "core/config.h"
#include "detector/detector.h"
#include "detector/source.h"
#include "mapper/mapper.h"

using namespace mcmt;

namespace {
struct Stats {
  double offset_sum = 0, rel_sum = 0;
  int sides = 0, markers = 0;
  std::vector<double> per_side;
  void AddMarker(const std::array<Eigen::Vector2d, 4>& got, const std::array<Eigen::Vector2d, 4>& want) {
    Eigen::Vector2d centre = Eigen::Vector2d::Zero();
    for (const auto& p : want) centre += p / 4;
    double got_len = 0, want_len = 0;
    for (int s = 0; s < 4; ++s) {
      const Eigen::Vector2d a = want[s], b = want[(s + 1) % 4];
      Eigen::Vector2d n((b - a).y(), -(b - a).x());
      n.normalize();
      if (n.dot(0.5 * (a + b) - centre) < 0) n = -n;
      const double off = 0.5 * (n.dot(got[s] - a) + n.dot(got[(s + 1) % 4] - b));
      offset_sum += off, ++sides;
      per_side.push_back(off);
      got_len += (got[(s + 1) % 4] - got[s]).norm(), want_len += (b - a).norm();
    }
    rel_sum += got_len / want_len - 1.0, ++markers;
  }
  void Print(const char* what) const {
    if (!markers) return;
    std::printf("%-14s %5d markers: offset %+.4f px  size %+.3f %%\n", what, markers, offset_sum / sides,
                100 * rel_sum / markers);
  }
};
// test_mapper_realdata's measure: least-squares scale of the marker centres' distances against the
// 5.4 cm grid's, as marker spacing (diagonal squares) / marker size.
double SpacingOverSize(const RigMap& map) {
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
}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) return 2;
  const RigConfig rig = LoadRigConfig(argv[1]);
  const int max_frames = argc > 2 ? std::atoi(argv[2]) : -1;
  const std::string only = argc > 3 ? argv[3] : "";
  auto dict = cv::aruco::getPredefinedDictionary(cv::aruco::DICT_4X4_1000);
  auto board = cv::aruco::CharucoBoard::create(4, 5, 0.054, 0.0405, dict);
  std::map<int, int> marker_index;
  for (size_t i = 0; i < board->ids.size(); ++i) marker_index[board->ids[i]] = static_cast<int>(i);
  Stats mcmt_all, stock_all;
  std::map<int, Stats> mcmt_by_id;
  std::map<int, Stats> mcmt_by_size;  // marker side / 10 px
  double h_rms_sum = 0;
  int h_count = 0;
  std::vector<detections_t> as_detected, predicted_all;
  for (const CameraConfig& cam : rig.cameras) {
    if (!only.empty() && cam.name != only) continue;
    SourceOptions so;
    so.source = cam.source, so.camera = cam.name;
    auto source = FrameSource::Open(so);
    MarkerDetector detector(rig.markers, DetectorOptions::FromConfig(rig));
    detector.SetCamera(cam.model);
    const std::vector<detections_t> recorded = DetectRecording(rig, cam.name, max_frames);
    const CameraModel& m = cam.model;
    cv::Mat K = (cv::Mat_<double>(3, 3) << m.fx, 0, m.cx, 0, m.fy, m.cy, 0, 0, 1);
    cv::Mat dist(m.distortion, true);
    auto ideal = [&](double x, double y) {
      const Eigen::Vector2d n = m.Unproject(Eigen::Vector2d(x, y));
      return Eigen::Vector2d(m.fx * n.x() + m.cx, m.fy * n.y() + m.cy);
    };
    Frame frame;
    int frames = 0;
    auto pixel = [&](const Eigen::Vector2d& ideal_px) {  // ideal pixel -> raw pixel
      double xd, yd;
      m.Distort((ideal_px.x() - m.cx) / m.fx, (ideal_px.y() - m.cy) / m.fy, &xd, &yd);
      return Eigen::Vector2d(m.fx * xd + m.cx, m.fy * yd + m.cy);
    };
    Stats cam_stats;
    while ((max_frames < 0 || frames < max_frames) && source->Read(&frame)) {
      ++frames;
      const bool have_record = frames <= static_cast<int>(recorded.size());
      if (have_record) as_detected.push_back(recorded[frames - 1]);
      detections_t replaced;
      if (have_record) {
        replaced = recorded[frames - 1];
        replaced.markers.clear();
        replaced.num_markers = 0;
      }
      cv::Mat gray;
      if (frame.image.channels() == 3)
        cv::cvtColor(frame.image, gray, cv::COLOR_BGR2GRAY);
      else
        gray = frame.image;
      const std::vector<marker_t> found = detector.Detect(gray);
      cv::Mat inv = 255 - gray;
      std::vector<std::vector<cv::Point2f>> corners;
      std::vector<int> ids;
      cv::aruco::detectMarkers(inv, dict, corners, ids);
      if (std::getenv("DIAG_VERBOSE"))
        std::fprintf(stderr, "frame %d: mcmt %zu stock %zu\n", frames, found.size(), ids.size());
      if (ids.size() < 3) continue;
      std::vector<cv::Point2f> cc;
      std::vector<int> cids;
      cv::aruco::interpolateCornersCharuco(corners, ids, inv, board, cc, cids, K, dist);
      if (std::getenv("DIAG_VERBOSE")) std::fprintf(stderr, "  charuco %zu\n", cc.size());
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
      const cv::Matx33d h(H);
      auto apply = [&](double x, double y) {
        const cv::Vec3d v = h * cv::Vec3d(x, y, 1);
        return Eigen::Vector2d(v[0] / v[2], v[1] / v[2]);
      };
      double rms = 0;
      for (size_t i = 0; i < plane.size(); ++i)
        rms += (apply(plane[i].x, plane[i].y) - Eigen::Vector2d(image[i].x, image[i].y)).squaredNorm();
      rms = std::sqrt(rms / plane.size());
      h_rms_sum += rms, ++h_count;
      if (rms > 0.5) continue;
      auto predicted = [&](int id, std::array<Eigen::Vector2d, 4>* want) {
        auto it = marker_index.find(id);
        if (it == marker_index.end()) return false;
        for (int k = 0; k < 4; ++k) {
          const cv::Point3f p = board->objPoints[it->second][k];
          (*want)[k] = apply(p.x, p.y);
        }
        return true;
      };
      if (have_record)
        for (const marker_t& mk : recorded[frames - 1].markers) {
          std::array<Eigen::Vector2d, 4> want;
          if (!predicted(mk.id, &want)) continue;
          const Eigen::Vector2d c0 = ideal(mk.corners[0][0], mk.corners[0][1]);
          if ((c0 - want[0]).norm() > 5) continue;
          marker_t r = mk;
          for (int k = 0; k < 4; ++k) {
            const Eigen::Vector2d q = pixel(want[k]);
            r.corners[k][0] = q.x(), r.corners[k][1] = q.y();
          }
          replaced.markers.push_back(r);
        }
      replaced.num_markers = static_cast<int>(replaced.markers.size());
      if (have_record && replaced.num_markers > 0) predicted_all.push_back(replaced);
      for (const marker_t& mk : found) {
        std::array<Eigen::Vector2d, 4> want, got;
        if (!predicted(mk.id, &want)) continue;
        for (int k = 0; k < 4; ++k) got[k] = ideal(mk.corners[k][0], mk.corners[k][1]);
        if ((got[0] - want[0]).norm() > 5) continue;  // another rotation / not this marker
        mcmt_all.AddMarker(got, want), cam_stats.AddMarker(got, want);
        mcmt_by_id[mk.id].AddMarker(got, want);
        mcmt_by_size[static_cast<int>((want[1] - want[0]).norm() / 10)].AddMarker(got, want);
      }
      for (size_t i = 0; i < ids.size(); ++i) {
        std::array<Eigen::Vector2d, 4> want, got;
        if (!predicted(ids[i], &want)) continue;
        for (int k = 0; k < 4; ++k) got[k] = ideal(corners[i][k].x, corners[i][k].y);
        if ((got[0] - want[0]).norm() > 5) continue;
        stock_all.AddMarker(got, want);
      }
    }
    cam_stats.Print(cam.name.c_str());
  }
  std::printf("homography rms on chessboard corners: %.3f px (mean of %d frames)\n",
              h_count ? h_rms_sum / h_count : 0.0, h_count);
  mcmt_all.Print("mcmt all");
  stock_all.Print("stock all");
  for (const auto& [id, s] : mcmt_by_id) s.Print(("id " + std::to_string(id)).c_str());
  for (const auto& [b, s] : mcmt_by_size)
    s.Print((std::to_string(b * 10) + "-" + std::to_string(b * 10 + 10) + " px").c_str());
  for (int variant = 0; variant < 2; ++variant) {
    Mapper mapper(MapperOptions::FromConfig(rig));
    for (const auto& d : variant == 0 ? as_detected : predicted_all) mapper.Add(d);
    try {
      const MapResult result = mapper.Solve();
      const double r = SpacingOverSize(result.map);
      std::printf("map of %s: %zu markers, spacing / size %.5f (%+.3f %%)\n",
                  variant == 0 ? "the detected corners" : "the chessboard-predicted corners",
                  result.map.markers.size(), r, 100 * (r / 1.885618 - 1));
    } catch (const std::exception& e) {
      std::printf("map %d: %s\n", variant, e.what());
    }
  }
  return 0;
}
