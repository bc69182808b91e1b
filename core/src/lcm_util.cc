#include "core/lcm_util.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <memory>
#include <set>
#include <stdexcept>

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

// Walks an encoded LCM message (big-endian, strings as int32 length incl. NUL + bytes) checking
// that every length fits in the bytes present. Mirrors the field order of lcmtypes/*.lcm.
class WireReader {
 public:
  WireReader(const void* data, size_t size) : data_(static_cast<const uint8_t*>(data)), size_(size) {}

  bool Fixed(size_t bytes, const char* what) {
    if (size_ - pos_ < bytes) return Fail(std::string("truncated at ") + what);
    pos_ += bytes;
    return true;
  }
  bool Int32(int32_t* v, const char* what) {
    if (size_ - pos_ < 4) return Fail(std::string("truncated at ") + what);
    const uint8_t* b = data_ + pos_;
    *v = static_cast<int32_t>((uint32_t(b[0]) << 24) | (uint32_t(b[1]) << 16) | (uint32_t(b[2]) << 8) |
                              uint32_t(b[3]));
    pos_ += 4;
    return true;
  }
  bool Count(int32_t* n, size_t min_element_bytes, const char* what) {
    if (!Int32(n, what)) return false;
    if (*n < 0) return Fail(std::string("negative length ") + std::to_string(*n) + " of " + what);
    if (static_cast<uint64_t>(*n) * min_element_bytes > size_ - pos_)
      return Fail(std::string("length ") + std::to_string(*n) + " of " + what + " exceeds the message");
    return true;
  }
  bool String(const char* what) {
    int32_t len = 0;
    if (!Int32(&len, what)) return false;
    if (len < 1 || static_cast<uint64_t>(len) > size_ - pos_)
      return Fail(std::string("bad string length ") + std::to_string(len) + " of " + what);
    pos_ += static_cast<size_t>(len);
    return true;
  }
  bool Hash(int64_t expected) {
    if (size_ < 8) return Fail("shorter than a fingerprint");
    uint64_t h = 0;
    for (int i = 0; i < 8; ++i) h = (h << 8) | data_[i];
    if (static_cast<int64_t>(h) != expected) return Fail("fingerprint mismatch (another message type?)");
    pos_ = 8;
    return true;
  }
  bool End() {
    if (pos_ != size_) return Fail("trailing bytes");
    return true;
  }
  bool Fail(const std::string& why) {
    if (error_.empty()) error_ = why;
    return false;
  }
  const std::string& error() const { return error_; }

 private:
  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
  std::string error_;
};

bool CameraModelBody(WireReader& r) {
  int32_t n = 0;
  return r.Fixed(4 + 4 + 4 * 8, "camera_model_t.width..cy") && r.String("distortion_model") &&
         r.Count(&n, 8, "distortion") && r.Fixed(8 * static_cast<size_t>(n), "distortion");
}
bool MarkerBody(WireReader& r) { return r.Fixed(4 + 8 * 8, "marker_t"); }
bool Pose3dBody(WireReader& r) { return r.Fixed(8 * 7, "pose3d_t"); }
constexpr size_t kMinCameraModelBytes = 4 + 4 + 32 + 5 + 4;
constexpr size_t kMarkerBytes = 4 + 64;
constexpr size_t kPoseBytes = 56;

bool DetectionsBody(WireReader& r) {
  int32_t n = 0;
  if (!(r.Fixed(16, "utime, seq") && r.String("camera") && r.String("dictionary") && CameraModelBody(r) &&
        r.Count(&n, kMarkerBytes, "markers")))
    return false;
  for (int32_t i = 0; i < n; ++i)
    if (!MarkerBody(r)) return false;
  return r.Fixed(8, "detection_ms");
}

bool RigMapBody(WireReader& r) {
  int32_t nc = 0, nm = 0;
  if (!(r.Fixed(12, "utime, version") && r.String("reference_camera") && r.Fixed(4, "reference_marker") &&
        r.String("dictionary") && r.Count(&nc, 5 + kMinCameraModelBytes + kPoseBytes, "cameras")))
    return false;
  for (int32_t i = 0; i < nc; ++i)
    if (!r.String("camera_names")) return false;
  for (int32_t i = 0; i < nc; ++i)
    if (!CameraModelBody(r)) return false;
  for (int32_t i = 0; i < nc; ++i)
    if (!Pose3dBody(r)) return false;
  if (!r.Count(&nm, 4 + 8 + kPoseBytes, "markers")) return false;
  if (!r.Fixed(12 * static_cast<size_t>(nm), "marker_ids, marker_sizes")) return false;
  for (int32_t i = 0; i < nm; ++i)
    if (!Pose3dBody(r)) return false;
  return r.Fixed(16, "rms_px, num_frames, num_observations");
}

bool ObjectLayoutBody(WireReader& r) {
  int32_t nm = 0;
  if (!(r.String("object_layout_t.name") && r.Fixed(1 + 4, "is_static, reference_marker") &&
        r.Count(&nm, 4 + 8 + kPoseBytes, "object_layout_t.markers") &&
        r.Fixed(12 * static_cast<size_t>(nm), "marker_ids, marker_sizes")))
    return false;
  for (int32_t i = 0; i < nm; ++i)
    if (!Pose3dBody(r)) return false;
  return Pose3dBody(r) && r.Fixed(16, "object_layout_t.rms_px, num_frames, num_observations");
}
// An object_layout_t holds at least its name (5), the fixed fields and a pose.
constexpr size_t kMinObjectLayoutBytes = 5 + 1 + 4 + 4 + kPoseBytes + 16;

bool RigMap2Body(WireReader& r) {
  int32_t nc = 0, no = 0;
  if (!(r.Fixed(12, "utime, version") && r.String("reference_camera") && r.String("dictionary") &&
        r.String("rig_frame") && r.Count(&nc, 5 + kMinCameraModelBytes + kPoseBytes + 16, "cameras")))
    return false;
  for (int32_t i = 0; i < nc; ++i)
    if (!r.String("camera_names")) return false;
  for (int32_t i = 0; i < nc; ++i)
    if (!CameraModelBody(r)) return false;
  for (int32_t i = 0; i < nc; ++i)
    if (!Pose3dBody(r)) return false;
  if (!r.Fixed(16 * static_cast<size_t>(nc) + 8, "time_offset_us, time_drift_ppm, time_reference_utime"))
    return false;
  if (!r.Count(&no, kMinObjectLayoutBytes, "objects")) return false;
  for (int32_t i = 0; i < no; ++i)
    if (!ObjectLayoutBody(r)) return false;
  return r.Fixed(16, "rms_px, num_frames, num_observations");
}

bool ObjectPoseBody(WireReader& r) {
  int32_t nc = 0, nm = 0;
  if (!(r.Fixed(16, "utime, seq") && r.String("object") && Pose3dBody(r) &&
        r.Fixed(36 * 8 + 8, "covariance, rms_px") && r.Count(&nc, 5, "cameras")))
    return false;
  for (int32_t i = 0; i < nc; ++i)
    if (!r.String("cameras")) return false;
  return r.Count(&nm, 4, "markers") && r.Fixed(4 * static_cast<size_t>(nm), "markers") &&
         r.Fixed(4 + 1 + 8, "num_rejected, status, latency_ms");
}

template <typename Msg>
bool CheckTop(const void* data, size_t size, bool (*body)(WireReader&), std::string* error) {
  WireReader r(data, size);
  const bool ok = r.Hash(Msg::getHash()) && body(r) && r.End();
  if (!ok && error) *error = r.error();
  return ok;
}

}  // namespace

bool CheckEncoded(const void* data, size_t size, const camera_model_t*, std::string* error) {
  return CheckTop<camera_model_t>(data, size, CameraModelBody, error);
}
bool CheckEncoded(const void* data, size_t size, const marker_t*, std::string* error) {
  return CheckTop<marker_t>(data, size, MarkerBody, error);
}
bool CheckEncoded(const void* data, size_t size, const detections_t*, std::string* error) {
  return CheckTop<detections_t>(data, size, DetectionsBody, error);
}
bool CheckEncoded(const void* data, size_t size, const pose3d_t*, std::string* error) {
  return CheckTop<pose3d_t>(data, size, Pose3dBody, error);
}
bool CheckEncoded(const void* data, size_t size, const rig_map_t*, std::string* error) {
  return CheckTop<rig_map_t>(data, size, RigMapBody, error);
}
bool CheckEncoded(const void* data, size_t size, const object_layout_t*, std::string* error) {
  return CheckTop<object_layout_t>(data, size, ObjectLayoutBody, error);
}
bool CheckEncoded(const void* data, size_t size, const rig_map2_t*, std::string* error) {
  return CheckTop<rig_map2_t>(data, size, RigMap2Body, error);
}
bool CheckEncoded(const void* data, size_t size, const object_pose_t*, std::string* error) {
  return CheckTop<object_pose_t>(data, size, ObjectPoseBody, error);
}
bool CheckEncoded(const void* data, size_t size, const mapper_status_t*, std::string* error) {
  return CheckTop<mapper_status_t>(
      data, size,
      [](WireReader& r) { return r.Fixed(8 + 1 + 6 * 4 + 16, "mapper_status_t") && r.String("message"); },
      error);
}
bool CheckEncoded(const void* data, size_t size, const mapper_command_t*, std::string* error) {
  return CheckTop<mapper_command_t>(
      data, size, [](WireReader& r) { return r.Fixed(8, "utime") && r.String("command"); }, error);
}

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

bool IsDetectionsChannel(const std::string& channel) {
  return channel.rfind(kDetectionsChannelPrefix, 0) == 0;
}

std::string DetectionsProblem(const detections_t& msg, const std::string& channel) {
  const std::string who = "camera '" + msg.camera + "' on " + channel;
  if (msg.camera.empty()) return "a detections message on " + channel + " has no camera name";
  if (DetectionsChannel(msg.camera) != channel)
    return who + ": the message's camera field belongs on " + DetectionsChannel(msg.camera) +
           " (camera field and channel disagree)";
  try {
    FromCameraModelMsg(msg.camera_model);
  } catch (const std::exception& e) {
    return who + ": invalid camera model in the message: " + e.what();
  }
  return "";
}

int DropInvalidMarkers(detections_t* msg, std::vector<int>* dropped_ids) {
  constexpr double kMaxPixel = 1e6;
  const size_t before = msg->markers.size();
  auto bad = [&](const marker_t& m) {
    for (const auto& c : m.corners)
      for (double v : c)
        if (!std::isfinite(v) || std::abs(v) > kMaxPixel) {
          if (dropped_ids) dropped_ids->push_back(m.id);
          return true;
        }
    return false;
  };
  msg->markers.erase(std::remove_if(msg->markers.begin(), msg->markers.end(), bad), msg->markers.end());
  msg->num_markers = static_cast<int32_t>(msg->markers.size());
  return static_cast<int>(before - msg->markers.size());
}

bool DuplicateFilter::Repeated(const detections_t& msg) {
  auto& seen = seen_[msg.camera];
  if (!seen.insert({msg.utime, msg.seq}).second) {
    ++count_;
    if (examples_.size() < 20)
      examples_.push_back("camera " + msg.camera + " seq " + std::to_string(msg.seq) + " utime " +
                          std::to_string(msg.utime));
    return true;
  }
  if (seen.size() > window_) seen.erase(seen.begin());
  return false;
}

namespace {

// rig_map_t and rig_map2_t hold the cameras with the same field names, rig_map_t and object_layout_t the
// markers: one conversion each, for both.
template <class Msg>
void AddCamerasToMsg(const RigMap& map, Msg* msg) {
  msg->num_cameras = static_cast<int32_t>(map.cameras.size());
  for (const auto& c : map.cameras) {
    msg->camera_names.push_back(c.name);
    msg->camera_models.push_back(ToCameraModelMsg(c.model));
    msg->rig_from_cam.push_back(ToPose3d(c.rig_from_cam));
  }
}

template <class Msg>
std::vector<MapCamera> CamerasFromMsg(const Msg& msg) {
  std::vector<MapCamera> cameras;
  for (int i = 0; i < msg.num_cameras; ++i) {
    MapCamera c;
    c.name = msg.camera_names[i];
    c.model = FromCameraModelMsg(msg.camera_models[i]);
    c.rig_from_cam = FromPose3d(msg.rig_from_cam[i]);
    cameras.push_back(c);
  }
  return cameras;
}

template <class Msg>
void AddMarkersToMsg(const std::vector<MapMarker>& markers, Msg* msg) {
  msg->num_markers = static_cast<int32_t>(markers.size());
  for (const MapMarker& m : markers) {
    msg->marker_ids.push_back(m.id);
    msg->marker_sizes.push_back(m.size);
    msg->object_from_marker.push_back(ToPose3d(m.object_from_marker));
  }
}

template <class Msg>
std::vector<MapMarker> MarkersFromMsg(const Msg& msg) {
  std::vector<MapMarker> markers;
  for (int i = 0; i < msg.num_markers; ++i) {
    MapMarker m;
    m.id = msg.marker_ids[i];
    m.size = msg.marker_sizes[i];
    m.object_from_marker = FromPose3d(msg.object_from_marker[i]);
    markers.push_back(m);
  }
  return markers;
}

}  // namespace

rig_map_t ToRigMapMsg(const RigMap& map, int64_t utime) {
  rig_map_t msg;
  msg.utime = utime;
  msg.version = map.version;
  msg.reference_camera = map.reference_camera;
  msg.reference_marker = map.reference_marker;
  msg.dictionary = map.dictionary;
  AddCamerasToMsg(map, &msg);
  AddMarkersToMsg(map.markers, &msg);
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
  map.cameras = CamerasFromMsg(msg);
  map.markers = MarkersFromMsg(msg);
  map.rms_px = msg.rms_px;
  map.num_frames = msg.num_frames;
  map.num_observations = msg.num_observations;
  return map;
}

namespace {

object_layout_t ToLayoutMsg(const std::string& name, bool is_static, int reference_marker,
                            const std::vector<MapMarker>& markers) {
  object_layout_t msg;
  msg.name = name;
  msg.is_static = is_static;
  msg.reference_marker = reference_marker;
  AddMarkersToMsg(markers, &msg);
  msg.rig_from_object = ToPose3d(Rigid3::Identity());
  msg.rms_px = 0.0;
  msg.num_frames = 0;
  msg.num_observations = 0;
  return msg;
}

}  // namespace

rig_map2_t ToRigMap2Msg(const RigMap& map, int64_t utime) {
  rig_map2_t msg;
  msg.utime = utime;
  msg.version = map.objects.empty() ? kMapVersion : kMapVersionBodies;
  msg.reference_camera = map.reference_camera;
  msg.dictionary = map.dictionary;
  msg.rig_frame = map.rig_frame;
  AddCamerasToMsg(map, &msg);
  for (const auto& c : map.cameras) {
    msg.time_offset_us.push_back(c.time_offset_us);
    msg.time_drift_ppm.push_back(c.time_drift_ppm);
  }
  msg.time_reference_utime = map.time_reference_utime;
  if (map.objects.empty()) {
    msg.objects.push_back(ToLayoutMsg("", false, map.reference_marker, map.markers));
  } else {
    for (const MapObject& o : map.objects) {
      object_layout_t layout = ToLayoutMsg(o.name, o.is_static, o.reference_marker, o.markers);
      layout.rig_from_object = ToPose3d(o.rig_from_object);
      layout.rms_px = o.rms_px;
      layout.num_frames = o.num_frames;
      layout.num_observations = o.num_observations;
      msg.objects.push_back(layout);
    }
  }
  msg.num_objects = static_cast<int32_t>(msg.objects.size());
  msg.rms_px = map.rms_px;
  msg.num_frames = map.num_frames;
  msg.num_observations = map.num_observations;
  return msg;
}

RigMap FromRigMap2Msg(const rig_map2_t& msg) {
  RigMap map;
  map.version = msg.version;
  map.reference_camera = msg.reference_camera;
  map.dictionary = msg.dictionary;
  map.rig_frame = msg.rig_frame;
  map.cameras = CamerasFromMsg(msg);
  for (int i = 0; i < msg.num_cameras; ++i) {
    map.cameras[i].time_offset_us = msg.time_offset_us[i];
    map.cameras[i].time_drift_ppm = msg.time_drift_ppm[i];
  }
  map.time_reference_utime = msg.time_reference_utime;
  if (msg.num_objects < 1) throw std::invalid_argument("rig_map2_t without any object");
  if (msg.version == kMapVersion) {
    if (msg.num_objects != 1)
      throw std::invalid_argument("rig_map2_t version 1 with " + std::to_string(msg.num_objects) +
                                  " objects (expected one)");
    map.markers = MarkersFromMsg(msg.objects[0]);
    map.reference_marker = msg.objects[0].reference_marker;
  } else if (msg.version == kMapVersionBodies) {
    std::set<std::string> names;
    for (const object_layout_t& layout : msg.objects) {
      if (!names.insert(layout.name).second)
        throw std::invalid_argument("rig_map2_t: object '" + layout.name + "' twice");
      MapObject o;
      o.name = layout.name;
      o.is_static = layout.is_static;
      o.reference_marker = layout.reference_marker;
      o.markers = MarkersFromMsg(layout);
      o.rig_from_object = FromPose3d(layout.rig_from_object);
      o.rms_px = layout.rms_px;
      o.num_frames = layout.num_frames;
      o.num_observations = layout.num_observations;
      map.objects.push_back(o);
    }
    const MapObject& first = map.objects[FirstMovingObject(map)];
    map.markers = first.markers;
    map.reference_marker = first.reference_marker;
  } else {
    throw std::invalid_argument("rig_map2_t: unsupported map version " + std::to_string(msg.version));
  }
  map.rms_px = msg.rms_px;
  map.num_frames = msg.num_frames;
  map.num_observations = msg.num_observations;
  return map;
}

int64_t EncodedHash(const void* data, size_t size) {
  if (size < 8) return 0;
  uint64_t h = 0;
  for (size_t i = 0; i < 8; ++i) h = (h << 8) | static_cast<const uint8_t*>(data)[i];
  return static_cast<int64_t>(h);
}

bool DecodeMapMessage(const void* data, size_t size, MapMessage* out, std::string* error) {
  const int64_t hash = EncodedHash(data, size);
  std::string reason;
  try {
    if (size >= 8 && hash == rig_map_t::getHash()) {
      rig_map_t msg;
      if (Decode(data, size, &msg, &reason)) {
        out->map = FromRigMapMsg(msg);
        out->utime = msg.utime;
        out->type = "rig_map_t";
        return true;
      }
    } else if (size >= 8 && hash == rig_map2_t::getHash()) {
      rig_map2_t msg;
      if (Decode(data, size, &msg, &reason)) {
        out->map = FromRigMap2Msg(msg);
        out->utime = msg.utime;
        out->type = "rig_map2_t";
        return true;
      }
    } else {
      reason = "neither a rig_map2_t nor a rig_map_t (" + std::to_string(size) +
               " bytes: fingerprint mismatch, another message type?)";
    }
  } catch (const std::exception& e) {
    reason = std::string("invalid map message: ") + e.what();
  }
  if (error) *error = reason;
  return false;
}

TrajectoryRow FromObjectPoseMsg(const object_pose_t& msg) {
  TrajectoryRow row;
  row.utime = msg.utime;
  row.seq = msg.seq;
  row.rig_from_object = FromPose3d(msg.rig_from_object);
  row.rms_px = msg.rms_px;
  row.cameras = msg.num_cameras;
  row.markers = msg.num_markers;
  if (msg.status == object_pose_t::STATUS_TRACKING || msg.status == object_pose_t::STATUS_AMBIGUOUS) {
    Matrix6d covariance;
    for (int a = 0; a < 6; ++a)
      for (int b = 0; b < 6; ++b) covariance(a, b) = msg.covariance[a][b];
    row.quality =
        QualityOfPose(row.rig_from_object, covariance, msg.status == object_pose_t::STATUS_AMBIGUOUS);
  }
  return row;
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
