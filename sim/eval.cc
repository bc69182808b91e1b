// Metrics of an estimate against ground truth (see eval.h for the alignments).
#include "sim/eval.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "core/json.h"
#include "core/lcm_util.h"
#include "core/log_reader.h"
#include "core/marker.h"
#include "core/objects.h"
#include "core/se3.h"
#include "mcmt/object_pose_t.hpp"

namespace mcmt {
namespace sim {

namespace {

constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;

double AngleDeg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  const Eigen::Matrix3d r = a.transpose() * b;
  const double c = std::clamp(0.5 * (r.trace() - 1.0), -1.0, 1.0);
  // acos is ill-conditioned near 0: use the skew part for small angles.
  const Eigen::Vector3d s(r(2, 1) - r(1, 2), r(0, 2) - r(2, 0), r(1, 0) - r(0, 1));
  return std::atan2(0.5 * s.norm(), c) * kRadToDeg;
}

std::string Fmt(double v, int digits = 3) {
  char b[64];
  std::snprintf(b, sizeof(b), "%.*f", digits, v);
  return b;
}

std::string JsonStats(const Stats& s) {
  return "{\"count\": " + std::to_string(s.count) + ", \"mean\": " + JsonNumber(s.mean) +
         ", \"median\": " + JsonNumber(s.median) + ", \"max\": " + JsonNumber(s.max) +
         ", \"rms\": " + JsonNumber(s.rms) + "}";
}

}  // namespace

Stats ComputeStats(std::vector<double> values) {
  Stats s;
  s.count = static_cast<int>(values.size());
  if (values.empty()) return s;
  double sum = 0, sq = 0;
  for (double v : values) {
    sum += v;
    sq += v * v;
    s.max = std::max(s.max, v);
  }
  s.mean = sum / values.size();
  s.rms = std::sqrt(sq / values.size());
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  s.median = n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
  return s;
}

namespace {

// The map's cameras against the truth's (names must belong to it): r's camera errors, the rigid alignment
// of the rig frames (on the camera centres, or through the first camera where fewer than 3) and the
// scale error of the distances between cameras.
void EvaluateCameras(const GroundTruth& truth, const RigMap& map, EvalResult* out) {
  EvalResult& r = *out;
  std::vector<const SimCamera*> gt_cams;
  std::vector<const MapCamera*> est_cams;
  for (const MapCamera& c : map.cameras) {
    const SimCamera* g = truth.FindCamera(c.name);
    if (!g) {
      std::string names;
      for (const auto& t : truth.cameras) names += (names.empty() ? "" : ", ") + t.name;
      throw EvalInputError("camera '" + c.name +
                           "' of the map is not in the ground truth (cameras: " + names + ")");
    }
    gt_cams.push_back(g);
    est_cams.push_back(&c);
  }
  if (gt_cams.empty()) throw EvalInputError("the map has no camera");
  for (const SimCamera& c : truth.cameras)
    if (!map.FindCamera(c.name)) r.missing_cameras.push_back(c.name);
  r.mapped_cameras = static_cast<int>(gt_cams.size());
  if (gt_cams.size() >= 3) {
    std::vector<Eigen::Vector3d> est, gt;
    for (size_t i = 0; i < gt_cams.size(); ++i) {
      est.push_back(est_cams[i]->rig_from_cam.translation());
      gt.push_back(gt_cams[i]->rig_from_cam.translation());
    }
    r.gt_rig_from_est_rig = AlignRigid(est, gt);
  } else {
    r.gt_rig_from_est_rig = gt_cams[0]->rig_from_cam * Inverse(est_cams[0]->rig_from_cam);
  }
  const Rigid3& A = r.gt_rig_from_est_rig;
  std::vector<double> cam_pos, cam_rot;
  for (size_t i = 0; i < gt_cams.size(); ++i) {
    const Rigid3 est = A * est_cams[i]->rig_from_cam;
    CameraError e;
    e.name = gt_cams[i]->name;
    e.position_mm = 1000.0 * TranslationDistance(est, gt_cams[i]->rig_from_cam);
    e.rotation_deg = AngleDeg(est.linear(), gt_cams[i]->rig_from_cam.linear());
    cam_pos.push_back(e.position_mm);
    cam_rot.push_back(e.rotation_deg);
    r.cameras.push_back(e);
  }
  r.camera_position_mm = ComputeStats(cam_pos);
  r.camera_rotation_deg = ComputeStats(cam_rot);
  double dot = 0, gt_sq = 0;
  for (size_t i = 0; i < gt_cams.size(); ++i)
    for (size_t j = i + 1; j < gt_cams.size(); ++j) {
      const double gt =
          (gt_cams[i]->rig_from_cam.translation() - gt_cams[j]->rig_from_cam.translation()).norm();
      dot += gt * (est_cams[i]->rig_from_cam.translation() - est_cams[j]->rig_from_cam.translation()).norm();
      gt_sq += gt * gt;
    }
  if (gt_sq > 0) r.scale_error = dot / gt_sq - 1.0;
}

// The map's markers against the truth's (ids must belong to it): r's marker errors, the rigid alignment of
// the object frames (on the corners) and the configuration error.
void EvaluateMarkers(const GroundTruth& truth, const RigMap& map, EvalResult* out) {
  EvalResult& r = *out;
  std::vector<const SimMarker*> gt_marks;
  std::vector<const MapMarker*> est_marks;
  for (const MapMarker& m : map.markers) {
    const SimMarker* g = truth.FindMarker(m.id);
    if (!g) {
      std::string ids;
      for (const auto& t : truth.markers) ids += (ids.empty() ? "" : ", ") + std::to_string(t.id);
      throw EvalInputError("marker id " + std::to_string(m.id) +
                           " of the map is not in the ground truth (ids: " + ids + ")");
    }
    gt_marks.push_back(g);
    est_marks.push_back(&m);
  }
  if (gt_marks.empty()) throw EvalInputError("the map has no marker");
  for (const SimMarker& m : truth.markers)
    if (!map.FindMarker(m.id)) r.missing_markers.push_back(m.id);
  r.mapped_markers = static_cast<int>(gt_marks.size());
  std::vector<Eigen::Vector3d> est_corners, gt_corners;
  for (size_t i = 0; i < gt_marks.size(); ++i) {
    const MarkerCorners3d ce = MarkerCornersInMarker(est_marks[i]->size);
    const MarkerCorners3d cg = MarkerCornersInMarker(gt_marks[i]->size);
    for (int k = 0; k < 4; ++k) {
      est_corners.push_back(est_marks[i]->object_from_marker * ce[k]);
      gt_corners.push_back(gt_marks[i]->object_from_marker * cg[k]);
    }
  }
  r.gt_object_from_est_object = AlignRigid(est_corners, gt_corners);
  const Rigid3& B = r.gt_object_from_est_object;
  std::vector<double> conf;
  for (size_t i = 0; i < gt_marks.size(); ++i) {
    MarkerError e;
    e.id = gt_marks[i]->id;
    double sum = 0;
    for (int k = 0; k < 4; ++k) {
      const double d = 1000.0 * (B * est_corners[4 * i + k] - gt_corners[4 * i + k]).norm();
      conf.push_back(d);
      sum += d;
    }
    e.corner_mm = sum / 4;
    e.size_mm = 1000.0 * (est_marks[i]->size - gt_marks[i]->size);
    r.markers.push_back(e);
  }
  r.configuration_mm = ComputeStats(conf);
}

// The object's poses in `trajectory` against the truth's frames (seqs must belong to it), through both
// alignments; a seq given twice counts once (the first).
void EvaluatePoses(const GroundTruth& truth, const std::vector<TrajectoryRow>& trajectory, EvalResult* out) {
  EvalResult& r = *out;
  const Rigid3& A = r.gt_rig_from_est_rig;
  const Rigid3& B = r.gt_object_from_est_object;
  r.has_trajectory = true;
  std::map<int64_t, const SimFrame*> by_seq;
  for (const SimFrame& f : truth.frames) by_seq[f.seq] = &f;
  std::set<int64_t> seen;
  std::vector<double> trans, rot;
  std::vector<double> status_trans[2], status_rot[2];  // [ambiguous]
  int beyond_position = 0, beyond_rotation = 0;
  std::vector<Eigen::Vector3d> est_pos, gt_pos;
  std::vector<double> sigma_mm;  // per est_pos: the row's finite position sigma, else NAN
  const Rigid3 B_inv = Inverse(B);
  for (const TrajectoryRow& row : trajectory) {
    auto it = by_seq.find(row.seq);
    if (it == by_seq.end())
      throw EvalInputError("trajectory seq " + std::to_string(row.seq) + " is not a ground-truth frame (0.." +
                           std::to_string(truth.frames.empty() ? -1 : truth.frames.back().seq) + ")");
    if (!seen.insert(row.seq).second) continue;  // duplicate: first one counts
    const Rigid3& gt = it->second->rig_from_object;
    const Rigid3 est = A * row.rig_from_object * B_inv;
    trans.push_back(1000.0 * TranslationDistance(est, gt));
    rot.push_back(AngleDeg(est.linear(), gt.linear()));
    const std::optional<PoseQuality>& q = row.quality;
    const bool sigma = q && std::isfinite(q->sigma_position_m) && std::isfinite(q->sigma_rotation_rad);
    if (q) {
      ++r.frames_with_quality;
      status_trans[q->ambiguous].push_back(trans.back());
      status_rot[q->ambiguous].push_back(rot.back());
    }
    if (sigma) {
      ++r.frames_with_sigma;
      beyond_position += trans.back() > 3000.0 * q->sigma_position_m;
      beyond_rotation += rot.back() > 3.0 * q->sigma_rotation_rad * 180.0 / M_PI;
    }
    est_pos.push_back((row.rig_from_object * B_inv).translation());
    sigma_mm.push_back(sigma ? 1000.0 * q->sigma_position_m : NAN);
    gt_pos.push_back(gt.translation());
  }
  r.frames_with_pose = static_cast<int>(seen.size());
  r.object_translation_mm = ComputeStats(trans);
  r.object_rotation_deg = ComputeStats(rot);
  r.ambiguous_frames = static_cast<int>(status_trans[1].size());
  r.tracking_translation_mm = ComputeStats(status_trans[0]);
  r.tracking_rotation_deg = ComputeStats(status_rot[0]);
  r.ambiguous_translation_mm = ComputeStats(status_trans[1]);
  r.ambiguous_rotation_deg = ComputeStats(status_rot[1]);
  if (r.frames_with_sigma > 0) {
    r.beyond_3sigma_position = static_cast<double>(beyond_position) / r.frames_with_sigma;
    r.beyond_3sigma_rotation = static_cast<double>(beyond_rotation) / r.frames_with_sigma;
  }
  if (!est_pos.empty()) {
    const Rigid3 align = AlignRigid(est_pos, gt_pos);
    std::vector<double> d;
    for (size_t i = 0; i < est_pos.size(); ++i) d.push_back(1000.0 * (align * est_pos[i] - gt_pos[i]).norm());
    r.object_translation_aligned_mm = ComputeStats(d);
    if (r.frames_with_sigma > 0) {
      int beyond = 0;
      for (size_t i = 0; i < d.size(); ++i) beyond += std::isfinite(sigma_mm[i]) && d[i] > 3.0 * sigma_mm[i];
      r.beyond_3sigma_position_aligned = static_cast<double>(beyond) / r.frames_with_sigma;
    }
  }
}

}  // namespace

EvalResult Evaluate(const GroundTruth& session_truth, const RigMap* map,
                    const std::vector<TrajectoryRow>* trajectory) {
  const GroundTruth truth = TruthAtEnd(session_truth);  // a map holds every camera's latest pose
  EvalResult r;
  r.gt_cameras = static_cast<int>(truth.cameras.size());
  r.gt_markers = static_cast<int>(truth.markers.size());
  r.gt_frames = static_cast<int>(truth.frames.size());
  if (!map) throw EvalInputError("a map is required (--map)");
  r.has_map = true;
  r.map_rms_px = map->rms_px;
  // Marker ids only mean the same markers in the same dictionary. Dictionary files may be named by
  // different paths, so only two predefined names are compared.
  auto predefined = [](const std::string& d) { return d.rfind("DICT_", 0) == 0; };
  if (predefined(map->dictionary) && predefined(truth.dictionary) && map->dictionary != truth.dictionary)
    throw EvalInputError("the map's dictionary " + map->dictionary + " is not the ground truth's " +
                         truth.dictionary);

  EvaluateCameras(truth, *map, &r);
  EvaluateMarkers(truth, *map, &r);
  if (trajectory) EvaluatePoses(truth, *trajectory, &r);
  return r;
}

RigMap MapFromGroundTruth(const GroundTruth& truth, size_t ref_camera, size_t ref_marker,
                          std::vector<TrajectoryRow>* trajectory) {
  const Rigid3 est_from_gt_rig = Inverse(truth.cameras.at(ref_camera).rig_from_cam);
  const Rigid3 gt_object_from_est = truth.markers.at(ref_marker).object_from_marker;
  const Rigid3 est_from_gt_object = Inverse(gt_object_from_est);
  RigMap map;
  map.dictionary = truth.dictionary;
  map.reference_camera = truth.cameras[ref_camera].name;
  map.reference_marker = truth.markers[ref_marker].id;
  for (const SimCamera& c : truth.cameras) {
    MapCamera m;
    m.name = c.name;
    m.model = c.model;
    m.rig_from_cam = est_from_gt_rig * c.rig_from_cam;
    map.cameras.push_back(m);
  }
  for (const SimMarker& g : truth.markers) {
    MapMarker m;
    m.id = g.id;
    m.size = g.size;
    m.object_from_marker = est_from_gt_object * g.object_from_marker;
    map.markers.push_back(m);
  }
  if (trajectory)
    for (const SimFrame& f : truth.frames) {
      TrajectoryRow r;
      r.seq = f.seq;
      r.utime = f.utime;
      r.rig_from_object = est_from_gt_rig * f.rig_from_object * gt_object_from_est;
      trajectory->push_back(r);
    }
  return map;
}

std::vector<TrajectoryRow> ReadTrajectoryAny(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FileFormatError(path + ": cannot open the trajectory");
  unsigned char magic[4] = {0, 0, 0, 0};
  in.read(reinterpret_cast<char*>(magic), 4);
  in.close();
  const bool is_log = magic[0] == 0xED && magic[1] == 0xA1 && magic[2] == 0xDA && magic[3] == 0x01;
  if (!is_log) return ReadTrajectory(path);
  std::vector<TrajectoryRow> rows;
  int bad = 0;
  const LogReadReport report = ForEachLogEvent(path, [&](const LogEvent& ev) {
    if (ev.channel != kPoseChannel) return true;
    object_pose_t msg;
    if (!Decode(ev.data.data(), ev.data.size(), &msg)) {
      ++bad;
      return true;
    }
    if (msg.status == object_pose_t::STATUS_TRACKING || msg.status == object_pose_t::STATUS_AMBIGUOUS)
      rows.push_back(FromObjectPoseMsg(msg));
    return true;
  });
  if (report.damaged())  // what is readable would be judged as if it were the whole trajectory
    throw FileFormatError(path + ": " + report.Summary());
  if (rows.empty() && bad > 0)
    throw FileFormatError(path + ": " + std::to_string(bad) + " undecodable messages on " + kPoseChannel);
  return rows;
}

RigMap SelectObject(const RigMap& map, const std::string& object, const GroundTruth& truth,
                    std::vector<TrajectoryRow>* trajectory) {
  if (map.objects.empty()) {
    if (!object.empty())
      throw EvalInputError("--object " + object + ": the map holds one object (version 1)");
    return map;
  }
  std::string names;
  for (const MapObject& o : map.objects) names += (names.empty() ? "" : ", ") + o.name;
  if (object.empty())
    throw EvalInputError("the map holds several objects (" + names + "): name one with --object");
  const MapObject* found = map.FindObject(object);
  if (!found) throw EvalInputError("--object " + object + ": not in the map (objects: " + names + ")");
  if (found->is_static && trajectory->empty())
    for (const SimFrame& f : truth.frames) {
      TrajectoryRow row;
      row.utime = f.utime;
      row.seq = f.seq;
      row.rig_from_object = found->rig_from_object;
      trajectory->push_back(row);
    }
  return map.ObjectMap(static_cast<size_t>(found - map.objects.data()));
}

namespace {

void StatsLine(std::ostringstream& s, const std::string& name, const Stats& st) {
  std::string n = name;
  if (n.size() < 32) n += std::string(32 - n.size(), ' ');
  s << "| " << n << " | " << Fmt(st.mean) << std::string(std::max(0, 7 - (int)Fmt(st.mean).size()), ' ')
    << " | " << Fmt(st.median) << std::string(std::max(0, 7 - (int)Fmt(st.median).size()), ' ') << " | "
    << Fmt(st.max) << std::string(std::max(0, 7 - (int)Fmt(st.max).size()), ' ') << " |\n";
}

const char kStatsHeader[] =
    "| metric (after rigid alignment)   | mean    | median  | max     |\n"
    "|----------------------------------|---------|---------|---------|\n";

void PoseLines(std::ostringstream& s, const EvalResult& r, const std::string& what) {
  if (r.has_trajectory && r.object_rotation_deg.count > 0) {
    StatsLine(s, what + " rotation error (deg)", r.object_rotation_deg);
    StatsLine(s, what + " translation error (mm)", r.object_translation_mm);
  }
  if (r.ambiguous_frames > 0) {  // else the tracking poses are all of them
    StatsLine(s, "  tracking: rotation (deg)", r.tracking_rotation_deg);
    StatsLine(s, "  tracking: translation (mm)", r.tracking_translation_mm);
    StatsLine(s, "  ambiguous: rotation (deg)", r.ambiguous_rotation_deg);
    StatsLine(s, "  ambiguous: translation (mm)", r.ambiguous_translation_mm);
  }
}

// "poses with a status: ...": their count and the errors beyond 3 sigma (a tracker's trajectory only).
void CovarianceLine(std::ostringstream& s, const EvalResult& r) {
  if (r.frames_with_quality == 0) return;
  s << "poses with a status: " << r.frames_with_quality << " (" << r.ambiguous_frames << " ambiguous)";
  if (r.frames_with_sigma > 0)
    s << "; error beyond 3 sigma: position " << Fmt(100.0 * r.beyond_3sigma_position, 1) << " %, rotation "
      << Fmt(100.0 * r.beyond_3sigma_rotation, 1)
      << " % of poses (a right covariance: at most 2.9 %; without the map's covariance it holds the map "
         "fixed); position after the trajectory's own alignment "
      << Fmt(100.0 * r.beyond_3sigma_position_aligned, 1) << " %";
  s << "\n";
}

void CameraTable(std::ostringstream& s, const EvalResult& r) {
  s << "\n| camera | position error (mm) | rotation error (deg) "
       "|\n|--------|--------------------|----------------------|\n";
  for (const auto& c : r.cameras)
    s << "| " << c.name << " | " << Fmt(c.position_mm) << " | " << Fmt(c.rotation_deg, 4) << " |\n";
}

void MarkerTable(std::ostringstream& s, const EvalResult& r) {
  s << "\n| marker | corner error (mm) | size error (mm) "
       "|\n|--------|-------------------|-----------------|\n";
  for (const auto& m : r.markers)
    s << "| " << m.id << " | " << Fmt(m.corner_mm) << " | " << Fmt(m.size_mm) << " |\n";
}

void CamerasMapped(std::ostringstream& s, const EvalResult& r) {
  s << "cameras mapped: " << r.mapped_cameras << " / " << r.gt_cameras;
  if (!r.missing_cameras.empty()) {
    s << " (missing:";
    for (const auto& n : r.missing_cameras) s << " " << n;
    s << ")";
  }
  if (!std::isnan(r.scale_error))
    s << ", metric scale error " << (r.scale_error >= 0 ? "+" : "") << Fmt(100.0 * r.scale_error) << " %";
}

void MarkersMapped(std::ostringstream& s, const EvalResult& r) {
  s << "markers mapped: " << r.mapped_markers << " / " << r.gt_markers;
  if (!r.missing_markers.empty()) {
    s << " (missing:";
    for (int id : r.missing_markers) s << " " << id;
    s << ")";
  }
}

void FramesWithPose(std::ostringstream& s, const EvalResult& r) {
  const double frac = r.gt_frames > 0 ? 100.0 * r.frames_with_pose / r.gt_frames : 0.0;
  s << "frames with a pose: " << r.frames_with_pose << " / " << r.gt_frames << " (" << Fmt(frac, 1)
    << " %)\n";
}

std::string JsonCameras(const EvalResult& r) {
  std::ostringstream s;
  s << "{\"ground_truth\": " << r.gt_cameras << ", \"mapped\": " << r.mapped_cameras << ", \"missing\": [";
  for (size_t i = 0; i < r.missing_cameras.size(); ++i)
    s << (i ? ", " : "") << JsonString(r.missing_cameras[i]);
  s << "],\n    \"scale_error_pct\": " << JsonNumber(100.0 * r.scale_error)
    << ",\n    \"position_mm\": " << JsonStats(r.camera_position_mm)
    << ",\n    \"rotation_deg\": " << JsonStats(r.camera_rotation_deg) << ",\n    \"per_camera\": [";
  for (size_t i = 0; i < r.cameras.size(); ++i)
    s << (i ? ", " : "") << "{\"name\": " << JsonString(r.cameras[i].name)
      << ", \"position_mm\": " << JsonNumber(r.cameras[i].position_mm)
      << ", \"rotation_deg\": " << JsonNumber(r.cameras[i].rotation_deg) << "}";
  s << "]}";
  return s.str();
}

std::string JsonMarkers(const EvalResult& r) {
  std::ostringstream s;
  s << "{\"ground_truth\": " << r.gt_markers << ", \"mapped\": " << r.mapped_markers << ", \"missing\": [";
  for (size_t i = 0; i < r.missing_markers.size(); ++i) s << (i ? ", " : "") << r.missing_markers[i];
  s << "],\n    \"configuration_mm\": " << JsonStats(r.configuration_mm) << ",\n    \"per_marker\": [";
  for (size_t i = 0; i < r.markers.size(); ++i)
    s << (i ? ", " : "") << "{\"id\": " << r.markers[i].id
      << ", \"corner_mm\": " << JsonNumber(r.markers[i].corner_mm)
      << ", \"size_mm\": " << JsonNumber(r.markers[i].size_mm) << "}";
  s << "]}";
  return s.str();
}

std::string JsonObject(const EvalResult& r) {
  if (!r.has_trajectory) return "null";
  std::ostringstream s;
  s << "{\"ground_truth_frames\": " << r.gt_frames << ", \"frames_with_pose\": " << r.frames_with_pose
    << ", \"fraction_with_pose\": "
    << JsonNumber(r.gt_frames ? double(r.frames_with_pose) / r.gt_frames : 0.0)
    << ",\n    \"translation_mm\": " << JsonStats(r.object_translation_mm)
    << ",\n    \"rotation_deg\": " << JsonStats(r.object_rotation_deg)
    << ",\n    \"translation_mm_trajectory_aligned\": " << JsonStats(r.object_translation_aligned_mm);
  if (r.frames_with_quality > 0)
    s << ",\n    \"frames_with_status\": " << r.frames_with_quality
      << ", \"ambiguous_frames\": " << r.ambiguous_frames
      << ",\n    \"tracking\": {\"translation_mm\": " << JsonStats(r.tracking_translation_mm)
      << ", \"rotation_deg\": " << JsonStats(r.tracking_rotation_deg) << "}"
      << ",\n    \"ambiguous\": {\"translation_mm\": " << JsonStats(r.ambiguous_translation_mm)
      << ", \"rotation_deg\": " << JsonStats(r.ambiguous_rotation_deg) << "}"
      << ",\n    \"beyond_3_sigma\": {\"frames\": " << r.frames_with_sigma
      << ", \"position\": " << JsonNumber(r.beyond_3sigma_position)
      << ", \"rotation\": " << JsonNumber(r.beyond_3sigma_rotation)
      << ", \"position_trajectory_aligned\": " << JsonNumber(r.beyond_3sigma_position_aligned) << "}";
  s << "}";
  return s.str();
}

}  // namespace

std::string FormatTable(const EvalResult& r) {
  std::ostringstream s;
  s << kStatsHeader;
  PoseLines(s, r, "object");
  StatsLine(s, "camera position error (mm)", r.camera_position_mm);
  StatsLine(s, "object configuration error (mm)", r.configuration_mm);
  StatsLine(s, "camera rotation error (deg)", r.camera_rotation_deg);
  if (r.has_trajectory && r.object_translation_aligned_mm.count > 0)
    StatsLine(s, "object transl. (traj. Horn) (mm)", r.object_translation_aligned_mm);
  s << "\n";
  CamerasMapped(s, r);
  s << "; ";
  MarkersMapped(s, r);
  s << "; map RMS reprojection error " << Fmt(r.map_rms_px) << " px\n";
  if (r.has_trajectory) FramesWithPose(s, r);
  CovarianceLine(s, r);
  CameraTable(s, r);
  MarkerTable(s, r);
  return s.str();
}

std::string FormatJson(const EvalResult& r) {
  std::ostringstream s;
  s << "{\n";
  s << "  \"cameras\": " << JsonCameras(r) << ",\n";
  s << "  \"markers\": " << JsonMarkers(r) << ",\n";
  s << "  \"map_rms_px\": " << JsonNumber(r.map_rms_px) << ",\n";
  s << "  \"object\": " << JsonObject(r) << "\n";
  s << "}\n";
  return s.str();
}

std::vector<BodyResult> EvaluateBodies(
    const std::map<std::string, GroundTruth>& truths, const RigMap& map,
    const std::map<std::string, std::vector<TrajectoryRow>>* trajectories) {
  if (map.objects.empty())
    throw EvalInputError("the map holds one object (version 1): no bodies to evaluate");
  std::vector<BodyResult> out;
  for (const MapObject& o : map.objects) {
    auto truth = truths.find(o.name);
    if (truth == truths.end()) throw EvalInputError("body '" + o.name + "' of the map has no ground truth");
    std::vector<TrajectoryRow> trajectory;
    bool with_poses = o.is_static;
    if (!o.is_static && trajectories) {
      auto t = trajectories->find(o.name);
      if (t != trajectories->end()) {
        trajectory = t->second;
        with_poses = true;
      }
    }
    BodyResult b;
    b.name = o.name;
    b.is_static = o.is_static;
    const RigMap own = SelectObject(map, o.name, truth->second, &trajectory);
    try {
      b.result = Evaluate(truth->second, &own, with_poses ? &trajectory : nullptr);
    } catch (const EvalInputError& e) {
      throw EvalInputError("body '" + o.name + "': " + e.what());
    }
    out.push_back(std::move(b));
  }
  return out;
}

std::map<std::string, GroundTruth> ReadBodyTruths(const std::string& ground_truth, const RigMap& map) {
  const size_t slash = ground_truth.find_last_of('/');
  const std::string dir = slash == std::string::npos ? "." : ground_truth.substr(0, slash);
  std::map<std::string, GroundTruth> out;
  for (const MapObject& o : map.objects) {
    const std::string path = dir + "/ground_truth_" + o.name + ".yaml";
    std::ifstream probe(path);
    if (!probe)
      throw EvalInputError(path + ": no ground truth for body '" + o.name +
                           "' (mcmt-sim --scene bodies writes one per body beside ground_truth.yaml)");
    out[o.name] = ReadGroundTruth(path);
  }
  return out;
}

std::map<std::string, std::vector<TrajectoryRow>> ReadBodyTrajectories(const std::string& path,
                                                                       const RigMap& map) {
  std::map<std::string, std::vector<TrajectoryRow>> out;
  std::ifstream in(path, std::ios::binary);
  unsigned char magic[4] = {0, 0, 0, 0};
  const bool readable = static_cast<bool>(in.read(reinterpret_cast<char*>(magic), 4));
  const bool is_log =
      readable && magic[0] == 0xED && magic[1] == 0xA1 && magic[2] == 0xDA && magic[3] == 0x01;
  if (!is_log) {
    for (const auto& [body, file] : BodyTrajectoryFiles(path, map)) out[body] = ReadTrajectory(file);
    return out;
  }
  int bad = 0;
  const LogReadReport report = ForEachLogEvent(path, [&](const LogEvent& ev) {
    // Every pose stream but the single object's MCMT_POSE, by type (tracker.channels may rename them).
    if (ev.channel == kPoseChannel || !HasType<object_pose_t>(ev.data.data(), ev.data.size())) return true;
    object_pose_t msg;
    if (!Decode(ev.data.data(), ev.data.size(), &msg)) {
      ++bad;
      return true;
    }
    if (msg.status == object_pose_t::STATUS_TRACKING || msg.status == object_pose_t::STATUS_AMBIGUOUS)
      out[BodyOfPose(ev.channel, msg.object)].push_back(FromObjectPoseMsg(msg));
    return true;
  });
  if (report.damaged()) throw FileFormatError(path + ": " + report.Summary());
  if (out.empty())
    throw FileFormatError(path + ": no pose on " + kPoseChannel + "_<BODY>" +
                          (bad > 0 ? " (" + std::to_string(bad) + " undecodable messages)" : ""));
  return out;
}

std::string FormatBodiesTable(const std::vector<BodyResult>& bodies) {
  std::ostringstream s;
  if (bodies.empty()) return "";
  const EvalResult& first = bodies.front().result;
  s << "## cameras\n\n" << kStatsHeader;
  StatsLine(s, "camera position error (mm)", first.camera_position_mm);
  StatsLine(s, "camera rotation error (deg)", first.camera_rotation_deg);
  s << "\n";
  CamerasMapped(s, first);
  s << "; map RMS reprojection error " << Fmt(first.map_rms_px) << " px\n";
  CameraTable(s, first);
  for (const BodyResult& b : bodies) {
    const EvalResult& r = b.result;
    s << "\n## body " << b.name << (b.is_static ? " (static)" : " (moving)") << "\n\n" << kStatsHeader;
    StatsLine(s, "layout error (mm)", r.configuration_mm);
    PoseLines(s, r, b.is_static ? "static" : "pose");
    if (!b.is_static && r.has_trajectory && r.object_translation_aligned_mm.count > 0)
      StatsLine(s, "pose transl. (traj. Horn) (mm)", r.object_translation_aligned_mm);
    s << "\n";
    MarkersMapped(s, r);
    s << "\n";
    if (!b.is_static) {
      if (r.has_trajectory) {
        FramesWithPose(s, r);
        CovarianceLine(s, r);
      } else
        s << "poses: not evaluated (give --trajectory OUTDIR or a log of MCMT_POSE_" << ChannelSuffix(b.name)
          << ")\n";
    }
    MarkerTable(s, r);
  }
  return s.str();
}

std::string FormatBodiesJson(const std::vector<BodyResult>& bodies) {
  std::ostringstream s;
  s << "{\n";
  if (!bodies.empty()) {
    s << "  \"cameras\": " << JsonCameras(bodies.front().result) << ",\n";
    s << "  \"map_rms_px\": " << JsonNumber(bodies.front().result.map_rms_px) << ",\n";
  }
  s << "  \"bodies\": [";
  for (size_t i = 0; i < bodies.size(); ++i) {
    const BodyResult& b = bodies[i];
    s << (i ? ",\n" : "\n") << "   {\"name\": " << JsonString(b.name)
      << ", \"static\": " << (b.is_static ? "true" : "false")
      << ",\n    \"markers\": " << JsonMarkers(b.result) << ",\n    \"poses\": " << JsonObject(b.result)
      << "}";
  }
  s << "]\n}\n";
  return s.str();
}

}  // namespace sim
}  // namespace mcmt
