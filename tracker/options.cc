// TrackerOptions from the rig YAML, map/rig consistency, constant-velocity motion model.
#include "core/options.h"

#include <sstream>
#include <stdexcept>

#include "tracker/tracker.h"

namespace mcmt {

const OptionTable<TrackerOptions>& TrackerOptionTable() {
  using O = TrackerOptions;
  const auto H = [](auto HealthOptions::*member) { return OptionTable<O>::Of(&O::health, member); };
  static const OptionTable<O>* table =
      &(*new OptionTable<O>("tracker"))
           .Add("channel", &O::channel, "output channel of object_pose_t", NotEmpty())
           .Add("object", &O::object, "object name put in object_pose_t")
           .Add("deadline_ms", &O::deadline_ms, "ms",
                "solve a frame at the latest this long after its first detection "
                "(default: sync.deadline_ms)",
                Above(0))
           .Add("sync_tolerance_ms", &O::sync_tolerance_ms, "ms",
                "detections this close in utime form one frame (default: sync.tolerance_ms)", AtLeast(0))
           .Add("camera_timeout_s", &O::camera_timeout_s, "s",
                "a camera silent this long is not waited for (default: sync.camera_timeout_s)", Above(0))
           .Add("max_wait_ms", &O::max_wait_ms, "ms",
                "live: a frame missing a lagging camera waits for it up to this long (0: only deadline_ms)",
                AtLeast(0))
           .Add("max_clock_jump_s", &O::max_clock_jump_s, "s",
                "a message this far ahead of its camera's clock is rejected (0: no check)", AtLeast(0))
           .Add("max_iterations", &O::max_iterations, "", "Levenberg-Marquardt iterations per start",
                AtLeast(1))
           .Add("huber_px", &O::huber_px, "px", "Huber threshold of the robust loss (corner distance)",
                Above(0))
           .Add("outlier_px", &O::outlier_px, "px",
                "a marker observation whose RMS corner error exceeds this is dropped", Above(0))
           .Add("ambiguity_ratio", &O::ambiguity_ratio, "",
                "tau_e: a single square with IPPE ratio below it is ambiguous", AtLeast(1))
           .Add("max_gap_s", &O::max_gap_s, "s", "no prediction across a longer gap (re-initialise)",
                Above(0))
           .Add("min_sigma_px", &O::min_sigma_px, "px",
                "floor of the residual standard deviation of the covariance", AtLeast(0))
           .Add("max_start_markers", &O::max_start_markers, "",
                "when lost: IPPE hypotheses of at most this many "
                "observations",
                AtLeast(1))
           .Add("status_period_s", &O::status_period_s, "s", "status line period, wall time (0: none)",
                AtLeast(0))
           .Add("camera_health", &O::camera_health,
                "judge each camera under the pose from the others (suspect, excluded; MCMT_TRACKER_STATUS)")
           .Add("health_gate_px", H(&HealthOptions::gate_px), "px",
                "a camera's markers are left out of a frame whose RMS under the pose from the others "
                "exceeds max(this, health_gate_ratio x its baseline)",
                Above(0))
           .Add("health_gate_ratio", H(&HealthOptions::gate_ratio), "", "see health_gate_px", AtLeast(1))
           .Add("health_suspect_px", H(&HealthOptions::suspect_px), "px",
                "suspect when the median RMS of the last health_window_frames exceeds max(this, "
                "health_suspect_ratio x its baseline)",
                Above(0))
           .Add("health_suspect_ratio", H(&HealthOptions::suspect_ratio), "", "see health_suspect_px",
                AtLeast(1))
           .Add("health_window_frames", H(&HealthOptions::window), "frames",
                "judged frames in the median that decides suspect", AtLeast(1))
           .Add("health_exclude_frames", H(&HealthOptions::exclude_frames), "frames",
                "suspect this many judged frames in a row: excluded from every pose until a new map or "
                "until it is good again (health_recover_frames)",
                AtLeast(1))
           .Add("health_baseline_frames", H(&HealthOptions::baseline_frames), "frames",
                "a camera's baseline: the median RMS of its last this many judged frames while ok",
                AtLeast(1))
           .Add("health_min_baseline_frames", H(&HealthOptions::min_baseline_frames), "frames",
                "judged frames while ok before a camera can be gated or suspected", AtLeast(1))
           .Add("health_recover_ratio", H(&HealthOptions::recover_ratio), "",
                "an excluded camera is good when its median RMS is at most this x its suspect threshold (0: "
                "never, it waits for a new map)",
                InRange(0, 1))
           .Add("health_recover_frames", H(&HealthOptions::recover_frames), "frames",
                "good this many judged frames in a row: an excluded camera is used again (no new map)",
                AtLeast(1));
  return *table;
}

namespace {

void CheckBetweenOptions(const TrackerOptions& o, const std::string& file) {
  if (o.health.min_baseline_frames > o.health.baseline_frames)
    TrackerOptionTable().Fail(file, "health_min_baseline_frames",
                              "must be <= health_baseline_frames (" +
                                  std::to_string(o.health.baseline_frames) + "), got " +
                                  std::to_string(o.health.min_baseline_frames));
}

}  // namespace

TrackerOptions TrackerOptions::FromConfig(const RigConfig& rig) {
  TrackerOptions o;
  // The shared sync: section gives the defaults; tracker: keys override.
  const SyncOptions sync = LoadSyncOptions(rig);
  o.sync_tolerance_ms = sync.tolerance_ms;
  o.deadline_ms = sync.deadline_ms;
  o.camera_timeout_s = sync.camera_timeout_s;
  TrackerOptionTable().Load(rig.tracker, &o);
  CheckBetweenOptions(o, rig.tracker.file());
  return o;
}

void TrackerOptions::Validate() const {
  TrackerOptionTable().Check(*this);
  CheckBetweenOptions(*this, "");
}

void CheckMapMatchesRig(const RigMap& map, const RigConfig& rig, const std::string& map_name) {
  for (const auto& c : map.cameras) {
    if (rig.FindCamera(c.name)) continue;
    std::ostringstream names;
    for (size_t i = 0; i < rig.cameras.size(); ++i) names << (i ? ", " : "") << rig.cameras[i].name;
    throw std::runtime_error(map_name + ": camera '" + c.name + "' is not a camera of " + rig.path + " (" +
                             names.str() + "): a map of another rig?");
  }
}

void MotionModel::Update(int64_t utime, const Rigid3& rig_from_object) {
  if (count_ > 0 && utime <= utime_[0]) return;  // never goes back in time
  utime_[1] = utime_[0];
  pose_[1] = pose_[0];
  utime_[0] = utime;
  pose_[0] = rig_from_object;
  count_ = std::min(count_ + 1, 2);
}

bool MotionModel::Predict(int64_t utime, Rigid3* predicted) const {
  if (count_ == 0 || utime - utime_[0] > max_gap_us_) return false;
  *predicted = pose_[0];
  const int64_t dt_prev = utime_[0] - utime_[1];
  if (count_ < 2 || dt_prev <= 0 || dt_prev > max_gap_us_ || utime <= utime_[0]) return true;
  // Constant velocity in the rig frame: step = pose0 * inv(pose1), scaled to the time ahead.
  const double scale = static_cast<double>(utime - utime_[0]) / static_cast<double>(dt_prev);
  const Eigen::Matrix3d r_step = pose_[0].linear() * pose_[1].linear().transpose();
  const Eigen::Vector3d t_step = pose_[0].translation() - r_step * pose_[1].translation();
  const Eigen::AngleAxisd aa(r_step);
  const Eigen::Matrix3d r_scaled = Eigen::AngleAxisd(aa.angle() * scale, aa.axis()).toRotationMatrix();
  Rigid3 step = Rigid3::Identity();
  step.linear() = r_scaled;
  step.translation() = t_step * scale;
  Rigid3 out = step * pose_[0];
  out.linear() = Eigen::Quaterniond(out.linear()).normalized().toRotationMatrix();
  *predicted = out;
  return true;
}

}  // namespace mcmt
