// Per-camera health in the tracker: is each camera still where the map says it is?
//
// Every frame seen by a camera and by at least one other, the camera is judged by the RMS corner error
// of its markers under the object pose solved from the other cameras alone (its own markers left out, so
// a moved camera cannot pull the pose towards itself). Per camera:
//   gate     this frame's RMS > max(gate_px, gate_ratio * baseline): its markers are left out of this
//            frame's published pose (counted in rejected_share)
//   suspect  the median of its last `window` judged RMS > max(suspect_px, suspect_ratio * baseline)
//   excluded suspect for exclude_frames judged frames in a row: left out of every pose (still judged,
//            under the pose from the cameras used) until a new map (mcmt-mapper --maintain re-estimates it
//            and publishes one) or until it is good again
//   ok again a suspect camera whose window median falls back below the threshold; an excluded one whose
//            window median stays at or below recover_ratio x the threshold for recover_frames judged
//            frames in a row (hysteresis: a camera that did not move, only saw a transient - a hand, a
//            reflection - comes back under the same map; one that moved stays far above)
//   not judged  a camera that reported in unjudged_frames frames without being judged once since the map,
//            while two other cameras saw the object too (within a second, in other frames): clocks apart
//            by more than the sync tolerance; its health is unknown, said once by the tracker; judged, ok
// baseline = the median of its judged RMS while ok (the last baseline_frames), so a camera whose detector
// is noisier than the others' is held to its own level; nothing is gated or suspected before
// min_baseline_frames judged frames (a map that is off from the start is the mapper's to report). No LCM
// here: tracker_node.cc publishes the state as tracker_status_t on MCMT_TRACKER_STATUS.
#pragma once

#include <cstdint>
#include <deque>
#include <map>
#include <string>
#include <vector>

namespace mcmt {

struct HealthOptions {
  double gate_px = 1.2;
  double gate_ratio = 5.0;
  double suspect_px = 0.8;
  double suspect_ratio = 3.0;
  int window = 9;
  int exclude_frames = 6;
  int baseline_frames = 300;
  int min_baseline_frames = 30;  // judged frames while ok before a camera is gated or suspected
  double recover_ratio = 0.5;    // an excluded camera is good when its median is <= this x the threshold
  int recover_frames = 30;       // ... for this many judged frames in a row: ok again
  int unjudged_frames = 30;      // frames a camera reports in, never judged, before it is "not judged"
};

// The values of camera_health_t's STATE_ constants.
enum class CameraState : int8_t { kOk = 0, kSuspect = 1, kExcluded = 2, kNotJudged = 3 };
const char* CameraStateName(CameraState state);

struct CameraHealth {
  std::string camera;
  CameraState state = CameraState::kOk;
  double rms_px = -1.0;  // window median (-1: not judged yet)
  double baseline_px = 0.0;
  double rejected_share = 0.0;  // over the last `window` judged frames
  int frames = 0;               // judged frames
  int unjudged_frames = 0;      // frames it reported in while never judged (since the map)
  int64_t since_utime = 0;
  int64_t first_suspect_utime = -1;  // frame utime it first left ok since the map (-1: never)
};

class HealthMonitor {
 public:
  HealthMonitor(const std::vector<std::string>& cameras, const HealthOptions& options);

  bool Excluded(const std::string& camera) const;
  // The RMS above which the camera's markers are left out of the current frame, pixels.
  double GatePx(const std::string& camera) const;
  // One judged frame; returns true when the camera's state changed.
  bool Update(const std::string& camera, int64_t utime, double rms_px, bool gated);
  // A frame the camera reported in (a mapped marker) and could not be judged in; returns true when it
  // became "not judged" (never judged since the map, unjudged_frames such frames).
  bool NotJudged(const std::string& camera, int64_t utime);
  std::vector<CameraHealth> Snapshot() const;        // cameras in the order given
  CameraHealth Of(const std::string& camera) const;  // throws std::out_of_range for another camera

 private:
  struct Track {
    CameraHealth health;
    std::deque<double> window;
    std::deque<char> gated;
    std::deque<double> history;          // judged RMS while ok, for the baseline (oldest first)
    std::vector<double> sorted_history;  // the same, sorted
    int suspect_run = 0;
    int recover_run = 0;  // excluded: judged frames in a row good enough to come back
  };
  double Baseline(const Track& t) const;
  double SuspectPx(const Track& t) const;  // max(suspect_px, suspect_ratio x baseline)
  void AddToBaseline(double rms_px, Track* t) const;
  bool Established(const Track& t) const;
  HealthOptions options_;
  std::vector<std::string> order_;
  std::map<std::string, Track> tracks_;
};

}  // namespace mcmt
