#include "core/frame_sync.h"

#include <algorithm>
#include <cstdlib>

namespace mcmt {

FrameSynchronizer::FrameSynchronizer(FrameSyncOptions options) : options_(std::move(options)) {}

std::set<std::string> FrameSynchronizer::Cameras() const {
  std::set<std::string> out;
  for (const auto& kv : last_utime_) out.insert(kv.first);
  return out;
}

// Live (arrivals are wall times) a camera is alive while it was heard of within camera_timeout_us of
// wall time: detectors that drift apart in message time (videos at --rate max in parallel, a camera whose
// messages lag) are waited for, not declared dead. In a log, message time decides.
bool FrameSynchronizer::Alive(const std::string& camera) const {
  const auto last = last_utime_.find(camera);
  if (options_.arrival_is_wall_time) {
    if (last == last_utime_.end()) return now_us_ - first_arrival_any_ <= options_.camera_timeout_us;
    return now_us_ - last_arrival_.at(camera) <= options_.camera_timeout_us;
  }
  if (last == last_utime_.end()) return newest_utime_ - oldest_utime_ <= options_.camera_timeout_us;
  return last->second >= newest_utime_ - options_.camera_timeout_us;
}

std::set<std::string> FrameSynchronizer::StaleCameras() const {
  std::set<std::string> out;
  if (newest_utime_ == INT64_MIN) return out;
  for (const auto& kv : last_utime_)
    if (!Alive(kv.first)) out.insert(kv.first);
  for (const auto& cam : options_.cameras)
    if (!last_utime_.count(cam) && !Alive(cam)) out.insert(cam);
  return out;
}

std::set<std::string> FrameSynchronizer::AliveCameras() const {
  std::set<std::string> out;
  if (newest_utime_ == INT64_MIN) return out;
  for (const auto& kv : last_utime_)
    if (Alive(kv.first)) out.insert(kv.first);
  for (const auto& cam : options_.cameras)  // expected, not yet heard of
    if (!last_utime_.count(cam) && Alive(cam)) out.insert(cam);
  return out;
}

namespace {

bool HasCamera(const SyncedFrame& frame, const std::string& camera) {
  for (const auto& v : frame.views)
    if (v.camera == camera) return true;
  return false;
}

bool HasAll(const SyncedFrame& frame, const std::set<std::string>& cameras) {
  for (const auto& cam : cameras)
    if (!HasCamera(frame, cam)) return false;
  return true;
}

}  // namespace

std::vector<SyncedFrame> FrameSynchronizer::EmitUpTo(int64_t utime_inclusive) {
  std::vector<SyncedFrame> out;
  const std::set<std::string> alive = AliveCameras();
  while (!pending_.empty() && pending_.begin()->first <= utime_inclusive) {
    const int64_t key = pending_.begin()->first;
    SyncedFrame frame = std::move(pending_.begin()->second);
    pending_.erase(pending_.begin());
    first_arrival_.erase(key);
    frame.complete = HasAll(frame, alive);
    ++stats_.frames_emitted;
    if (!frame.complete) ++stats_.frames_incomplete;
    emitted_until_utime_ = std::max(emitted_until_utime_, key);
    for (const detections_t& v : frame.views) {
      const auto [it, added] = last_emitted_.emplace(v.camera, key);
      if (!added) it->second = std::max(it->second, key);
    }
    out.push_back(std::move(frame));
  }
  return out;
}

int64_t FrameSynchronizer::RunsOn(int64_t utime, int64_t since_arrival_us, int64_t arrival_us) const {
  return options_.arrival_is_wall_time ? utime + (arrival_us - since_arrival_us) : utime;
}

int64_t FrameSynchronizer::OtherCamerasClock(int64_t arrival_us) const {
  int64_t clock = INT64_MIN;
  for (const auto& [camera, utime] : last_utime_)
    clock = std::max(clock, RunsOn(utime, last_arrival_.at(camera), arrival_us));
  return clock;
}

// Messages on another clock count as one run while each is within max_clock_jump_us of the one before.
int FrameSynchronizer::ExtendRun(Jump* run, int64_t utime, int64_t arrival_us) const {
  run->count =
      (run->count > 0 && std::llabs(utime - run->utime) <= options_.max_clock_jump_us) ? run->count + 1 : 1;
  run->utime = utime;
  run->arrival = arrival_us;
  return run->count;
}

void FrameSynchronizer::ForgetPace(const std::string& camera) {
  lags_.erase(camera);
  gaps_.erase(camera);
}

void FrameSynchronizer::RecentMax::Push(int64_t v) {
  if (values.size() < kLagWindow)
    values.push_back(v);
  else
    values[next] = v;
  next = (next + 1) % kLagWindow;
}

int64_t FrameSynchronizer::RecentMax::Max() const {
  return values.empty() ? INT64_MIN : *std::max_element(values.begin(), values.end());
}

bool FrameSynchronizer::ClockPlausible(const detections_t& d, int64_t arrival_us) {
  clock_rejection_.clear();
  const int64_t jump = options_.max_clock_jump_us;
  if (jump <= 0) return true;
  std::string against;
  int64_t predicted = INT64_MIN;
  const auto own = last_utime_.find(d.camera);
  if (own != last_utime_.end()) {
    predicted = RunsOn(own->second, last_arrival_[d.camera], arrival_us);
    against = "its own clock";
  } else {
    predicted = OtherCamerasClock(arrival_us);
    against = "the other cameras' clocks";
  }
  if (predicted == INT64_MIN || d.utime - predicted <= jump) {
    jumps_.erase(d.camera);
    return true;
  }
  // Messages that keep coming on the new clock, consistent with each other: a restarted source, or the
  // clock was set by a camera ahead of the others. The cameras vote.
  if (ExtendRun(&jumps_[d.camera], d.utime, arrival_us) >= kClockJumpConfirm &&
      WinsVote(d.camera, arrival_us))
    return true;
  ++stats_.clock_jumps;
  clock_rejection_ = "camera '" + d.camera + "': utime " + std::to_string(d.utime) + " is " +
                     std::to_string((d.utime - predicted) / 1000) + " ms ahead of " + against +
                     " (more than " + std::to_string(jump / 1000) + " ms): message rejected";
  return false;
}

bool FrameSynchronizer::FarBehindAndOutvoted(const detections_t& d, int64_t arrival_us) {
  const int64_t jump = options_.max_clock_jump_us;
  if (jump <= 0) return false;
  // A camera's own clock going back (a restarted recording), or its first messages far behind the other
  // cameras' clocks (one of them set the clock ahead). Not a gradual drift between cameras (detectors
  // going through videos at different speeds): that is lag, waited for within max_wait_us.
  int64_t clock = INT64_MIN;
  const auto own = last_utime_.find(d.camera);
  const bool own_clock = own != last_utime_.end();
  std::string against = "its own clock";
  if (own_clock) {
    clock = own->second;
  } else {
    against = "the other cameras' clocks";
    clock = OtherCamerasClock(arrival_us);
  }
  if (clock == INT64_MIN || clock - d.utime <= jump) {
    behind_.erase(d.camera);
    return false;
  }
  // Fewer in a row: a late view as far as anyone can tell yet. A camera's first messages are held back
  // (they would set its clock); others go on to the late-view check.
  if (ExtendRun(&behind_[d.camera], d.utime, arrival_us) < kClockJumpConfirm) {
    if (own_clock) return false;
    ++stats_.out_of_order;
    return true;
  }
  if (WinsVote(d.camera, arrival_us)) return false;
  ++stats_.clock_jumps;
  clock_rejection_ = "camera '" + d.camera + "': utime " + std::to_string(d.utime) + " is " +
                     std::to_string((clock - d.utime) / 1000) + " ms behind " + against + " (more than " +
                     std::to_string(jump / 1000) + " ms): message rejected";
  return true;
}

std::map<std::string, int64_t> FrameSynchronizer::VoterClocks(int64_t arrival_us) const {
  std::map<std::string, int64_t> clocks;
  auto heard = [&](int64_t at) {
    return !options_.arrival_is_wall_time || arrival_us - at <= options_.camera_timeout_us;
  };
  for (const auto& [camera, utime] : last_utime_)
    if (heard(last_arrival_.at(camera))) clocks[camera] = RunsOn(utime, last_arrival_.at(camera), arrival_us);
  for (const auto* runs : {&jumps_, &behind_})
    for (const auto& [camera, run] : *runs)
      if (run.count >= kClockJumpConfirm && heard(run.arrival))
        clocks[camera] = RunsOn(run.utime, run.arrival, arrival_us);
  return clocks;
}

// The camera's run (a confirmed one in jumps_ or behind_) against the clocks of every camera heard of:
// the clock with the most cameras within max_clock_jump_us wins; on a tie the established clock stays,
// unless it is ahead of the arrival wall time (impossible for stamps of the capture). When the run wins,
// the synchronizer follows it (FollowClock).
bool FrameSynchronizer::WinsVote(const std::string& camera, int64_t arrival_us) {
  const int64_t jump = options_.max_clock_jump_us;
  const std::map<std::string, int64_t> clocks = VoterClocks(arrival_us);
  const int64_t mine = clocks.at(camera);
  auto support = [&](int64_t t) {
    int n = 0;
    for (const auto& kv : clocks) n += std::llabs(kv.second - t) <= jump;
    return n;
  };
  const int my_support = support(mine);
  for (const auto& [other, t] : clocks) {
    if (std::llabs(t - mine) <= jump) continue;
    const int s = support(t);
    const bool impossible = options_.arrival_is_wall_time && t - arrival_us > jump;
    if (s > my_support || (s == my_support && !impossible)) return false;
  }
  FollowClock(mine, arrival_us);
  return true;
}

// The cameras on `clock` (within max_clock_jump_us) go on from their runs; the others are forgotten (their
// later messages are judged against this clock), with their pending views; frames emitted on the old
// clock no longer make the new clock's views late.
void FrameSynchronizer::FollowClock(int64_t clock, int64_t arrival_us) {
  const int64_t jump = options_.max_clock_jump_us;
  const std::map<std::string, int64_t> clocks = VoterClocks(arrival_us);
  for (const auto* runs : {&jumps_, &behind_})
    for (const auto& [camera, run] : *runs)
      if (run.count >= kClockJumpConfirm && std::llabs(clocks.at(camera) - clock) <= jump) {
        last_utime_[camera] = first_utime_[camera] = run.utime;
        last_arrival_[camera] = run.arrival;
        ForgetPace(camera);
      }
  for (const auto& [camera, t] : clocks) {
    jumps_.erase(camera);
    behind_.erase(camera);
  }
  for (auto it = last_utime_.begin(); it != last_utime_.end();) {
    if (std::llabs(RunsOn(it->second, last_arrival_[it->first], arrival_us) - clock) <= jump) {
      ++it;
      continue;
    }
    const std::string camera = it->first;
    first_utime_.erase(camera);
    last_arrival_.erase(camera);
    ForgetPace(camera);
    it = last_utime_.erase(it);
  }
  for (auto it = pending_.begin(); it != pending_.end();) {
    if (std::llabs(it->first - clock) <= jump + options_.camera_timeout_us) {
      ++it;
      continue;
    }
    first_arrival_.erase(it->first);
    it = pending_.erase(it);
  }
  newest_utime_ = INT64_MIN;
  oldest_utime_ = INT64_MAX;
  for (const auto& [camera, utime] : last_utime_) {
    newest_utime_ = std::max(newest_utime_, utime);
    oldest_utime_ = std::min(oldest_utime_, first_utime_[camera]);
  }
  emitted_until_utime_ = INT64_MIN;
  for (auto it = last_emitted_.begin(); it != last_emitted_.end();) {
    if (!last_utime_.count(it->first) || std::llabs(it->second - clock) > jump + options_.camera_timeout_us) {
      it = last_emitted_.erase(it);
      continue;
    }
    emitted_until_utime_ = std::max(emitted_until_utime_, it->second);
    ++it;
  }
}

std::vector<SyncedFrame> FrameSynchronizer::Add(const detections_t& detections, int64_t arrival_us) {
  const int64_t utime = detections.utime;
  if (!ClockPlausible(detections, arrival_us)) return {};
  if (FarBehindAndOutvoted(detections, arrival_us)) return {};
  // Measured before the late-view check: a camera whose views all come late must get its wait.
  if (options_.max_wait_us > 0 && options_.arrival_is_wall_time)
    lags_[detections.camera].Push(arrival_us - utime);
  // The nearest pending frame within tolerance.
  auto best = pending_.end();
  int64_t best_gap = 0;
  for (auto it = pending_.lower_bound(utime - options_.tolerance_us);
       it != pending_.end() && it->first <= utime + options_.tolerance_us; ++it) {
    const int64_t gap = std::llabs(it->first - utime);
    if (best == pending_.end() || gap < best_gap) {
      best = it;
      best_gap = gap;
    }
  }
  // No pending frame takes it, and it is not newer than the frames already emitted (with tolerance):
  // a late view of an emitted frame, or an out-of-order message. Dropped.
  if (best == pending_.end() && emitted_until_utime_ != INT64_MIN &&
      utime <= emitted_until_utime_ + options_.tolerance_us) {
    ++stats_.out_of_order;
    // A camera heard of for the first time by a late view (one that joins a running rig and reports
    // after the others): known from now on, so the next frames wait for it instead of dropping it for ever.
    if (!last_utime_.count(detections.camera)) {
      last_utime_[detections.camera] = utime;
      first_utime_[detections.camera] = utime;
      last_arrival_[detections.camera] = arrival_us;
    }
    return {};
  }
  if (best != pending_.end() && HasCamera(best->second, detections.camera)) {
    ++stats_.duplicates;
    return {};
  }

  // Accepted: liveness and the camera set.
  const std::string& camera = detections.camera;
  now_us_ = std::max(now_us_, arrival_us);
  first_arrival_any_ = std::min(first_arrival_any_, arrival_us);
  if (const auto previous = last_arrival_.find(camera); previous != last_arrival_.end())
    gaps_[camera].Push(arrival_us - previous->second);
  last_arrival_[camera] = arrival_us;
  auto last = last_utime_.find(camera);
  if (last == last_utime_.end()) {
    last_utime_[camera] = utime;
    first_utime_[camera] = utime;
  } else {
    last->second = std::max(last->second, utime);
    if (utime > first_utime_[camera] + options_.tolerance_us) settled_ = true;  // a second frame
  }
  newest_utime_ = std::max(newest_utime_, utime);
  oldest_utime_ = std::min(oldest_utime_, utime);
  if (!settled_ && !options_.cameras.empty()) {
    settled_ = std::all_of(options_.cameras.begin(), options_.cameras.end(),
                           [this](const std::string& c) { return last_utime_.count(c) > 0; });
  }

  if (best == pending_.end()) {
    SyncedFrame frame;
    frame.utime = utime;
    frame.seq = detections.seq;
    best = pending_.emplace(utime, std::move(frame)).first;
    first_arrival_[utime] = arrival_us;
  }
  best->second.views.push_back(detections);
  best->second.last_arrival_us = arrival_us;
  if (!settled_) return {};

  // The newest pending frame that every alive camera has reported closes it and everything older
  // (cameras report in order, so an older frame missing a camera will not get it any more).
  const std::set<std::string> alive = AliveCameras();
  int64_t emit_until = INT64_MIN;
  for (auto it = pending_.rbegin(); it != pending_.rend(); ++it)
    if (HasAll(it->second, alive)) {
      emit_until = it->first;
      break;
    }
  // A frame that cannot complete any more: every alive camera missing from it has already reported a
  // newer capture (cameras report in order). Emitted at once as incomplete instead of waiting for the
  // deadline (cameras at different rates, or clocks further apart than the tolerance).
  for (auto it = pending_.upper_bound(emit_until); it != pending_.end(); ++it) {
    bool hopeless = true;
    for (const auto& cam : alive) {
      if (HasCamera(it->second, cam)) continue;
      const auto last_seen = last_utime_.find(cam);
      if (last_seen == last_utime_.end() || last_seen->second <= it->first + options_.tolerance_us) {
        hopeless = false;
        break;
      }
    }
    if (hopeless) emit_until = it->first;
  }
  if (emit_until == INT64_MIN) return {};
  return EmitUpTo(emit_until);
}

int64_t FrameSynchronizer::Lag(const std::string& camera) const {
  const auto it = lags_.find(camera);
  return it == lags_.end() ? INT64_MIN : it->second.Max();
}

int64_t FrameSynchronizer::DueTime(int64_t key, int64_t first_arrival_us,
                                   const std::set<std::string>& alive) const {
  int64_t due = first_arrival_us + options_.deadline_us;
  if (options_.max_wait_us <= options_.deadline_us || !options_.arrival_is_wall_time) return due;
  const SyncedFrame& frame = pending_.at(key);
  for (const std::string& camera : alive) {
    if (HasCamera(frame, camera)) continue;
    const int64_t lag = Lag(camera);
    // An expected camera not heard of yet: its lag is unknown, wait as long as allowed (the first second).
    due = std::max(due, lag == INT64_MIN ? first_arrival_us + options_.max_wait_us
                                         : key + lag + options_.deadline_us);  // when it usually arrives
    // A camera that has not reached this capture yet but keeps reporting at its pace (its lag may grow:
    // a detector slower through a video than the others) is waited for until one of its usual gaps
    // between messages has passed without news.
    const auto last = last_utime_.find(camera);
    const auto gaps = gaps_.find(camera);
    if (last != last_utime_.end() && last->second < key && gaps != gaps_.end() &&
        !gaps->second.values.empty())
      due = std::max(due, last_arrival_.at(camera) + gaps->second.Max() + options_.deadline_us);
  }
  return std::min(due, first_arrival_us + options_.max_wait_us);
}

std::vector<SyncedFrame> FrameSynchronizer::Poll(int64_t now_us) {
  now_us_ = std::max(now_us_, now_us);
  int64_t newest_due = INT64_MIN;
  const std::set<std::string> alive = AliveCameras();
  for (const auto& kv : first_arrival_)
    if (DueTime(kv.first, kv.second, alive) <= now_us) newest_due = std::max(newest_due, kv.first);
  if (newest_due == INT64_MIN) return {};
  return EmitUpTo(newest_due);
}

std::vector<SyncedFrame> FrameSynchronizer::Flush() {
  if (pending_.empty()) return {};
  return EmitUpTo(pending_.rbegin()->first);
}

}  // namespace mcmt
