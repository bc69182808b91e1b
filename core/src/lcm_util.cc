#include "core/lcm_util.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <memory>

namespace mcmt {
namespace {

std::string ChannelSuffix(const std::string& camera_name) {
  std::string out = camera_name;
  for (char& c : out) {
    const unsigned char u = static_cast<unsigned char>(c);
    c = std::isalnum(u) || c == '_' ? static_cast<char>(std::toupper(u)) : '_';
  }
  return out;
}

}  // namespace

std::string DetectionsChannel(const std::string& camera_name) {
  return kDetectionsChannelPrefix + ChannelSuffix(camera_name);
}

std::string ImageChannel(const std::string& camera_name) {
  return kImageChannelPrefix + ChannelSuffix(camera_name);
}

pose3d_t ToPose3d(const Rigid3& a_from_b) {
  pose3d_t p;
  const auto q = QuaternionWxyz(a_from_b);
  for (int i = 0; i < 3; ++i) p.position[i] = a_from_b.translation()[i];
  for (int i = 0; i < 4; ++i) p.orientation[i] = q[i];
  return p;
}

Rigid3 FromPose3d(const pose3d_t& pose) {
  return RigidFromQuaternion(
      {pose.orientation[0], pose.orientation[1], pose.orientation[2], pose.orientation[3]},
      Eigen::Vector3d(pose.position[0], pose.position[1], pose.position[2]));
}

camera_model_t ToCameraModelMsg(const CameraModel& model) {
  camera_model_t msg;
  msg.width = model.width;
  msg.height = model.height;
  msg.fx = model.fx;
  msg.fy = model.fy;
  msg.cx = model.cx;
  msg.cy = model.cy;
  msg.distortion_model = DistortionModelName(model.model);
  msg.num_distortion = static_cast<int32_t>(model.distortion.size());
  msg.distortion = model.distortion;
  return msg;
}

CameraModel FromCameraModelMsg(const camera_model_t& msg) {
  CameraModel model;
  model.width = msg.width;
  model.height = msg.height;
  model.fx = msg.fx;
  model.fy = msg.fy;
  model.cx = msg.cx;
  model.cy = msg.cy;
  model.model = DistortionModelFromName(msg.distortion_model);
  model.distortion = msg.distortion;
  model.Validate();
  return model;
}

rig_map_t ToRigMapMsg(const RigMap& map, int64_t utime) {
  rig_map_t msg;
  msg.utime = utime;
  msg.version = map.version;
  msg.reference_camera = map.reference_camera;
  msg.reference_marker = map.reference_marker;
  msg.dictionary = map.dictionary;
  msg.num_cameras = static_cast<int32_t>(map.cameras.size());
  for (const auto& c : map.cameras) {
    msg.camera_names.push_back(c.name);
    msg.camera_models.push_back(ToCameraModelMsg(c.model));
    msg.rig_from_cam.push_back(ToPose3d(c.rig_from_cam));
  }
  msg.num_markers = static_cast<int32_t>(map.markers.size());
  for (const auto& m : map.markers) {
    msg.marker_ids.push_back(m.id);
    msg.marker_sizes.push_back(m.size);
    msg.object_from_marker.push_back(ToPose3d(m.object_from_marker));
  }
  msg.rms_px = map.rms_px;
  msg.num_frames = map.num_frames;
  msg.num_observations = map.num_observations;
  return msg;
}

RigMap FromRigMapMsg(const rig_map_t& msg) {
  RigMap map;
  map.version = msg.version;
  map.reference_camera = msg.reference_camera;
  map.reference_marker = msg.reference_marker;
  map.dictionary = msg.dictionary;
  for (int i = 0; i < msg.num_cameras; ++i) {
    MapCamera c;
    c.name = msg.camera_names[i];
    c.model = FromCameraModelMsg(msg.camera_models[i]);
    c.rig_from_cam = FromPose3d(msg.rig_from_cam[i]);
    map.cameras.push_back(c);
  }
  for (int i = 0; i < msg.num_markers; ++i) {
    MapMarker m;
    m.id = msg.marker_ids[i];
    m.size = msg.marker_sizes[i];
    m.object_from_marker = FromPose3d(msg.object_from_marker[i]);
    map.markers.push_back(m);
  }
  map.rms_px = msg.rms_px;
  map.num_frames = msg.num_frames;
  map.num_observations = msg.num_observations;
  return map;
}

MarkerCorners2d CornersOf(const marker_t& marker) {
  MarkerCorners2d c;
  for (int i = 0; i < 4; ++i) c[i] = Eigen::Vector2d(marker.corners[i][0], marker.corners[i][1]);
  return c;
}

std::string LogReadUrl(const std::string& log_path) {
  return "file://" + std::filesystem::absolute(log_path).lexically_normal().string() + "?speed=0";
}

std::unique_ptr<lcm::LCM> OpenLcm(const std::string& url) {
  auto lcm = std::make_unique<lcm::LCM>(url);
  if (!lcm->good()) {
    const std::string shown = url.empty() ? std::string("(LCM default)") : url;
    std::string hint;
    if (url.empty() || url.rfind("udpm://", 0) == 0)
      hint = " (for multicast without a network: ip route add 224.0.0.0/4 dev lo)";
    if (url.rfind("file://", 0) == 0) hint = " (is the log file readable?)";
    throw std::runtime_error("cannot open LCM url '" + shown + "'" + hint);
  }
  return lcm;
}

bool HandleUntil(lcm::LCM& lcm, const std::function<bool()>& done, std::chrono::milliseconds timeout,
                 std::chrono::milliseconds tick) {
  using Clock = std::chrono::steady_clock;
  const auto deadline = Clock::now() + timeout;
  if (tick.count() <= 0) tick = std::chrono::milliseconds(1);
  while (true) {
    if (done()) return true;
    const auto now = Clock::now();
    if (now >= deadline) return false;
    const auto remaining = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - now);
    const auto wait =
        std::max<std::chrono::milliseconds>(std::min(tick, remaining), std::chrono::milliseconds(1));
    const int status = lcm.handleTimeout(static_cast<int>(wait.count()));
    if (status < 0) return done();  // error or end of a file:// log
  }
}

int64_t NowUtime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace mcmt
