// The mapper in maintenance mode (`mcmt-mapper --config rig.yaml --map map.yaml --maintain`): keeps a live
// rig's map true while it tracks.
//
//   listens   MCMT_DETECTIONS_* (a ring of recent messages per camera), the tracker's poses (MCMT_POSE:
//             which frames have an object pose and which cameras it used) and MCMT_TRACKER_STATUS (the
//             tracker's per-camera health, tracker/health.h)
//   suspects  a camera of the map that the tracker reports suspect or excluded (under the map this node
//             published last), and a camera of the rig that publishes detections but is not in the map
//   collects  the frames after the suspicion began (after the new camera's first message) in which the
//             tracker has a pose solved without that camera and the camera sees markers: the others' view
//             of the object, frame by frame; maintain_frames of them (maintain_added_frames for a new
//             camera)
//   solves    the offline update on those frames' detections (mapper/update.h: Mapper::SetBaseMap, one
//             implementation): a moved camera re-estimated, a new one added, the others and the layout
//             held at the map's values
//   checks    the camera is reported moved (or added) by the update, and its RMS in the new map is at most
//             maintain_max_rms_ratio x the median of the other cameras' (else nothing is published and the
//             reason goes into the status message)
//   publishes the new map on MCMT_MAP (rig_map2_t utime: the map's version, higher than every map before),
//             the change as a mapper_status_t (STATE_DONE) on MCMT_MAPPER_STATUS, and the map file in
//             --out when given
// Trackers switch to the newer map between frames (tracker/tracker_node.cc) and judge every camera
// afresh; the re-estimated camera comes back ok.
#pragma once

#include <cstdint>
#include <deque>
#include <iosfwd>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/files.h"
#include "core/stop.h"
#include "mapper/mapper.h"
#include "mcmt/detections_t.hpp"

namespace mcmt {

struct MaintainNodeOptions {
  std::string pose_channel = "MCMT_POSE";  // the tracker's object_pose_t
  std::string outdir;                      // "": no file; else OUTDIR/map.yaml rewritten at each new map
  int history_frames = 3000;               // detections kept per camera (and poses), newest
};

// One re-estimation: what it was for, and what came of it.
struct MaintainEvent {
  std::string camera;
  bool added = false;         // a camera the map lacked (else a suspect one)
  int64_t since_utime = 0;    // frames from this utime on were used
  int64_t solved_utime = 0;   // newest frame utime used
  int frames = 0;             // frames used
  bool published = false;     // the check passed and the map was published
  int64_t map_utime = 0;      // the published map's utime (its version)
  double rotation_deg = 0.0;  // moved camera: the change
  double translation_mm = 0.0;
  std::string message;  // one line (also the status message)
};

class MaintainNode {
 public:
  // input: where detections, poses and tracker status arrive; output: where maps and status go (may be
  // the same object). map: the map in use.
  MaintainNode(lcm::LCM& input, lcm::LCM* output, const RigConfig& rig, const MapperOptions& options,
               const RigMap& map, MaintainNodeOptions node_options, std::ostream& log);
  ~MaintainNode();
  MaintainNode(const MaintainNode&) = delete;
  MaintainNode& operator=(const MaintainNode&) = delete;

  // Handles messages and re-estimates until stop is requested.
  void Run(const StopToken& stop);
  // Re-estimates the cameras that have enough frames (called by Run after each message).
  void Step();

  // The raw handlers (public so that tests can feed bytes directly).
  void OnDetections(const std::string& channel, const void* data, size_t size);
  void OnPose(const void* data, size_t size);
  void OnTrackerStatus(const void* data, size_t size);

  const RigMap& map() const { return map_; }
  int64_t map_utime() const { return map_utime_; }  // 0: the map file
  const std::vector<MaintainEvent>& events() const { return events_; }

 private:
  struct Candidate {
    bool added = false;
    int64_t since_utime = 0;
    std::set<int64_t> frames;  // pose utimes without the camera, in which it sees markers
  };
  struct PoseInfo {
    std::set<std::string> cameras;  // cameras the pose used
  };
  void HandleDetections(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void HandlePose(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void HandleStatus(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void Suspect(const std::string& camera, bool added, int64_t since_utime);
  void CountFrame(int64_t pose_utime, const PoseInfo& pose);
  const detections_t* ViewAt(const std::string& camera, int64_t utime) const;
  void Reestimate(const std::string& camera, const Candidate& candidate);
  void Publish(const RigMap& map, const std::string& message);
  void Status(int8_t state, const std::string& message);

  lcm::LCM& input_;
  lcm::LCM* output_;
  const RigConfig& rig_;
  MapperOptions options_;
  MaintainNodeOptions node_options_;
  std::ostream& log_;
  RigMap map_;
  int64_t map_utime_ = 0;
  std::vector<lcm::Subscription*> subscriptions_;
  // Per camera, by utime on the reference camera's clock (RigMap::ReferenceUtime; the messages as sent).
  std::map<std::string, std::map<int64_t, detections_t>> views_;
  std::map<int64_t, PoseInfo> poses_;  // tracked frames, by utime
  std::map<std::string, Candidate> candidates_;
  std::map<std::string, int64_t> settled_until_;  // per camera: no suspicion from frames before this
  std::vector<MaintainEvent> events_;
  std::set<std::string> warned_;
};

}  // namespace mcmt
