// Why corner_weights sides (core/marker.h CornerSqrtInformation) helps on the reference renderer's maps and
// not on the real caliscope board: the board's chessboard corners predict every detected marker corner
// (tests/detector/chessboard_truth.h), and the detector's corner errors are split in the frame of the
// sides' information n1 n1^T + n2 n2^T: its weak direction (eigenvalue 1 - |cos a|, a the corner's angle:
// along an acute corner's bisector, across an obtuse one's) and its strong one (1 + |cos a|), signed
// outward (away from the marker's centre), per camera and corner angle, less each camera's mean error (a
// shift of all its corners, mostly OpenCV's ChArUco corners' +0.47 px: bench/detector/diag_pixel_convention).
// If each side were located to the same precision whatever the angle (what sides assumes), the "whitened"
// rms (error * sqrt(eigenvalue)) would be the same in both directions. Then the board is mapped (as
// test_mapper_realdata) with equal and sides weights from
//   - the detected corners; the chessboard's predicted corners; the predicted corners plus the camera's
//     shift, or only the weak (or only the strong) part of the detector's error less that shift;
//   - the detected corners of three cameras of four;
//   - ROUNDS random halves of the frames (the same utimes for all cameras): the spread of the board's
//     spacing / size within the session, and of the difference sides - equal on the same frames.
//   diag_corner_weights RIG_YAML [ROUNDS (20)] [CACHE (detected and predicted corners: read if present,
//   else written)]
// Environment: MCMT_CORNER_WEIGHT_FLOOR (the sides' floor, 0.05).
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <map>
#include <random>
#include <set>
#include <sstream>

#include "core/lcm_util.h"
#include "mapper/mapper.h"
#include "tests/detector/chessboard_truth.h"

using namespace mcmt;

namespace {

using Frames = std::vector<detections_t>;

// The detected and the chessboard-predicted corners of every frame, from the cache file if there is one.
void Load(const RigConfig& rig, const std::string& cache, Frames* detected, Frames* predicted) {
  std::ifstream in(cache);
  if (cache.empty() || !in) {
    const testing::ChessboardComparison c = testing::CompareWithChessboard(rig);
    *detected = c.detected, *predicted = c.predicted;
    if (cache.empty()) return;
    std::ofstream out(cache);
    for (int kind = 0; kind < 2; ++kind)
      for (const detections_t& d : kind == 0 ? c.detected : c.predicted) {
        out << kind << " " << d.utime << " " << d.seq << " " << d.camera << " " << d.num_markers << "\n";
        for (const marker_t& m : d.markers) {
          char line[512];
          std::snprintf(line, sizeof line, "%d %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n", m.id,
                        m.corners[0][0], m.corners[0][1], m.corners[1][0], m.corners[1][1], m.corners[2][0],
                        m.corners[2][1], m.corners[3][0], m.corners[3][1]);
          out << line;
        }
      }
    return;
  }
  std::map<std::string, camera_model_t> models;
  for (const CameraConfig& cam : rig.cameras) models[cam.name] = ToCameraModelMsg(cam.model);
  int kind;
  detections_t d;
  while (in >> kind >> d.utime >> d.seq >> d.camera >> d.num_markers) {
    d.dictionary = rig.markers.dictionary, d.camera_model = models.at(d.camera), d.detection_ms = 0;
    d.markers.resize(d.num_markers);
    for (marker_t& m : d.markers) {
      in >> m.id;
      for (auto& c : m.corners) in >> c[0] >> c[1];
    }
    (kind == 0 ? detected : predicted)->push_back(d);
  }
}

// The board's marker spacing / marker size of the map of `frames` relative to the board's, %; NaN if
// the mapper fails or does not place the ten markers.
double ScaleErrorPercent(const RigConfig& rig, const Frames& frames, bool sides, double floor) {
  RigConfig used = rig;  // the cameras that have frames
  std::set<std::string> seen;
  for (const detections_t& d : frames) seen.insert(d.camera);
  used.cameras.erase(std::remove_if(used.cameras.begin(), used.cameras.end(),
                                    [&](const CameraConfig& c) { return !seen.count(c.name); }),
                     used.cameras.end());
  MapperOptions options = MapperOptions::FromConfig(used);
  options.corner_weighting = {sides ? "sides" : "equal", floor};
  Mapper mapper(options);
  for (const detections_t& d : frames) mapper.Add(d);
  try {
    const MapResult result = mapper.Solve();
    if (result.map.markers.size() != 10 || result.map.cameras.size() < 3) return NAN;
    return 100.0 * (testing::BoardSpacingOverSize(result.map) / 1.885618 - 1.0);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "map: %s\n", e.what());
    return NAN;
  }
}

std::string Key(const detections_t& d) { return d.camera + "/" + std::to_string(d.utime); }

// Corner k's weak (along both sides) and strong unit directions, signed outward, and their eigenvalues
// of n1 n1^T + n2 n2^T; its angle, deg.
struct CornerFrame {
  Eigen::Vector2d weak, strong;
  double weak_eig = 0, strong_eig = 0, angle_deg = 0;
};

CornerFrame FrameOf(const MarkerCorners2d& c, int k) {
  Eigen::Matrix2d omega = Eigen::Matrix2d::Zero();
  const Eigen::Vector2d d1 = (c[(k + 1) % 4] - c[k]).normalized(), d2 = (c[(k + 3) % 4] - c[k]).normalized();
  for (const Eigen::Vector2d& d : {d1, d2}) {
    const Eigen::Vector2d n(-d.y(), d.x());
    omega += n * n.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(omega);  // ascending
  CornerFrame f;
  f.weak = eig.eigenvectors().col(0), f.strong = eig.eigenvectors().col(1);
  f.weak_eig = eig.eigenvalues()(0), f.strong_eig = eig.eigenvalues()(1);
  const Eigen::Vector2d centre = 0.25 * (c[0] + c[1] + c[2] + c[3]);
  if (f.weak.dot(c[k] - centre) < 0) f.weak = -f.weak;
  if (f.strong.dot(c[k] - centre) < 0) f.strong = -f.strong;
  f.angle_deg = std::acos(std::clamp(d1.dot(d2), -1.0, 1.0)) * 180 / M_PI;
  return f;
}

struct Stats {
  int n = 0;
  double weak = 0, strong = 0, weak2 = 0, strong2 = 0, white_weak2 = 0, white_strong2 = 0, across2 = 0;
  // Least squares of e^2 = iso + side / eigenvalue over both directions of every corner (covariance
  // iso I + side (n1 n1^T + n2 n2^T)^-1): normal equations.
  Eigen::Matrix2d ata = Eigen::Matrix2d::Zero();
  Eigen::Vector2d atb = Eigen::Vector2d::Zero();
  void Add(const CornerFrame& f, const Eigen::Vector2d& e, const MarkerCorners2d& c, int k) {
    const double w = f.weak.dot(e), s = f.strong.dot(e);
    ++n, weak += w, strong += s, weak2 += w * w, strong2 += s * s;
    white_weak2 += w * w * f.weak_eig, white_strong2 += s * s * f.strong_eig;
    for (const auto& [e2, eig] : {std::pair{w * w, f.weak_eig}, std::pair{s * s, f.strong_eig}}) {
      const Eigen::Vector2d row(1.0, 1.0 / std::max(eig, 0.05));
      ata += row * row.transpose(), atb += e2 * row;
    }
    for (int step : {1, 3}) {  // across each of the two sides
      const Eigen::Vector2d d = (c[(k + step) % 4] - c[k]).normalized();
      across2 += 0.5 * std::pow(Eigen::Vector2d(-d.y(), d.x()).dot(e), 2);
    }
  }
  void Print(const std::string& what) const {
    if (n < 8) return;
    const Eigen::Vector2d fit = ata.ldlt().solve(atb);
    auto root = [](double v) { return v < 0 ? -std::sqrt(-v) : std::sqrt(v); };
    std::printf("| %s | %d | %+.3f | %+.3f | %.3f | %.3f | %.3f | %.3f | %.2f | %.3f | %.3f |\n",
                what.c_str(), n, weak / n, strong / n, std::sqrt(weak2 / n), std::sqrt(strong2 / n),
                std::sqrt(across2 / n), std::sqrt(white_weak2 / n), std::sqrt(white_weak2 / white_strong2),
                root(fit(0)), root(fit(1)));
  }
};

// Every predicted frame with its detected markers' corners moved to the prediction plus `part` of the
// detector's error at each corner less its camera's mean `shift` (in the corner's weak / strong frame).
Frames Hybrid(const Frames& predicted, const std::map<std::string, const detections_t*>& detected,
              const std::map<std::string, Eigen::Vector2d>& shift,
              const std::function<Eigen::Vector2d(const CornerFrame&, const Eigen::Vector2d& error,
                                                  const Eigen::Vector2d& shift)>& part) {
  Frames out = predicted;
  for (detections_t& d : out) {
    const detections_t* det = detected.at(Key(d));
    for (marker_t& m : d.markers)
      for (const marker_t& g : det->markers) {
        if (g.id != m.id) continue;
        const MarkerCorners2d got = CornersOf(g), want = CornersOf(m);
        for (int k = 0; k < 4; ++k) {
          const Eigen::Vector2d p =
              want[k] + part(FrameOf(got, k), got[k] - want[k] - shift.at(d.camera), shift.at(d.camera));
          m.corners[k][0] = p.x(), m.corners[k][1] = p.y();
        }
      }
  }
  return out;
}

void PrintMaps(const RigConfig& rig, const std::string& what, const Frames& frames, double floor) {
  const double equal = ScaleErrorPercent(rig, frames, false, floor);
  const double sides = ScaleErrorPercent(rig, frames, true, floor);
  std::printf("| %s | %+.3f | %+.3f | %+.3f |\n", what.c_str(), equal, sides, sides - equal);
}

// Mean and standard deviation.
std::pair<double, double> MeanSd(const std::vector<double>& v) {
  double s = 0, s2 = 0;
  for (double x : v) s += x, s2 += x * x;
  const double mean = s / v.size();
  return {mean, std::sqrt(std::max(0.0, s2 / v.size() - mean * mean) * v.size() / (v.size() - 1.0))};
}

using ByKey = std::map<std::string, const detections_t*>;
using Shifts = std::map<std::string, Eigen::Vector2d>;

// Each camera's mean corner error (a shift of all its corners: the same as a principal point offset).
Shifts MeanShifts(const Frames& predicted, const ByKey& by_key) {
  Shifts shift;
  std::map<std::string, int> count;
  for (const detections_t& p : predicted)
    for (const marker_t& m : p.markers)
      for (const marker_t& g : by_key.at(Key(p))->markers)
        if (g.id == m.id)
          for (int k = 0; k < 4; ++k) {
            auto [it, added] = shift.try_emplace(p.camera, Eigen::Vector2d::Zero());
            it->second += CornersOf(g)[k] - CornersOf(m)[k], ++count[p.camera];
          }
  for (auto& [camera, s] : shift) {
    s /= count[camera];
    std::printf("%s: mean corner error (detected - predicted) %+.3f %+.3f px (subtracted below)\n",
                camera.c_str(), s.x(), s.y());
  }
  return shift;
}

// The corner errors (raw px, less the camera's shift) per camera and corner angle; returns the detected
// markers that have a prediction.
Frames PrintCornerErrors(const Frames& predicted, const ByKey& by_key, const Shifts& shift) {
  std::map<std::string, Stats> stats;
  Frames detected_predicted;
  for (const detections_t& p : predicted) {
    detections_t kept = *by_key.at(Key(p));
    kept.markers.clear();
    for (const marker_t& m : p.markers)
      for (const marker_t& g : by_key.at(Key(p))->markers) {
        if (g.id != m.id) continue;
        kept.markers.push_back(g);
        const MarkerCorners2d got = CornersOf(g), want = CornersOf(m);
        for (int k = 0; k < 4; ++k) {
          const CornerFrame f = FrameOf(got, k);
          const int band = std::clamp(static_cast<int>(std::floor(f.angle_deg / 15)), 3, 8);
          const std::string angle = "angle " + std::to_string(15 * band) + "-" +
                                    std::to_string(15 * band + 15) + " deg" +
                                    (band == 3   ? " and less"
                                     : band == 8 ? " and more"
                                                 : "");
          for (const std::string& key :
               {p.camera + " all", p.camera + " " + angle, "all " + angle, std::string("all all")})
            stats[key].Add(f, got[k] - want[k] - shift.at(p.camera), got, k);
        }
      }
    kept.num_markers = static_cast<int>(kept.markers.size());
    detected_predicted.push_back(kept);
  }
  std::printf(
      "## Corner errors against the chessboard's prediction (raw px; outward +)\n\n"
      "| camera, corner angle | corners | mean weak | mean strong | rms weak | rms strong | rms across a "
      "side "
      "| whitened rms weak | whitened weak / strong | fit: isotropic | fit: per side |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const auto& [key, s] : stats) s.Print(key);
  return detected_predicted;
}

// The maps of the detected, predicted and hybrid corners and of three cameras of four.
void PrintAllMaps(const RigConfig& rig, const Frames& detected, const Frames& detected_predicted,
                  const Frames& predicted, const ByKey& by_key, const Shifts& shift, double floor) {
  std::printf(
      "\n## Board spacing / size, %% (floor %.3g)\n\n| corners | equal | sides | sides - equal |\n"
      "|---|---|---|---|\n",
      floor);
  PrintMaps(rig, "detected", detected, floor);
  PrintMaps(rig, "detected, markers with a prediction", detected_predicted, floor);
  PrintMaps(rig, "chessboard-predicted", predicted, floor);
  using V = Eigen::Vector2d;
  PrintMaps(rig, "predicted + the camera's mean shift",
            Hybrid(predicted, by_key, shift, [](const CornerFrame&, const V&, const V& s) { return s; }),
            floor);
  PrintMaps(rig, "predicted + weak part of the error less the shift",
            Hybrid(predicted, by_key, shift,
                   [](const CornerFrame& f, const V& e, const V&) -> V { return f.weak.dot(e) * f.weak; }),
            floor);
  PrintMaps(
      rig, "predicted + strong part of the error less the shift",
      Hybrid(predicted, by_key, shift,
             [](const CornerFrame& f, const V& e, const V&) -> V { return f.strong.dot(e) * f.strong; }),
      floor);
  for (const CameraConfig& cam : rig.cameras) {
    Frames without;
    for (const detections_t& d : detected)
      if (d.camera != cam.name) without.push_back(d);
    PrintMaps(rig, "detected, without " + cam.name, without, floor);
  }
}

// Random halves of the frames (delete-half jackknife: the halves' spread estimates the full session's).
void PrintHalves(const RigConfig& rig, const Frames& detected, int rounds, double floor) {
  std::set<int64_t> utimes;
  for (const detections_t& d : detected) utimes.insert(d.utime);
  std::mt19937 rng(1);
  std::vector<double> equal, sides, diff;
  for (int r = 0; r < rounds; ++r) {
    std::vector<int64_t> all(utimes.begin(), utimes.end());
    std::shuffle(all.begin(), all.end(), rng);
    const std::set<int64_t> half(all.begin(), all.begin() + all.size() / 2);
    Frames frames;
    for (const detections_t& d : detected)
      if (half.count(d.utime)) frames.push_back(d);
    const double e = ScaleErrorPercent(rig, frames, false, floor),
                 s = ScaleErrorPercent(rig, frames, true, floor);
    if (std::isnan(e) || std::isnan(s)) continue;
    equal.push_back(e), sides.push_back(s), diff.push_back(s - e);
  }
  if (equal.size() < 2) return;
  const auto [me, se] = MeanSd(equal);
  const auto [ms, ss] = MeanSd(sides);
  const auto [md, sd] = MeanSd(diff);
  std::printf(
      "\nhalves of the frames (%zu of %d mapped): equal %+.3f +- %.3f %%, sides %+.3f +- %.3f %%, "
      "sides - equal %+.3f +- %.3f %% (mean +- sd over the halves)\n",
      equal.size(), rounds, me, se, ms, ss, md, sd);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: diag_corner_weights RIG_YAML [ROUNDS] [CACHE]\n");
    return 2;
  }
  const RigConfig rig = LoadRigConfig(argv[1]);
  const int rounds = argc > 2 ? std::atoi(argv[2]) : 20;
  const double floor =
      std::getenv("MCMT_CORNER_WEIGHT_FLOOR") ? std::atof(std::getenv("MCMT_CORNER_WEIGHT_FLOOR")) : 0.05;
  Frames detected, predicted;
  Load(rig, argc > 3 ? argv[3] : "", &detected, &predicted);
  ByKey by_key;
  for (const detections_t& d : detected) by_key[Key(d)] = &d;
  const Shifts shift = MeanShifts(predicted, by_key);
  const Frames detected_predicted = PrintCornerErrors(predicted, by_key, shift);
  PrintAllMaps(rig, detected, detected_predicted, predicted, by_key, shift, floor);
  PrintHalves(rig, detected, rounds, floor);
  return 0;
}
