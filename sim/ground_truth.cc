// ground_truth.yaml: writing (exact, %.17g) and reading back.
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <sstream>
#include <stdexcept>

#include "core/files.h"
#include "sim/sim.h"

namespace mcmt {
namespace sim {

namespace {

std::string Num(double v) { return YamlNumber(v); }

std::string Pose(const Rigid3& pose) {
  const Eigen::Quaterniond q(pose.linear());
  Eigen::Vector4d wxyz(q.w(), q.x(), q.y(), q.z());
  if (wxyz[0] < 0) wxyz = -wxyz;
  const Eigen::Vector3d& t = pose.translation();
  return "{translation: [" + Num(t.x()) + ", " + Num(t.y()) + ", " + Num(t.z()) + "], rotation_wxyz: [" +
         Num(wxyz[0]) + ", " + Num(wxyz[1]) + ", " + Num(wxyz[2]) + ", " + Num(wxyz[3]) + "]}";
}

[[noreturn]] void Fail(const std::string& file, const std::string& key, const std::string& what) {
  throw std::runtime_error(file + ": " + key + ": " + what);
}

double GetNumber(const YAML::Node& node, const std::string& file, const std::string& key) {
  if (!node || !node.IsScalar()) Fail(file, key, "missing or not a number");
  try {
    return node.as<double>();
  } catch (const std::exception&) {
    Fail(file, key, "expected a number, got '" + node.Scalar() + "'");
  }
}

int64_t GetInt64(const YAML::Node& node, const std::string& file, const std::string& key) {
  if (!node || !node.IsScalar()) Fail(file, key, "missing or not an integer");
  try {
    return node.as<int64_t>();
  } catch (const std::exception&) {
    Fail(file, key, "expected an integer, got '" + node.Scalar() + "'");
  }
}

Rigid3 GetPose(const YAML::Node& node, const std::string& file, const std::string& key) {
  if (!node || !node.IsMap())
    Fail(file, key, "missing pose {translation: [x, y, z], rotation_wxyz: [w, x, y, z]}");
  const YAML::Node t = node["translation"], r = node["rotation_wxyz"];
  if (!t || !t.IsSequence() || t.size() != 3) Fail(file, key + ".translation", "expected 3 numbers");
  if (!r || !r.IsSequence() || r.size() != 4) Fail(file, key + ".rotation_wxyz", "expected 4 numbers");
  double v[7];
  for (int i = 0; i < 3; ++i) v[i] = GetNumber(t[i], file, key + ".translation");
  for (int i = 0; i < 4; ++i) v[3 + i] = GetNumber(r[i], file, key + ".rotation_wxyz");
  Eigen::Quaterniond q(v[3], v[4], v[5], v[6]);
  const double n = q.norm();
  if (!(n > 0.5 && n < 2.0)) Fail(file, key + ".rotation_wxyz", "not a unit quaternion");
  q.normalize();
  Rigid3 pose = Rigid3::Identity();
  pose.linear() = q.toRotationMatrix();
  pose.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
  return pose;
}

// moves: and late_cameras: (optional), naming cameras of the truth.
void ReadCameraChanges(const YAML::Node& root, const std::string& path, GroundTruth* truth) {
  auto camera = [&](const YAML::Node& n, const std::string& key) {
    if (!n || !n.IsScalar() || !truth->FindCamera(n.Scalar())) Fail(path, key, "missing or not a camera");
    return n.Scalar();
  };
  const YAML::Node moves = root["moves"];
  if (moves && !moves.IsSequence()) Fail(path, "moves", "expected a list");
  for (size_t i = 0; moves && i < moves.size(); ++i) {
    const std::string key = "moves[" + std::to_string(i) + "]";
    CameraMove m;
    m.camera = camera(moves[i]["camera"], key + ".camera");
    m.frame = GetInt64(moves[i]["frame"], path, key + ".frame");
    m.rotation_deg = GetNumber(moves[i]["rotation_deg"], path, key + ".rotation_deg");
    m.translation_mm = GetNumber(moves[i]["translation_mm"], path, key + ".translation_mm");
    m.rig_from_cam_after = GetPose(moves[i]["rig_from_cam_after"], path, key + ".rig_from_cam_after");
    truth->moves.push_back(m);
  }
  const YAML::Node late = root["late_cameras"];
  if (late && !late.IsSequence()) Fail(path, "late_cameras", "expected a list");
  for (size_t i = 0; late && i < late.size(); ++i) {
    const std::string key = "late_cameras[" + std::to_string(i) + "]";
    truth->late_cameras.push_back(
        {camera(late[i]["camera"], key + ".camera"), GetInt64(late[i]["frame"], path, key + ".frame")});
  }
  const YAML::Node clocks = root["clocks"];
  if (clocks && !clocks.IsMap()) Fail(path, "clocks", "expected a map of camera names");
  if (clocks)
    for (const auto& entry : clocks) {
      const std::string name = camera(entry.first, "clocks");
      const std::string key = "clocks." + name;
      truth->clocks[name] = {GetNumber(entry.second["offset_ms"], path, key + ".offset_ms"),
                             GetNumber(entry.second["drift_ppm"], path, key + ".drift_ppm")};
    }
}

}  // namespace

const SimCamera* GroundTruth::FindCamera(const std::string& name) const {
  for (const auto& c : cameras)
    if (c.name == name) return &c;
  return nullptr;
}

const SimMarker* GroundTruth::FindMarker(int id) const {
  for (const auto& m : markers)
    if (m.id == id) return &m;
  return nullptr;
}

void WriteGroundTruth(const std::string& path, const GroundTruth& truth) {
  std::ostringstream s;
  s << "# mcmt-sim ground truth. Rig frame: a world frame (origin at the centre of the camera circle, z "
       "up);\n"
       "# object frame: the object's body frame. Poses a_from_b map points of frame b into frame a.\n";
  s << "version: 1\n";
  s << "object: " << truth.object << "\n";
  s << "dictionary: " << truth.dictionary << "\n";
  s << "marker_size: " << Num(truth.marker_size) << "\n";
  s << "fps: " << Num(truth.fps) << "\n";
  s << "rig_frame: world\n";
  s << "cameras:\n";
  for (const SimCamera& c : truth.cameras) {
    const CameraModel& m = c.model;
    s << "  " << c.name << ":\n";
    s << "    rig_from_cam: " << Pose(c.rig_from_cam) << "\n";
    s << "    width: " << m.width << "\n    height: " << m.height << "\n";
    s << "    fx: " << Num(m.fx) << "\n    fy: " << Num(m.fy) << "\n    cx: " << Num(m.cx)
      << "\n    cy: " << Num(m.cy) << "\n";
    s << "    distortion_model: " << DistortionModelName(m.model) << "\n    distortion: [";
    for (size_t i = 0; i < m.distortion.size(); ++i) s << (i ? ", " : "") << Num(m.distortion[i]);
    s << "]\n";
  }
  s << "markers:\n";
  for (const SimMarker& m : truth.markers) {
    s << "  " << m.id << ": {size: " << Num(m.size) << ", object_from_marker: " << Pose(m.object_from_marker)
      << "}\n";
  }
  s << "frames:\n";
  for (const SimFrame& f : truth.frames)
    s << "  - {seq: " << f.seq << ", utime: " << f.utime << ", rig_from_object: " << Pose(f.rig_from_object)
      << "}\n";
  if (!truth.moves.empty()) s << "moves:\n";
  for (const CameraMove& m : truth.moves)
    s << "  - {camera: " << m.camera << ", frame: " << m.frame << ", rotation_deg: " << Num(m.rotation_deg)
      << ", translation_mm: " << Num(m.translation_mm)
      << ", rig_from_cam_after: " << Pose(m.rig_from_cam_after) << "}\n";
  if (!truth.late_cameras.empty()) s << "late_cameras:\n";
  for (const LateCamera& l : truth.late_cameras)
    s << "  - {camera: " << l.camera << ", frame: " << l.frame << "}\n";
  if (!truth.clocks.empty()) s << "clocks:\n";
  for (const auto& [camera, clock] : truth.clocks)
    s << "  " << camera << ": {offset_ms: " << Num(clock.offset_ms) << ", drift_ppm: " << Num(clock.drift_ppm)
      << "}\n";
  WriteFileAtomic(path, s.str());
}

GroundTruth ReadGroundTruth(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw std::runtime_error(path + ": cannot open the ground-truth file");
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(path + ": not valid YAML (" + e.msg + " at line " +
                             std::to_string(e.mark.line + 1) + ")");
  }
  if (!root.IsMap()) throw std::runtime_error(path + ": not a ground-truth file (expected a mapping)");
  GroundTruth truth;
  if (root["version"] && GetNumber(root["version"], path, "version") != 1)
    Fail(path, "version", "unsupported version '" + root["version"].Scalar() + "'");
  if (root["object"]) truth.object = root["object"].Scalar();
  if (root["dictionary"]) truth.dictionary = root["dictionary"].Scalar();
  truth.marker_size = GetNumber(root["marker_size"], path, "marker_size");
  if (root["fps"]) truth.fps = GetNumber(root["fps"], path, "fps");
  const YAML::Node cams = root["cameras"];
  if (!cams || !cams.IsMap() || cams.size() == 0) Fail(path, "cameras", "missing or empty");
  for (const auto& kv : cams) {
    SimCamera c;
    c.name = kv.first.Scalar();
    const std::string key = "cameras." + c.name;
    const YAML::Node n = kv.second;
    c.rig_from_cam = GetPose(n["rig_from_cam"], path, key + ".rig_from_cam");
    if (n["width"]) {
      c.model.width = static_cast<int>(GetInt64(n["width"], path, key + ".width"));
      c.model.height = static_cast<int>(GetInt64(n["height"], path, key + ".height"));
      c.model.fx = GetNumber(n["fx"], path, key + ".fx");
      c.model.fy = GetNumber(n["fy"], path, key + ".fy");
      c.model.cx = GetNumber(n["cx"], path, key + ".cx");
      c.model.cy = GetNumber(n["cy"], path, key + ".cy");
      if (n["distortion_model"]) {
        try {
          c.model.model = DistortionModelFromName(n["distortion_model"].Scalar());
        } catch (const std::exception& e) {
          Fail(path, key + ".distortion_model", e.what());
        }
      }
      if (n["distortion"] && n["distortion"].IsSequence())
        for (const auto& d : n["distortion"])
          c.model.distortion.push_back(GetNumber(d, path, key + ".distortion"));
    }
    truth.cameras.push_back(c);
  }
  const YAML::Node markers = root["markers"];
  if (!markers || !markers.IsMap() || markers.size() == 0) Fail(path, "markers", "missing or empty");
  for (const auto& kv : markers) {
    SimMarker m;
    const std::string key = "markers." + kv.first.Scalar();
    try {
      m.id = kv.first.as<int>();
    } catch (const std::exception&) {
      Fail(path, key, "marker ids must be integers");
    }
    m.size = kv.second["size"] ? GetNumber(kv.second["size"], path, key + ".size") : truth.marker_size;
    m.object_from_marker = GetPose(kv.second["object_from_marker"], path, key + ".object_from_marker");
    truth.markers.push_back(m);
    truth.marker_sizes[m.id] = m.size;
  }
  const YAML::Node frames = root["frames"];
  if (frames && !frames.IsSequence()) Fail(path, "frames", "expected a list");
  if (frames) {
    for (size_t i = 0; i < frames.size(); ++i) {
      const std::string key = "frames[" + std::to_string(i) + "]";
      SimFrame f;
      f.seq = GetInt64(frames[i]["seq"], path, key + ".seq");
      if (frames[i]["utime"]) f.utime = GetInt64(frames[i]["utime"], path, key + ".utime");
      f.rig_from_object = GetPose(frames[i]["rig_from_object"], path, key + ".rig_from_object");
      truth.frames.push_back(f);
    }
  }
  ReadCameraChanges(root, path, &truth);
  return truth;
}

}  // namespace sim
}  // namespace mcmt
