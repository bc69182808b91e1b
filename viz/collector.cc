#include "viz/collector.h"

#include <algorithm>
#include <cstdlib>
#include <iostream>

#include "core/lcm_util.h"
#include "core/objects.h"
#include "mcmt/detections_t.hpp"
#include "mcmt/object_pose_t.hpp"
#include "mcmt/tracker_status_t.hpp"

namespace mcmt::viz {

LcmCollector::LcmCollector(lcm::LCM& lcm, size_t keep_frames, size_t keep_poses)
    : lcm_(lcm), keep_frames_(keep_frames), keep_poses_(keep_poses) {
  // Every channel: pose streams are told by their type (tracker.channels may name them anything). LCM's
  // default queue (30) would drop a burst between two redraws; the camera images this also receives are
  // small, rate-limited JPEGs (detector.image_rate_hz), so the larger queue stays small in memory.
  subscriptions_.push_back(lcm_.subscribe(".*", &LcmCollector::OnMessage, this));
  subscriptions_.back()->setQueueCapacity(kSubscriptionQueueCapacity);
}

LcmCollector::~LcmCollector() {
  for (auto* s : subscriptions_) lcm_.unsubscribe(s);
}

LogReadReport LcmCollector::ReadLog(const std::string& path) {
  const LogReadReport report = ForEachLogEvent(path, [this](const LogEvent& e) {
    Handle(e.channel, e.data.data(), e.data.size());
    return true;
  });
  for (const std::string& line : report.damage) std::cerr << "mcmt-viz: warning: " << line << "\n";
  if (report.damaged()) std::cerr << "mcmt-viz: warning: " << report.Summary() << "\n";
  return report;
}

void LcmCollector::OnMessage(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  Handle(channel, rbuf->data, rbuf->data_size);
}

void LcmCollector::Handle(const std::string& channel, const void* data, size_t size) {
  if (channel == kMapChannel)
    OnMap(data, size, channel);
  else if (IsDetectionsChannel(channel))
    OnDetections(data, size, channel);
  else if (channel == kTrackerStatusChannel)
    OnTrackerStatus(data, size, channel);
  else if (channel == kPoseChannel || !BodyOfPoseChannel(channel, "").empty() ||
           HasType<object_pose_t>(data, size))
    OnPose(data, size, channel);
}

void LcmCollector::OnMap(const void* data, size_t size, const std::string& channel) {
  ++messages_;
  MapMessage msg;  // rig_map2_t or rig_map_t
  std::string error;
  if (!DecodeMapMessage(data, size, &msg, &error)) {
    if (stats_.decode_errors++ == 0) std::cerr << "mcmt-viz: warning: " << channel << ": " << error << "\n";
    return;
  }
  map_ = std::move(msg.map);
  ++map_count_;
}

void LcmCollector::OnPose(const void* data, size_t size, const std::string& channel) {
  ++messages_;
  object_pose_t msg;
  std::string error;
  if (!Decode(data, size, &msg, &error)) {
    if (stats_.decode_errors++ == 0) std::cerr << "mcmt-viz: warning: " << channel << ": " << error << "\n";
    return;
  }
  stats_.status = msg.status;
  if (msg.status == object_pose_t::STATUS_LOST) {
    ++stats_.lost;
    return;
  }
  PoseStream& stream = channel == kPoseChannel ? poses_ : body_poses_[BodyOfPose(channel, msg.object)];
  stream.rows.push_back(FromObjectPoseMsg(msg));
  if (keep_poses_ > 0 && stream.rows.size() >= 2 * keep_poses_) {
    const size_t drop = stream.rows.size() - keep_poses_;
    stream.rows.erase(stream.rows.begin(), stream.rows.begin() + static_cast<std::ptrdiff_t>(drop));
    stream.dropped += static_cast<int64_t>(drop);
  }
  ++stats_.poses;
  stats_.latency_ms = msg.latency_ms;
  stats_.rms_px = msg.rms_px;
  const int64_t now = NowUtime();
  arrivals_us_.push_back(now);
  while (!arrivals_us_.empty() && arrivals_us_.front() < now - 1000000) arrivals_us_.pop_front();
}

void LcmCollector::OnTrackerStatus(const void* data, size_t size, const std::string& channel) {
  ++messages_;
  tracker_status_t msg;
  std::string error;
  if (!Decode(data, size, &msg, &error)) {
    if (stats_.decode_errors++ == 0) std::cerr << "mcmt-viz: warning: " << channel << ": " << error << "\n";
    return;
  }
  ++status_count_;
  camera_states_.clear();
  for (const camera_health_t& c : msg.cameras) camera_states_[c.camera] = c.state;
}

void LcmCollector::OnDetections(const void* data, size_t size, const std::string& channel) {
  ++messages_;
  detections_t msg;
  std::string error;
  if (!Decode(data, size, &msg, &error)) {
    if (stats_.decode_errors++ == 0) std::cerr << "mcmt-viz: warning: " << channel << ": " << error << "\n";
    return;
  }
  std::vector<int>& ids = detections_[msg.utime][msg.camera];
  ids.clear();
  for (const auto& m : msg.markers) ids.push_back(m.id);
  if (keep_frames_ > 0)
    while (detections_.size() > keep_frames_) detections_.erase(detections_.begin());
}

int64_t LcmCollector::all_poses() const {
  int64_t n = poses_.total();
  for (const auto& [body, stream] : body_poses_) n += stream.total();
  return n;
}

double LcmCollector::RateHz(int64_t now_us) const {
  return static_cast<double>(std::count_if(arrivals_us_.begin(), arrivals_us_.end(),
                                           [&](int64_t t) { return t >= now_us - 1000000; }));
}

std::map<std::string, std::vector<int>> LcmCollector::DetectionsAt(int64_t utime) const {
  // Cameras of one frame share its utime; a small tolerance covers cameras stamped apart.
  constexpr int64_t kToleranceUs = 2000;
  std::map<std::string, std::vector<int>> out;
  std::map<std::string, int64_t> best_gap;
  for (auto it = detections_.lower_bound(utime - kToleranceUs);
       it != detections_.end() && it->first <= utime + kToleranceUs; ++it) {
    const int64_t gap = std::abs(it->first - utime);
    for (const auto& [camera, ids] : it->second) {
      auto g = best_gap.find(camera);
      if (g == best_gap.end() || gap < g->second) {
        best_gap[camera] = gap;
        out[camera] = ids;
      }
    }
  }
  return out;
}

}  // namespace mcmt::viz
