// Per-camera health (tracker/health.h has the rules).
#include "tracker/health.h"

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include "core/lcm_util.h"
#include "core/math.h"
#include "mcmt/tracker_status_t.hpp"
#include "tracker/tracker.h"

namespace mcmt {

const char* CameraStateName(CameraState state) {
  switch (state) {
    case CameraState::kOk:
      return "ok";
    case CameraState::kSuspect:
      return "suspect";
    case CameraState::kExcluded:
      return "excluded";
  }
  return "?";
}

HealthMonitor::HealthMonitor(const std::vector<std::string>& cameras, const HealthOptions& options)
    : options_(options), order_(cameras) {
  for (const std::string& c : cameras) tracks_[c].health.camera = c;
}

double HealthMonitor::Baseline(const Track& t) const {
  if (t.history.empty()) return 0.0;
  return Median(std::vector<double>(t.history.begin(), t.history.end()));
}

bool HealthMonitor::Excluded(const std::string& camera) const {
  const auto it = tracks_.find(camera);
  return it != tracks_.end() && it->second.health.state == CameraState::kExcluded;
}

double HealthMonitor::GatePx(const std::string& camera) const {
  const auto it = tracks_.find(camera);
  if (it == tracks_.end() || !Established(it->second)) return std::numeric_limits<double>::infinity();
  return std::max(options_.gate_px, options_.gate_ratio * Baseline(it->second));
}

bool HealthMonitor::Established(const Track& t) const {
  return static_cast<int>(t.history.size()) >= options_.min_baseline_frames;
}

bool HealthMonitor::Update(const std::string& camera, int64_t utime, double rms_px, bool gated) {
  const auto it = tracks_.find(camera);
  if (it == tracks_.end()) return false;
  Track& t = it->second;
  CameraHealth& h = t.health;
  t.window.push_back(rms_px);
  t.gated.push_back(gated);
  while (static_cast<int>(t.window.size()) > options_.window) {
    t.window.pop_front();
    t.gated.pop_front();
  }
  ++h.frames;
  h.rms_px = Median(std::vector<double>(t.window.begin(), t.window.end()));
  h.rejected_share = static_cast<double>(std::count(t.gated.begin(), t.gated.end(), 1)) /
                     static_cast<double>(t.gated.size());
  h.baseline_px = Baseline(t);
  const CameraState before = h.state;
  const bool full = static_cast<int>(t.window.size()) >= options_.window;
  const bool high = full && Established(t) &&
                    h.rms_px > std::max(options_.suspect_px, options_.suspect_ratio * h.baseline_px);
  if (h.state != CameraState::kExcluded) {
    t.suspect_run = high ? t.suspect_run + 1 : 0;
    if (!high) h.state = CameraState::kOk;
    if (high)
      h.state = t.suspect_run >= options_.exclude_frames ? CameraState::kExcluded : CameraState::kSuspect;
  }
  if (h.state == CameraState::kOk && !gated) {
    t.history.push_back(rms_px);
    if (static_cast<int>(t.history.size()) > options_.baseline_frames) t.history.pop_front();
  }
  if (h.state != before) h.since_utime = utime;
  if (h.state != CameraState::kOk && h.first_suspect_utime < 0) h.first_suspect_utime = utime;
  return h.state != before;
}

CameraHealth HealthMonitor::Of(const std::string& camera) const { return tracks_.at(camera).health; }

std::vector<CameraHealth> HealthMonitor::Snapshot() const {
  std::vector<CameraHealth> out;
  for (const std::string& c : order_) out.push_back(tracks_.at(c).health);
  return out;
}

}  // namespace mcmt

// ---------------------------------------------------------------------------------------------------
// The tracker node's use of it.

namespace mcmt {
namespace {

std::vector<MarkerObservation> Without(const std::vector<MarkerObservation>& obs,
                                       const std::set<std::string>& left_out) {
  std::vector<MarkerObservation> kept;
  for (const MarkerObservation& o : obs)
    if (!left_out.count(o.camera)) kept.push_back(o);
  return kept;
}

std::vector<MarkerObservation> Only(const std::vector<MarkerObservation>& obs, const std::string& camera) {
  std::vector<MarkerObservation> kept;
  for (const MarkerObservation& o : obs)
    if (o.camera == camera) kept.push_back(o);
  return kept;
}

}  // namespace

// A camera's RMS over its markers within outlier_px (one wrong marker is the pose solver's to reject,
// not a sign that the camera moved); when none is, its best marker's.
double TrackerNode::CameraRms(const std::vector<MarkerObservation>& mine, const Rigid3& pose) const {
  double sum = 0.0, best = -1.0;
  int n = 0;
  for (const MarkerObservation& o : mine) {
    const double r = estimator_->RmsAt({o}, pose);
    if (r < 0) continue;
    if (best < 0 || r < best) best = r;
    if (r <= options_.tracker.outlier_px) {
      sum += r * r;
      ++n;
    }
  }
  return n ? std::sqrt(sum / n) : best;
}

// Each camera's RMS under the pose from the others (those not left out); -1 where it cannot be judged.
std::map<std::string, double> TrackerNode::JudgeCameras(const std::vector<MarkerObservation>& obs,
                                                        const std::set<std::string>& cameras,
                                                        const std::set<std::string>& left_out,
                                                        const Rigid3* start) const {
  std::map<std::string, double> rms;
  for (const std::string& c : cameras) {
    rms[c] = -1.0;
    std::set<std::string> without = left_out;
    without.insert(c);
    const std::vector<MarkerObservation> others = Without(obs, without);
    std::set<std::string> other_cameras;
    for (const MarkerObservation& o : others) other_cameras.insert(o.camera);
    if (other_cameras.size() < 2) continue;  // one camera alone fixes the depth too loosely to judge
    Rigid3 from_others;
    if (start) {  // from this frame's pose: one refinement, no restarts
      if (!estimator_->RefinePose(others, *start, &from_others)) continue;
    } else {
      const PoseSolution solved = estimator_->Solve(others, nullptr);
      if (solved.status != PoseStatus::kTracking) continue;
      from_others = solved.rig_from_object;
    }
    const double r = CameraRms(Only(obs, c), from_others);
    if (r >= 0) rms[c] = std::isfinite(r) ? r : 1e3;
  }
  return rms;
}

PoseSolution TrackerNode::SolveJudgingCameras(const std::vector<MarkerObservation>& obs, const Rigid3* prior,
                                              int64_t utime) {
  std::set<std::string> cameras, excluded;
  for (const MarkerObservation& o : obs) {
    cameras.insert(o.camera);
    if (health_->Excluded(o.camera)) excluded.insert(o.camera);
  }
  PoseSolution sol = estimator_->Solve(Without(obs, excluded), prior);
  const Rigid3* start = sol.ok() ? &sol.rig_from_object : prior;
  // Worst first: a moved camera would make the cameras judged against it look moved too, so the camera
  // furthest over its gate is left out and the others judged again without it.
  std::set<std::string> gated = excluded;
  std::map<std::string, double> judged;
  for (;;) {
    std::set<std::string> open;
    for (const std::string& c : cameras)
      if (!gated.count(c)) open.insert(c);
    const std::map<std::string, double> rms = JudgeCameras(obs, open, gated, start);
    std::string worst;
    double worst_excess = 1.0;
    for (const auto& [c, r] : rms) {
      judged[c] = r;
      if (r / health_->GatePx(c) > worst_excess) {
        worst_excess = r / health_->GatePx(c);
        worst = c;
      }
    }
    if (worst.empty()) break;
    gated.insert(worst);
  }
  for (const std::string& c : excluded)  // excluded cameras are still watched
    judged[c] = JudgeCameras(obs, {c}, excluded, start)[c];
  std::string changes;
  for (const auto& [c, r] : judged) {
    if (r < 0 || !health_->Update(c, utime, r, gated.count(c) && !excluded.count(c))) continue;
    const CameraHealth h = health_->Of(c);
    std::ostringstream line;
    line << "camera '" << c << "' " << CameraStateName(h.state) << " (rms " << h.rms_px
         << " px under the pose from the others, baseline " << h.baseline_px << " px)";
    std::cerr << "mcmt-tracker: " << line.str() << std::endl;
    changes += (changes.empty() ? "" : "; ") + line.str();
  }
  if (!health_change_.empty()) {
    changes = health_change_ + (changes.empty() ? "" : "; " + changes);
    health_change_.clear();
  }
  if (gated.size() > excluded.size()) sol = estimator_->Solve(Without(obs, gated), start);
  if (!changes.empty() || utime - last_health_utime_ >= 1000000) PublishHealth(utime, changes);
  return sol;
}

void TrackerNode::PublishHealth(int64_t utime, const std::string& message) {
  last_health_utime_ = utime;
  if (!output_) return;
  tracker_status_t msg;
  msg.utime = utime;
  msg.map_utime = map_utime_ == INT64_MIN ? 0 : map_utime_;
  for (const CameraHealth& h : health_->Snapshot()) {
    camera_health_t c;
    c.camera = h.camera;
    c.state = static_cast<int8_t>(h.state);
    c.rms_px = h.rms_px;
    c.baseline_px = h.baseline_px;
    c.rejected_share = h.rejected_share;
    c.frames = h.frames;
    c.since_utime = h.since_utime;
    msg.cameras.push_back(c);
  }
  msg.num_cameras = static_cast<int32_t>(msg.cameras.size());
  msg.message = message;
  output_->publish(kTrackerStatusChannel, &msg);
}

}  // namespace mcmt
