// Groups detections of the same capture time across cameras into frames.
// Live use: a frame is complete as soon as every alive camera has reported it, or when its deadline
// (first arrival + deadline) passes, so one slow or dead camera never stalls the others. A camera
// is alive while it has reported within `camera_timeout_us` (in message utime).
// A frame that can no longer complete (every alive camera missing from it has already reported a
// newer capture: cameras report in order) leaves at once, incomplete, without waiting for its deadline.
// Out-of-order messages (older than a frame already emitted, including late views of a frame
// emitted by its deadline) and duplicates (same camera, same frame) are dropped and counted.
#pragma once

#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "mcmt/detections_t.hpp"

namespace mcmt {

struct FrameSyncOptions {
  int64_t tolerance_us = 2000;  // detections within this of a frame's utime join it
  int64_t deadline_us = 15000;  // wall-time wait after a frame's first arrival
  // Adaptive wait (0: none, only deadline_us). Each camera's lag (arrival - utime, the largest of its
  // last kLagWindow messages) is measured; a frame missing a camera waits until that camera's views
  // usually arrive (+ deadline_us), but never more than max_wait_us after the frame's first arrival.
  // Detectors that drift apart (videos at --rate max in parallel, a camera whose messages lag) lose no
  // view; a dead camera costs at most max_wait_us per frame until camera_timeout_us declares it stale.
  // An expected camera (options.cameras) not heard of yet is waited for max_wait_us. Wall-time arrivals only.
  int64_t max_wait_us = 0;
  // A camera silent this long (wall time of arrivals when live, message time in a log) is not waited for.
  int64_t camera_timeout_us = 1000000;
  // Cameras expected (e.g. the rig's). Optional. A listed camera not heard of yet is waited for until
  // camera_timeout_us has passed since the first message. Without the list, no frame
  // completes before the camera set has settled (some camera reported a second frame), so the first
  // frame is not emitted with only the first camera that happened to report.
  std::vector<std::string> cameras;
  // Clock check (0: none). A message whose utime is more than this ahead of what its camera's clock
  // predicts (its newest accepted utime, plus the wall time elapsed since it arrived when arrivals are
  // wall times), or -- for a camera's first messages -- of what the other cameras' clocks predict, is
  // rejected (counted in clock_jumps) and moves no clock: one message stamped +100 s must not make every
  // later frame late. A camera whose messages keep coming on another clock, ahead or behind
  // (kClockJumpConfirm in a row, consistent with each other), calls a vote among the cameras heard of
  // within camera_timeout_us: the clock most cameras agree on wins (a tie keeps the established clock,
  // unless that one is ahead of the wall time the messages arrive at). A restarted source, or all
  // cameras restarted, are followed; a camera ahead of or behind the others is rejected, named, even when
  // it happened to report first and set the clock.
  int64_t max_clock_jump_us = 5000000;
  bool arrival_is_wall_time = true;  // false: arrivals are message times (a log)
};

struct SyncedFrame {
  int64_t utime = 0;                // of the first detection that opened the frame
  int64_t seq = 0;                  // of the first detection that opened the frame
  std::vector<detections_t> views;  // one per camera, in order of arrival
  int64_t last_arrival_us = 0;      // wall time the last view arrived
  bool complete = false;            // every alive camera reported (false: emitted by deadline/flush)
};

struct FrameSyncStats {
  int64_t frames_emitted = 0;
  int64_t frames_incomplete = 0;
  int64_t duplicates = 0;
  int64_t out_of_order = 0;
  int64_t clock_jumps = 0;  // messages rejected by the clock check
};

class FrameSynchronizer {
 public:
  static constexpr int kClockJumpConfirm = 5;
  static constexpr size_t kLagWindow = 32;
  explicit FrameSynchronizer(FrameSyncOptions options = {});

  // Adds one camera's detections (arrival: wall time in us). Returns the frames completed by it,
  // oldest first.
  std::vector<SyncedFrame> Add(const detections_t& detections, int64_t arrival_us);
  // Frames whose deadline has passed at wall time now_us, oldest first.
  std::vector<SyncedFrame> Poll(int64_t now_us);
  // Everything pending, oldest first (end of a log).
  std::vector<SyncedFrame> Flush();

  // Why the last message given to Add was rejected by the clock check ("" when it was not): one line
  // naming the camera, its utime and the clock it disagrees with.
  const std::string& clock_rejection() const { return clock_rejection_; }

  // The measured lag of a camera (arrival - utime, largest recent), or INT64_MIN when unknown.
  int64_t Lag(const std::string& camera) const;

  // Cameras ever seen, and those not heard of for camera_timeout_us before the newest utime.
  std::set<std::string> Cameras() const;
  std::set<std::string> StaleCameras() const;
  const FrameSyncStats& stats() const { return stats_; }

 private:
  FrameSyncOptions options_;
  std::map<int64_t, SyncedFrame> pending_;     // by frame utime
  std::map<std::string, int64_t> last_utime_;  // per camera, newest message utime
  int64_t newest_utime_ = INT64_MIN;
  int64_t emitted_until_utime_ = INT64_MIN;  // frames at or before this are closed
  FrameSyncStats stats_;
  std::map<int64_t, int64_t> first_arrival_;    // frame utime -> wall time of first view
  std::map<std::string, int64_t> first_utime_;  // per camera, first message utime
  int64_t oldest_utime_ = INT64_MAX;            // first message utime overall
  bool settled_ = false;                        // the camera set is known (see options.cameras)
  struct Jump {
    int64_t utime = 0;    // last utime on the other clock
    int64_t arrival = 0;  // its arrival
    int count = 0;        // consistent messages in a row
  };
  std::map<std::string, int64_t> last_arrival_;  // per camera, arrival of its newest accepted message
  std::map<std::string, Jump> jumps_;            // runs of messages ahead of the clock
  std::map<std::string, Jump> behind_;           // runs of messages far behind the clock
  std::map<std::string, int64_t> last_emitted_;  // per camera, newest emitted frame with its view
  // The largest of the last kLagWindow values (a ring).
  struct RecentMax {
    std::vector<int64_t> values;
    size_t next = 0;
    void Push(int64_t v);
    int64_t Max() const;  // INT64_MIN when empty
  };
  std::map<std::string, RecentMax> lags_;      // per camera, recent arrival - utime
  std::map<std::string, RecentMax> gaps_;      // per camera, recent gaps between arrivals
  void ForgetPace(const std::string& camera);  // its lags and gaps (its clock changed)
  // Wall time at which the pending frame `key` (first arrival first_arrival_us) is due.
  int64_t DueTime(int64_t key, int64_t first_arrival_us, const std::set<std::string>& alive) const;
  std::string clock_rejection_;
  bool ClockPlausible(const detections_t& detections, int64_t arrival_us);
  bool FarBehindAndOutvoted(const detections_t& detections, int64_t arrival_us);
  int64_t RunsOn(int64_t utime, int64_t since_arrival_us, int64_t arrival_us) const;
  int64_t OtherCamerasClock(int64_t arrival_us) const;  // the newest, as they run on (INT64_MIN: none)
  int ExtendRun(Jump* run, int64_t utime, int64_t arrival_us) const;  // its length, this message included
  std::map<std::string, int64_t> VoterClocks(int64_t arrival_us) const;
  bool WinsVote(const std::string& camera, int64_t arrival_us);
  void FollowClock(int64_t clock, int64_t arrival_us);
  std::vector<SyncedFrame> EmitUpTo(int64_t utime_inclusive);
  std::set<std::string> AliveCameras() const;
  bool Alive(const std::string& camera) const;
  int64_t now_us_ = INT64_MIN;             // newest arrival or poll (wall time when live)
  int64_t first_arrival_any_ = INT64_MAX;  // arrival of the first accepted message
};

}  // namespace mcmt
