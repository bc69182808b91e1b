// LCM helpers: channel names, checked encode/decode, message <-> core conversions, loops.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/files.h"
#include "core/marker.h"
#include "core/se3.h"
#include "mcmt/camera_model_t.hpp"
#include "mcmt/detections_t.hpp"
#include "mcmt/mapper_command_t.hpp"
#include "mcmt/mapper_status_t.hpp"
#include "mcmt/marker_t.hpp"
#include "mcmt/object_layout_t.hpp"
#include "mcmt/object_pose_t.hpp"
#include "mcmt/pose3d_t.hpp"
#include "mcmt/rig_map2_t.hpp"
#include "mcmt/rig_map_t.hpp"

namespace mcmt {

constexpr char kDetectionsChannelPrefix[] = "MCMT_DETECTIONS_";
constexpr char kDetectionsChannelRegex[] = "MCMT_DETECTIONS_.*";
constexpr char kImageChannelPrefix[] = "MCMT_IMAGE_";
constexpr char kMapChannel[] = "MCMT_MAP";
constexpr char kPoseChannel[] = "MCMT_POSE";
constexpr char kMapperStatusChannel[] = "MCMT_MAPPER_STATUS";
constexpr char kMapperCommandChannel[] = "MCMT_MAPPER_COMMAND";
constexpr char kTrackerStatusChannel[] = "MCMT_TRACKER_STATUS";  // tracker_status_t, from mcmt-tracker
// Messages LCM keeps per subscription for a process between its handle() calls. LCM's default is 30, and
// it drops what arrives beyond that without a word: a burst of five cameras, or a process busy for a
// moment, would silently lose detections. Each subscription of a process that must not lose messages
// sets this (lcm::Subscription::setQueueCapacity).
constexpr int kSubscriptionQueueCapacity = 10000;

// "cam0" -> "MCMT_DETECTIONS_CAM0"; characters other than [A-Za-z0-9_] become '_'.
std::string DetectionsChannel(const std::string& camera_name);
std::string ImageChannel(const std::string& camera_name);

class LcmDecodeError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

template <typename Msg>
std::vector<uint8_t> Encode(const Msg& msg) {
  std::vector<uint8_t> buffer(msg.getEncodedSize());
  if (msg.encode(buffer.data(), 0, static_cast<int>(buffer.size())) != static_cast<int>(buffer.size()))
    throw std::runtime_error(std::string("cannot encode ") + Msg::getTypeName());
  return buffer;
}

// Structural check of an encoded message before LCM's generated decode() runs: LCM 1.3.1's decoders
// overflow on absurd array lengths (sizeof(double) * n in an int) and read out of bounds, so a
// foreign or corrupted buffer must be rejected first. Overloads for every mcmt type check the
// fingerprint, every string length and every array length against the bytes present.
bool CheckEncoded(const void* data, size_t size, const camera_model_t*, std::string* error);
bool CheckEncoded(const void* data, size_t size, const marker_t*, std::string* error);
bool CheckEncoded(const void* data, size_t size, const detections_t*, std::string* error);
bool CheckEncoded(const void* data, size_t size, const pose3d_t*, std::string* error);
bool CheckEncoded(const void* data, size_t size, const rig_map_t*, std::string* error);
bool CheckEncoded(const void* data, size_t size, const object_layout_t*, std::string* error);
bool CheckEncoded(const void* data, size_t size, const rig_map2_t*, std::string* error);
bool CheckEncoded(const void* data, size_t size, const object_pose_t*, std::string* error);
bool CheckEncoded(const void* data, size_t size, const mapper_status_t*, std::string* error);
bool CheckEncoded(const void* data, size_t size, const mapper_command_t*, std::string* error);
// Other (non-mcmt) types: no structural check beyond what their decode() does.
template <typename Msg>
bool CheckEncoded(const void*, size_t, const Msg*, std::string*) {
  return true;
}

// The fingerprint an encoded message starts with (0 for fewer than 8 bytes).
int64_t EncodedHash(const void* data, size_t size);
// Whether the buffer carries a Msg (by fingerprint only: Decode checks the rest).
template <typename Msg>
bool HasType(const void* data, size_t size) {
  return size >= 8 && EncodedHash(data, size) == Msg::getHash();
}

// Decodes exactly `size` bytes. A truncated, over-long, corrupted or foreign (fingerprint mismatch)
// buffer returns false with a reason in *error (never crashes, never throws).
template <typename Msg>
bool Decode(const void* data, size_t size, Msg* msg, std::string* error = nullptr) {
  if (size > static_cast<size_t>(INT32_MAX)) {
    if (error) *error = "message too large";
    return false;
  }
  std::string reason;
  if (!CheckEncoded(data, size, static_cast<const Msg*>(nullptr), &reason)) {
    if (error)
      *error = std::string("not a valid ") + Msg::getTypeName() + " (" + std::to_string(size) +
               " bytes: " + reason + ")";
    return false;
  }
  int n = -1;
  try {
    n = msg->decode(data, 0, static_cast<int>(size));
  } catch (const std::exception& e) {  // e.g. std::bad_alloc from a garbage array length
    n = -1;
  }
  if (n < 0) {
    if (error)
      *error = std::string("not a valid ") + Msg::getTypeName() + " (" + std::to_string(size) + " bytes)";
    return false;
  }
  if (static_cast<size_t>(n) != size) {
    if (error) *error = std::string("trailing bytes after ") + Msg::getTypeName();
    return false;
  }
  return true;
}

template <typename Msg>
Msg DecodeOrThrow(const void* data, size_t size) {
  Msg msg;
  std::string error;
  if (!Decode(data, size, &msg, &error)) throw LcmDecodeError(error);
  return msg;
}

// Conversions.
pose3d_t ToPose3d(const Rigid3& a_from_b);
Rigid3 FromPose3d(const pose3d_t& pose);
camera_model_t ToCameraModelMsg(const CameraModel& model);
CameraModel FromCameraModelMsg(const camera_model_t& msg);  // throws std::invalid_argument
rig_map_t ToRigMapMsg(const RigMap& map, int64_t utime);
RigMap FromRigMapMsg(const rig_map_t& msg);
// The map with its bodies (what mcmt-mapper publishes on MCMT_MAP): a version 1 map is one object with an
// empty name, a version 2 map its objects (and, from the first moving one, `markers`, as ReadMap). Camera
// clocks (time offsets and drifts) are carried; per-marker statistics are not.
rig_map2_t ToRigMap2Msg(const RigMap& map, int64_t utime);
RigMap FromRigMap2Msg(const rig_map2_t& msg);  // throws std::invalid_argument (camera model, no object)

// A map message on MCMT_MAP of either type, told apart by its fingerprint: rig_map2_t (mcmt-mapper) or
// rig_map_t (older logs and publishers). Every subscriber of MCMT_MAP decodes through this.
struct MapMessage {
  RigMap map;
  int64_t utime = 0;
  const char* type = "";  // "rig_map2_t" or "rig_map_t"
};
// False with a one-line reason in *error (a foreign fingerprint, a damaged buffer, an invalid camera model
// or layout); never throws.
bool DecodeMapMessage(const void* data, size_t size, MapMessage* out, std::string* error = nullptr);
// A tracker pose as a trajectory row (utime, seq, rig_from_object, rms_px, cameras, markers, and for a
// TRACKING or AMBIGUOUS pose its quality: QualityOfPose of its covariance); the status is the caller's to
// check (a LOST pose has no quality).
TrajectoryRow FromObjectPoseMsg(const object_pose_t& msg);
MarkerCorners2d CornersOf(const marker_t& marker);

// Content checks of a decoded detections_t received on `channel`, beyond its structure: "" when it is
// usable, else a one-line reason naming the camera and the channel (its `camera` field names another
// channel's camera, or its camera model is invalid, e.g. width -640 or three radtan coefficients).
std::string DetectionsProblem(const detections_t& msg, const std::string& channel);
// Removes the markers whose corners are not finite or absurd (beyond +-1e6 px) and returns how many;
// their ids go to *dropped_ids when given.
int DropInvalidMarkers(detections_t* msg, std::vector<int>* dropped_ids = nullptr);
bool IsDetectionsChannel(const std::string& channel);  // MCMT_DETECTIONS_*

// Drops repeated detections messages: the same camera, seq and utime seen before (a message recorded or
// relayed twice). Remembers the newest `window` messages per camera.
class DuplicateFilter {
 public:
  explicit DuplicateFilter(size_t window = 1 << 16) : window_(window) {}
  // True when (camera, seq, utime) was seen before (the caller drops the message); counts it.
  bool Repeated(const detections_t& msg);
  int64_t count() const { return count_; }
  // Up to 20 examples: "camera cam0 seq 12 utime 1000000".
  const std::vector<std::string>& examples() const { return examples_; }

 private:
  size_t window_;
  std::map<std::string, std::set<std::pair<int64_t, int64_t>>> seen_;  // camera -> (utime, seq)
  int64_t count_ = 0;
  std::vector<std::string> examples_;
};

// "file://<absolute path>?speed=0": reads a log as fast as possible through LCM's own provider.
std::string LogReadUrl(const std::string& log_path);
// Opens an LCM instance; throws std::runtime_error naming the URL when it is not good().
std::unique_ptr<lcm::LCM> OpenLcm(const std::string& url);

// Handles messages until done() is true (checked after every message and timeout tick) or the
// timeout passes. Returns true when done() became true. For file:// providers returns when the log
// ends (handle() < 0).
bool HandleUntil(lcm::LCM& lcm, const std::function<bool()>& done, std::chrono::milliseconds timeout,
                 std::chrono::milliseconds tick = std::chrono::milliseconds(20));

// Wall clock in microseconds since the epoch.
int64_t NowUtime();

}  // namespace mcmt
