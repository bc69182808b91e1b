// Per-camera health (tracker/health.h has the rules).
#include "tracker/health.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include "core/lcm_util.h"
#include "core/math.h"
#include "core/rigid_pose.h"
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
    case CameraState::kNotJudged:
      return "not judged";
  }
  return "?";
}

HealthMonitor::HealthMonitor(const std::vector<std::string>& cameras, const HealthOptions& options)
    : options_(options), order_(cameras) {
  for (const std::string& c : cameras) tracks_[c].health.camera = c;
}

// The median of the history (core's Median picks the element at size / 2 of the sorted values: the
// same one, kept sorted instead of sorted again every frame).
double HealthMonitor::Baseline(const Track& t) const {
  return t.sorted_history.empty() ? 0.0 : t.sorted_history[t.sorted_history.size() / 2];
}

void HealthMonitor::AddToBaseline(double rms_px, Track* t) const {
  t->history.push_back(rms_px);
  t->sorted_history.insert(std::upper_bound(t->sorted_history.begin(), t->sorted_history.end(), rms_px),
                           rms_px);
  if (static_cast<int>(t->history.size()) <= options_.baseline_frames) return;
  t->sorted_history.erase(
      std::lower_bound(t->sorted_history.begin(), t->sorted_history.end(), t->history.front()));
  t->history.pop_front();
}

double HealthMonitor::SuspectPx(const Track& t) const {
  return std::max(options_.suspect_px, options_.suspect_ratio * Baseline(t));
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
  const bool high = full && Established(t) && h.rms_px > SuspectPx(t);
  if (h.state != CameraState::kExcluded) {
    t.suspect_run = high ? t.suspect_run + 1 : 0;
    if (!high) h.state = CameraState::kOk;
    if (high)
      h.state = t.suspect_run >= options_.exclude_frames ? CameraState::kExcluded : CameraState::kSuspect;
  } else {
    // Hysteresis: back only when well under the suspect threshold for recover_frames in a row.
    const bool good = full && h.rms_px <= options_.recover_ratio * SuspectPx(t);
    t.recover_run = good ? t.recover_run + 1 : 0;
    if (t.recover_run >= options_.recover_frames) {
      h.state = CameraState::kOk;
      t.recover_run = 0;
      t.suspect_run = 0;
    }
  }
  if (h.state == CameraState::kOk && !gated) AddToBaseline(rms_px, &t);
  if (h.state != before) h.since_utime = utime;
  if ((h.state == CameraState::kSuspect || h.state == CameraState::kExcluded) && h.first_suspect_utime < 0)
    h.first_suspect_utime = utime;
  return h.state != before;
}

bool HealthMonitor::NotJudged(const std::string& camera, int64_t utime) {
  const auto it = tracks_.find(camera);
  if (it == tracks_.end()) return false;
  CameraHealth& h = it->second.health;
  if (h.frames > 0 || h.state == CameraState::kNotJudged) return false;
  if (++h.unjudged_frames < options_.unjudged_frames) return false;
  h.state = CameraState::kNotJudged;
  h.since_utime = utime;
  return true;
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
//
// A camera is judged under the pose from the others without solving again: at the frame's pose P (solved
// from every camera not excluded) each camera's inlier observations give its share (H_c, g_c) of the
// Gauss-Newton normal equations (core's PoseNormalEquations, the solver's Huber weights, rotation about
// P's origin); the others' pose is one step from P on the normal equations without that share,
// (sum_{k != c} H_k) dx = -(sum_{k != c} g_k), P (+) dx. P is the others' optimum up to the pull of camera
// c, which is what the step takes out (a moved camera's few pixels move P by far less than the region
// where the problem is linear), so this costs one pass over the frame's corners and a 6x6 solve per
// camera instead of a refinement per camera.

namespace mcmt {
namespace {

std::vector<MarkerObservation> Without(const std::vector<MarkerObservation>& obs,
                                       const std::set<std::string>& left_out) {
  std::vector<MarkerObservation> kept;
  for (const MarkerObservation& o : obs)
    if (!left_out.count(o.camera)) kept.push_back(o);
  return kept;
}

// One camera's part of the frame at the frame's pose.
struct CameraShare {
  std::vector<std::vector<PosePoint>> markers;  // its mapped observations' corners
  Matrix6d h = Matrix6d::Zero();                // its inliers' J^T W J and J^T W r at the frame's pose
  Vector6d g = Vector6d::Zero();
  int inliers = 0;
};

// The shares of every camera with a mapped observation, at `pose` (an observation within outlier_px of
// it is an inlier, as for the solver).
std::map<std::string, CameraShare> Shares(const PoseEstimator& estimator, const TrackerOptions& o,
                                          const std::vector<MarkerObservation>& obs, const Rigid3& pose) {
  std::map<std::string, CameraShare> shares;
  Matrix6d h;
  Vector6d g;
  for (const MarkerObservation& ob : obs) {
    std::vector<PosePoint> points = estimator.PosePoints(ob);
    if (points.empty()) continue;
    CameraShare& share = shares[ob.camera];
    double squares = 0.0;
    PoseNormalEquations(points, pose, pose.translation(), o.huber_px, &h, &g, &squares);
    if (squares <= 4.0 * o.outlier_px * o.outlier_px) {
      share.h += h;
      share.g += g;
      ++share.inliers;
    }
    share.markers.push_back(std::move(points));
  }
  return shares;
}

// A camera's RMS over its markers within outlier_px (one wrong marker is the pose solver's to reject,
// not a sign that the camera moved) and their number; when none is, its best marker's (one marker); rms
// -1 without a marker.
struct CameraResidual {
  double rms = -1.0;
  int markers = 0;
};
CameraResidual CameraRms(const CameraShare& share, const Rigid3& pose, double outlier_px) {
  double sum = 0.0, best = -1.0;
  int n = 0;
  for (const std::vector<PosePoint>& marker : share.markers) {
    const double r = std::sqrt(PoseSquaredError(marker, pose) / 4.0);
    if (best < 0 || r < best) best = r;
    if (r <= outlier_px) {
      sum += r * r;
      ++n;
    }
  }
  if (n) return {std::sqrt(sum / n), n};
  return {best, best < 0 ? 0 : 1};
}

// The pose from the cameras in `from` (their inlier shares), one Gauss-Newton step from `pose`; false
// when fewer than two of them have an inlier (one camera alone fixes the depth too loosely to judge) or
// the step is not determined.
bool PoseFrom(const std::map<std::string, CameraShare>& shares, const std::set<std::string>& from,
              const Rigid3& pose, Rigid3* out) {
  Matrix6d h = Matrix6d::Zero();
  Vector6d g = Vector6d::Zero();
  int cameras = 0;
  for (const std::string& c : from) {
    const auto it = shares.find(c);
    if (it == shares.end() || it->second.inliers == 0) continue;
    h += it->second.h;
    g += it->second.g;
    ++cameras;
  }
  if (cameras < 2) return false;
  h.diagonal() += Vector6d::Constant(1e-12);
  const Eigen::LDLT<Matrix6d> ldlt(h);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return false;
  const Vector6d dx = ldlt.solve(-g);
  if (!dx.allFinite()) return false;
  *out = ApplyPoseStep(pose, dx, pose.translation());
  return true;
}

// Each camera of `judged` under the pose from the cameras of `used` other than itself; rms -1 where it
// cannot be judged.
std::map<std::string, CameraResidual> Judge(const std::map<std::string, CameraShare>& shares,
                                            const std::set<std::string>& judged,
                                            const std::set<std::string>& used, const Rigid3& pose,
                                            double outlier_px) {
  std::map<std::string, CameraResidual> rms;
  for (const std::string& c : judged) {
    rms[c] = CameraResidual();
    const auto mine = shares.find(c);
    if (mine == shares.end()) continue;
    std::set<std::string> others = used;
    others.erase(c);
    Rigid3 from_others;
    if (!PoseFrom(shares, others, pose, &from_others)) continue;
    CameraResidual r = CameraRms(mine->second, from_others, outlier_px);
    if (r.rms >= 0 && !std::isfinite(r.rms)) r.rms = 1e3;
    rms[c] = r;
  }
  return rms;
}

// The cameras of `names`, quoted: "camera 'cam1'" or "cameras 'cam1', 'cam3'".
std::string CamerasText(const std::vector<std::string>& names) {
  std::string out = names.size() == 1 ? "camera " : "cameras ";
  for (size_t k = 0; k < names.size(); ++k) out += (k ? ", '" : "'") + names[k] + "'";
  return out;
}

}  // namespace

PoseSolution TrackerNode::SolveJudgingCameras(const PoseEstimator& estimator,
                                              const std::vector<MarkerObservation>& obs, const Rigid3* prior,
                                              FrameJudgement* frame) {
  std::set<std::string> cameras, excluded;
  for (const MarkerObservation& o : obs) {
    cameras.insert(o.camera);
    if (health_->Excluded(o.camera)) excluded.insert(o.camera);
  }
  PoseSolution sol = estimator.Solve(Without(obs, excluded), prior);
  std::map<std::string, CameraShare> shares;  // none when lost: nothing to judge against
  if (sol.ok()) shares = Shares(estimator, options_.tracker, obs, sol.rig_from_object);
  for (const auto& [c, share] : shares) {
    frame->seen.insert(c);
    int& most = frame->companions[c];
    most = std::max(most, static_cast<int>(shares.size()) - 1);
  }
  // Worst first: a moved camera would make the cameras judged against it look moved too, so the camera
  // furthest over its gate is left out and the others judged again without it.
  std::set<std::string> gated = excluded;
  std::map<std::string, CameraResidual> judged;
  for (;;) {
    std::set<std::string> open;
    for (const std::string& c : cameras)
      if (!gated.count(c)) open.insert(c);
    const std::map<std::string, CameraResidual> rms =
        Judge(shares, open, open, sol.rig_from_object, options_.tracker.outlier_px);
    std::string worst;
    double worst_excess = 1.0;
    for (const auto& [c, r] : rms) {
      judged[c] = r;
      if (r.rms / health_->GatePx(c) > worst_excess) {
        worst_excess = r.rms / health_->GatePx(c);
        worst = c;
      }
    }
    if (worst.empty()) break;
    gated.insert(worst);
  }
  std::set<std::string> used;  // excluded cameras are still watched, under the pose from the cameras used
  for (const std::string& c : cameras)
    if (!gated.count(c)) used.insert(c);
  for (const auto& [c, r] : Judge(shares, excluded, used, sol.rig_from_object, options_.tracker.outlier_px))
    judged[c] = r;
  // Pooled over the frame's bodies: the squares and markers of each body a camera was judged on.
  for (const auto& [c, r] : judged) {
    if (r.rms < 0 || r.markers == 0) continue;
    CameraJudgement& j = frame->cameras[c];
    j.squares += r.rms * r.rms * r.markers;
    j.markers += r.markers;
    j.gated = j.gated || (gated.count(c) && !excluded.count(c));
  }
  if (gated.size() > excluded.size()) {
    const Rigid3 start = sol.rig_from_object;
    sol = estimator.Solve(Without(obs, gated), &start);
  }
  return sol;
}

void TrackerNode::UpdateHealth(const FrameJudgement& frame, int64_t utime) {
  std::string changes;
  for (const auto& [c, j] : frame.cameras) {
    const double rms = std::sqrt(j.squares / j.markers);
    if (!health_->Update(c, utime, rms, j.gated)) continue;
    const CameraHealth h = health_->Of(c);
    std::ostringstream line;
    line << "camera '" << c << "' " << CameraStateName(h.state) << " (rms " << h.rms_px
         << " px under the pose from the others, baseline " << h.baseline_px << " px)";
    std::cerr << "mcmt-tracker: " << line.str() << std::endl;
    changes += (changes.empty() ? "" : "; ") + line.str();
  }
  // Cameras that report but are never judged: said once, in one line per kind, with the cure.
  // A camera's frame counts as unjudged only while two other cameras see a body too (within the last
  // second, in other frames): alone because nobody else sees the object is not a clock problem.
  for (const auto& [c, n] : frame.companions) companions_[c] = std::max(companions_[c], n);
  for (const std::string& c : frame.seen) last_seen_utime_[c] = utime;
  std::vector<std::string> alone, paired;
  for (const std::string& c : frame.seen) {
    if (frame.cameras.count(c)) continue;
    int others = 0;
    for (const auto& [o, seen_utime] : last_seen_utime_) others += o != c && utime - seen_utime <= 1000000;
    if (others >= 2 && health_->NotJudged(c, utime)) (companions_[c] == 0 ? alone : paired).push_back(c);
  }
  for (const bool single : {true, false}) {
    const std::vector<std::string>& names = single ? alone : paired;
    if (names.empty()) continue;
    const bool one = names.size() == 1;
    std::ostringstream line;
    line << CamerasText(names)
         << (single ? (one ? " never shares" : " never share") : (one ? " shares" : " share"))
         << (single ? " a frame with another camera"
                    : " frames with one other camera at most (two are needed)")
         << " within the sync tolerance (" << options_.tracker.sync_tolerance_ms << " ms) in "
         << options_.tracker.health.unjudged_frames
         << " frames while two others see the object: " << (one ? "its" : "their")
         << " health cannot be judged (state 'not judged'); if the cameras' clocks differ, map with "
            "mapper.time_offsets: true (the map's time_offset_us are applied to the detections) or widen "
            "tracker.sync_tolerance_ms";
    std::cerr << "mcmt-tracker: warning: " << line.str() << std::endl;
    changes += (changes.empty() ? "" : "; ") + line.str();
  }
  if (!health_change_.empty()) {
    changes = health_change_ + (changes.empty() ? "" : "; " + changes);
    health_change_.clear();
  }
  // INT64_MIN: none published yet (utime minus it would overflow).
  const bool due = last_health_utime_ == INT64_MIN || utime - last_health_utime_ >= 1000000;
  if (!changes.empty() || due) PublishHealth(utime, changes);
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
