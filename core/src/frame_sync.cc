#include "core/frame_sync.h"

#include <algorithm>
#include <cstdlib>

namespace mcmt {

FrameSynchronizer::FrameSynchronizer(FrameSyncOptions options) : options_(options) {}

std::set<std::string> FrameSynchronizer::Cameras() const {
  std::set<std::string> out;
  for (const auto& kv : last_utime_) out.insert(kv.first);
  return out;
}

std::set<std::string> FrameSynchronizer::StaleCameras() const {
  std::set<std::string> out;
  for (const auto& kv : last_utime_)
    if (kv.second < newest_utime_ - options_.camera_timeout_us) out.insert(kv.first);
  return out;
}

std::set<std::string> FrameSynchronizer::AliveCameras() const {
  std::set<std::string> out;
  for (const auto& kv : last_utime_)
    if (kv.second >= newest_utime_ - options_.camera_timeout_us) out.insert(kv.first);
  return out;
}

namespace {

bool HasAll(const SyncedFrame& frame, const std::set<std::string>& cameras) {
  for (const auto& cam : cameras) {
    bool found = false;
    for (const auto& v : frame.views)
      if (v.camera == cam) {
        found = true;
        break;
      }
    if (!found) return false;
  }
  return true;
}

}  // namespace

std::vector<SyncedFrame> FrameSynchronizer::EmitUpTo(int64_t utime_inclusive) {
  std::vector<SyncedFrame> out;
  const std::set<std::string> alive = AliveCameras();
  while (!pending_.empty() && pending_.begin()->first <= utime_inclusive) {
    SyncedFrame frame = std::move(pending_.begin()->second);
    const int64_t key = pending_.begin()->first;
    pending_.erase(pending_.begin());
    first_arrival_.erase(key);
    frame.complete = HasAll(frame, alive);
    ++stats_.frames_emitted;
    if (!frame.complete) ++stats_.frames_incomplete;
    emitted_until_utime_ = std::max(emitted_until_utime_, key);
    out.push_back(std::move(frame));
  }
  return out;
}

std::vector<SyncedFrame> FrameSynchronizer::Add(const detections_t& detections, int64_t arrival_us) {
  const int64_t utime = detections.utime;
  // A view of a frame already emitted (or older): late or out of order, dropped.
  if (emitted_until_utime_ != INT64_MIN && utime <= emitted_until_utime_ + options_.tolerance_us) {
    // Still inside the tolerance of a newer pending frame? Then it belongs there.
    bool pending_match = false;
    for (const auto& kv : pending_)
      if (std::llabs(kv.first - utime) <= options_.tolerance_us) pending_match = true;
    if (!pending_match) {
      ++stats_.out_of_order;
      return {};
    }
  }
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
  if (best != pending_.end()) {
    for (const auto& v : best->second.views)
      if (v.camera == detections.camera) {
        ++stats_.duplicates;
        return {};
      }
  }
  // Accepted: update liveness.
  auto seen = last_utime_.find(detections.camera);
  if (seen == last_utime_.end())
    last_utime_[detections.camera] = utime;
  else
    seen->second = std::max(seen->second, utime);
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

  // The newest pending frame that every alive camera has reported closes it and everything older
  // (cameras report in order, so an older frame missing a camera will not get it any more).
  const std::set<std::string> alive = AliveCameras();
  for (auto it = pending_.rbegin(); it != pending_.rend(); ++it)
    if (HasAll(it->second, alive)) return EmitUpTo(it->first);
  return {};
}

std::vector<SyncedFrame> FrameSynchronizer::Poll(int64_t now_us) {
  int64_t newest_due = INT64_MIN;
  for (const auto& kv : first_arrival_)
    if (kv.second + options_.deadline_us <= now_us) newest_due = std::max(newest_due, kv.first);
  if (newest_due == INT64_MIN) return {};
  return EmitUpTo(newest_due);
}

std::vector<SyncedFrame> FrameSynchronizer::Flush() {
  if (pending_.empty()) return {};
  return EmitUpTo(pending_.rbegin()->first);
}

}  // namespace mcmt
