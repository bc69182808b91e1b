// FrameAssembler: frames of detections across the expected cameras.
#include <cstdlib>

#include "tracker/tracker.h"

namespace mcmt {

FrameAssembler::FrameAssembler(FrameSyncOptions options, std::set<std::string> expected_cameras)
    : options_(options), expected_(std::move(expected_cameras)) {}

bool FrameAssembler::IsAlive(const std::string& camera) const {
  if (newest_utime_ == INT64_MIN) return true;
  auto it = last_utime_.find(camera);
  const int64_t last = it != last_utime_.end() ? it->second : first_utime_;
  return last >= newest_utime_ - options_.camera_timeout_us;
}

std::set<std::string> FrameAssembler::StaleCameras() const {
  std::set<std::string> out;
  for (const auto& c : expected_)
    if (!IsAlive(c)) out.insert(c);
  return out;
}

bool FrameAssembler::HasAllAlive(const SyncedFrame& frame) const {
  for (const auto& cam : expected_) {
    if (!IsAlive(cam)) continue;
    bool found = false;
    for (const auto& v : frame.views) found = found || v.camera == cam;
    if (!found) return false;
  }
  return true;
}

std::vector<SyncedFrame> FrameAssembler::EmitUpTo(int64_t utime_inclusive) {
  std::vector<SyncedFrame> out;
  while (!pending_.empty() && pending_.begin()->first <= utime_inclusive) {
    const int64_t key = pending_.begin()->first;
    SyncedFrame frame = std::move(pending_.begin()->second);
    pending_.erase(pending_.begin());
    first_arrival_.erase(key);
    frame.complete = HasAllAlive(frame);
    ++stats_.frames_emitted;
    if (!frame.complete) ++stats_.frames_incomplete;
    emitted_until_ = std::max(emitted_until_, key);
    out.push_back(std::move(frame));
  }
  return out;
}

std::vector<SyncedFrame> FrameAssembler::Add(const detections_t& detections, int64_t arrival_us) {
  const int64_t utime = detections.utime;
  // The nearest pending frame within the tolerance.
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
  // A view of a frame already closed (or older): late or out of order, dropped.
  if (best == pending_.end() && emitted_until_ != INT64_MIN &&
      utime <= emitted_until_ + options_.tolerance_us) {
    ++stats_.out_of_order;
    return {};
  }
  if (best != pending_.end()) {
    for (const auto& v : best->second.views)
      if (v.camera == detections.camera) {
        ++stats_.duplicates;
        return {};
      }
  }
  if (first_utime_ == INT64_MIN) first_utime_ = utime;
  int64_t& last = last_utime_.emplace(detections.camera, utime).first->second;
  last = std::max(last, utime);
  newest_utime_ = std::max(newest_utime_, utime);
  if (best == pending_.end()) {
    SyncedFrame frame;
    frame.utime = utime;
    frame.seq = detections.seq;
    best = pending_.emplace(utime, std::move(frame)).first;
    first_arrival_[utime] = arrival_us;
  }
  best->second.views.push_back(detections);
  best->second.last_arrival_us = arrival_us;
  // The newest frame every alive camera has reported closes it and everything older (cameras report
  // in order, so an older frame missing a camera will not get it any more).
  for (auto it = pending_.rbegin(); it != pending_.rend(); ++it)
    if (HasAllAlive(it->second)) return EmitUpTo(it->first);
  return {};
}

std::vector<SyncedFrame> FrameAssembler::Poll(int64_t now_us) {
  int64_t newest_due = INT64_MIN;
  for (const auto& kv : first_arrival_)
    if (kv.second + options_.deadline_us <= now_us) newest_due = std::max(newest_due, kv.first);
  if (newest_due == INT64_MIN) return {};
  return EmitUpTo(newest_due);
}

std::vector<SyncedFrame> FrameAssembler::Flush() {
  if (pending_.empty()) return {};
  return EmitUpTo(pending_.rbegin()->first);
}

}  // namespace mcmt
