// Collects what the viewer shows from LCM (live) or a log (core's reader): the newest
// MCMT_MAP, the poses on MCMT_POSE and, per body, every other object_pose_t channel (MCMT_POSE_<BODY> or one
// renamed by tracker.channels; the body named by core's BodyOfPose), the marker ids on MCMT_DETECTIONS_.*
// per frame utime and the tracker's camera states (MCMT_TRACKER_STATUS).
#pragma once

#include <cstdint>
#include <deque>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/files.h"
#include "core/log_reader.h"

namespace mcmt::viz {

// Live statistics of the pose stream (for the overlay).
struct PoseStats {
  int64_t poses = 0;          // poses with a valid pose (tracking or ambiguous)
  int64_t lost = 0;           // STATUS_LOST messages
  double latency_ms = 0.0;    // the newest message's latency_ms (tracker)
  double rms_px = 0.0;        // the newest message's RMS reprojection error
  int status = -1;            // the newest message's status
  int64_t decode_errors = 0;  // messages that did not decode (any channel)
};

// The newest poses of one stream; rows[i] is the (dropped + i)-th pose received.
struct PoseStream {
  std::vector<TrajectoryRow> rows;
  int64_t dropped = 0;
  int64_t total() const { return dropped + static_cast<int64_t>(rows.size()); }
};

class LcmCollector {
 public:
  // keep_frames: detections of at most this many frames (utimes) are kept (0: all, for logs).
  // keep_poses: about this many newest poses are kept (0: all, for logs); older ones are dropped
  // in chunks so that a long live session runs in bounded memory.
  LcmCollector(lcm::LCM& lcm, size_t keep_frames, size_t keep_poses = 0);
  ~LcmCollector();
  LcmCollector(const LcmCollector&) = delete;
  LcmCollector& operator=(const LcmCollector&) = delete;

  // Reads a whole log (core's reader: damage is skipped, and reported on stderr and in the result).
  LogReadReport ReadLog(const std::string& path);
  // One message, as a subscription would deliver it.
  void Handle(const std::string& channel, const void* data, size_t size);

  bool has_map() const { return map_.has_value(); }
  const RigMap& map() const { return *map_; }
  int map_count() const { return map_count_; }  // maps received (a new one replaces the old)
  // The poses kept; poses()[i] is the (first_pose_index() + i)-th pose received.
  const std::vector<TrajectoryRow>& poses() const { return poses_.rows; }
  int64_t first_pose_index() const { return poses_.dropped; }
  int64_t total_poses() const { return poses_.total(); }
  // The poses of every body's channel MCMT_POSE_<BODY>, by body name (kept as poses() are).
  const std::map<std::string, PoseStream>& body_poses() const { return body_poses_; }
  const PoseStream& pose_stream() const { return poses_; }  // MCMT_POSE's
  // Poses on MCMT_POSE and on every body channel.
  int64_t all_poses() const;
  // Marker ids per camera detected in the frame of `utime` (empty if none known).
  std::map<std::string, std::vector<int>> DetectionsAt(int64_t utime) const;
  const PoseStats& stats() const { return stats_; }
  // Per camera, its state in the newest MCMT_TRACKER_STATUS (camera_health_t::STATE_*; absent: never
  // reported); status_count() counts the status messages received.
  const std::map<std::string, int>& camera_states() const { return camera_states_; }
  int64_t status_count() const { return status_count_; }
  // Poses per second of wall time over the second before now_us (NowUtime()).
  double RateHz(int64_t now_us) const;
  int64_t messages() const { return messages_; }

 private:
  void OnMessage(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void OnMap(const void* data, size_t size, const std::string& channel);
  void OnPose(const void* data, size_t size, const std::string& channel);
  void OnDetections(const void* data, size_t size, const std::string& channel);
  void OnTrackerStatus(const void* data, size_t size, const std::string& channel);

  lcm::LCM& lcm_;
  size_t keep_frames_;
  size_t keep_poses_;
  std::vector<lcm::Subscription*> subscriptions_;
  std::optional<RigMap> map_;
  int map_count_ = 0;
  PoseStream poses_;
  std::map<std::string, PoseStream> body_poses_;
  std::map<int64_t, std::map<std::string, std::vector<int>>> detections_;
  std::deque<int64_t> arrivals_us_;  // wall time of recent poses (rate)
  PoseStats stats_;
  int64_t messages_ = 0;
  std::map<std::string, int> camera_states_;
  int64_t status_count_ = 0;
};

}  // namespace mcmt::viz
