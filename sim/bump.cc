// Cameras that move during a session (a bumped tripod) or start publishing late (a camera added to a
// running rig): options, poses per frame, and the truth at the end of a session.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <sstream>
#include <stdexcept>

#include "core/math.h"
#include "core/se3.h"
#include "sim/sim.h"

namespace mcmt {
namespace sim {

namespace {
constexpr double kPi = 3.14159265358979323846;
}  // namespace

CameraMoveOptions ParseCameraMove(const std::string& text) {
  std::vector<std::string> parts;
  std::stringstream in(text);
  for (std::string part; std::getline(in, part, ',');) parts.push_back(part);
  auto bad = [&](const std::string& why) {
    throw std::invalid_argument("--move-camera: expected CAM,FRAME,ROT_DEG,TRANS_MM (e.g. cam2,150,0.5,3), " +
                                why + ": '" + text + "'");
  };
  if (parts.size() != 4 || parts[0].empty()) bad("got");
  CameraMoveOptions m;
  m.camera = parts[0];
  char* end = nullptr;
  const long long frame = std::strtoll(parts[1].c_str(), &end, 10);
  if (end == parts[1].c_str() || *end || frame < 0) bad("FRAME must be an integer >= 0");
  m.frame = frame;
  m.rotation_deg = std::strtod(parts[2].c_str(), &end);
  if (end == parts[2].c_str() || *end || !(std::fabs(m.rotation_deg) <= 45)) bad("ROT_DEG must be -45..45");
  m.translation_mm = std::strtod(parts[3].c_str(), &end);
  if (end == parts[3].c_str() || *end || !(std::fabs(m.translation_mm) <= 1000))
    bad("TRANS_MM must be -1000..1000");
  return m;
}

Rigid3 MovedRigFromCam(const Rigid3& rig_from_cam, double rotation_deg, double translation_mm) {
  Rigid3 before_from_after = Rigid3::Identity();
  before_from_after.linear() = RotationFromVector(Eigen::Vector3d(0, rotation_deg * kPi / 180.0, 0));
  before_from_after.translation() = Eigen::Vector3d(1e-3 * translation_mm, 0, 0);
  return rig_from_cam * before_from_after;
}

SimCamera MakeExtraCamera(const RigOptions& rig) {
  RigOptions doubled = rig;
  doubled.num_cameras = 2 * rig.num_cameras;  // camera 1 of a rig twice as dense: halfway cam0 -> cam1
  SimCamera camera = MakeRig(doubled).at(1);
  camera.name = "cam" + std::to_string(rig.num_cameras);
  return camera;
}

SimCamera CameraAtFrame(const SimCamera& camera, const GroundTruth& truth, int64_t seq) {
  SimCamera at = camera;
  for (const CameraMove& m : truth.moves)
    if (m.camera == camera.name && seq >= m.frame) at.rig_from_cam = m.rig_from_cam_after;
  return at;
}

bool CameraActive(const std::string& camera, const GroundTruth& truth, int64_t seq) {
  for (const LateCamera& l : truth.late_cameras)
    if (l.camera == camera && seq < l.frame) return false;
  return true;
}

GroundTruth TruthAtEnd(const GroundTruth& truth) {
  GroundTruth end = truth;
  const int64_t last = truth.frames.empty() ? INT64_MAX : truth.frames.back().seq;
  for (SimCamera& c : end.cameras) c = CameraAtFrame(c, truth, last);
  return end;
}

DatasetOptions DetectionsOnlySession(const std::string& dir, int frames, uint64_t seed) {
  DatasetOptions o;
  o.out_dir = dir;
  o.detections_only = true;
  o.rig.camera_height = 0.5 * o.rig.radius;
  o.rig.seed = seed;
  o.object.seed = seed;
  o.trajectory.frames = frames;
  o.trajectory.seed = seed;
  o.trajectory.position_radius = 0.15 * o.rig.radius;
  o.trajectory.vertical_range = 0.08 * o.rig.radius;
  return o;
}

void AddCameraChanges(const DatasetOptions& o, GroundTruth* truth) {
  if (o.add_camera_frame >= 0) {
    if (o.add_camera_frame >= o.trajectory.frames)
      throw std::invalid_argument("--add-camera: frame " + std::to_string(o.add_camera_frame) +
                                  " is not before the session's end (" + std::to_string(o.trajectory.frames) +
                                  " frames)");
    truth->cameras.push_back(MakeExtraCamera(o.rig));
    if (o.add_camera_frame > 0)
      truth->late_cameras.push_back({truth->cameras.back().name, o.add_camera_frame});
  }
  for (const CameraMoveOptions& m : o.moves) {
    const SimCamera* camera = truth->FindCamera(m.camera);
    if (!camera) throw std::invalid_argument("--move-camera: no camera named '" + m.camera + "'");
    if (m.frame >= o.trajectory.frames)
      throw std::invalid_argument("--move-camera " + m.camera + ": frame " + std::to_string(m.frame) +
                                  " is not before the session's end (" + std::to_string(o.trajectory.frames) +
                                  " frames)");
    CameraMove move;
    move.camera = m.camera;
    move.frame = m.frame;
    move.rotation_deg = m.rotation_deg;
    move.translation_mm = m.translation_mm;
    move.rig_from_cam_after = MovedRigFromCam(CameraAtFrame(*camera, *truth, m.frame).rig_from_cam,
                                              m.rotation_deg, m.translation_mm);
    truth->moves.push_back(move);
  }
}

}  // namespace sim
}  // namespace mcmt
