// TrackerOptions from the rig YAML, map/rig consistency, constant-velocity motion model.
#include <sstream>
#include <stdexcept>

#include "tracker/tracker.h"

namespace mcmt {

TrackerOptions TrackerOptions::FromConfig(const RigConfig& rig) {
  TrackerOptions o;
  const YamlSection& s = rig.tracker;
  s.CheckKnownKeys({"channel", "object", "deadline_ms", "sync_tolerance_ms", "camera_timeout_s",
                    "max_iterations", "huber_px", "outlier_px", "ambiguity_ratio", "max_gap_s",
                    "min_sigma_px", "max_start_markers", "status_period_s", "max_clock_jump_s",
                    "max_wait_ms"});
  o.channel = s.GetString("channel", o.channel);
  o.object = s.GetString("object", o.object);
  // The shared sync: section (also read by the mapper) gives the defaults; tracker: keys override.
  if (rig.sync.Has("tolerance_ms"))
    o.sync_tolerance_ms = rig.sync.GetDouble("tolerance_ms", o.sync_tolerance_ms);
  if (rig.sync.Has("deadline_ms")) o.deadline_ms = rig.sync.GetPositiveDouble("deadline_ms", o.deadline_ms);
  if (rig.sync.Has("camera_timeout_s"))
    o.camera_timeout_s = rig.sync.GetPositiveDouble("camera_timeout_s", o.camera_timeout_s);
  o.sync_tolerance_ms = s.GetDouble("sync_tolerance_ms", o.sync_tolerance_ms);
  o.deadline_ms = s.GetPositiveDouble("deadline_ms", o.deadline_ms);
  o.camera_timeout_s = s.GetPositiveDouble("camera_timeout_s", o.camera_timeout_s);
  o.max_wait_ms = s.GetDouble("max_wait_ms", o.max_wait_ms);
  o.max_clock_jump_s = s.GetDouble("max_clock_jump_s", o.max_clock_jump_s);
  o.max_iterations = s.GetInt("max_iterations", o.max_iterations);
  o.huber_px = s.GetPositiveDouble("huber_px", o.huber_px);
  o.outlier_px = s.GetPositiveDouble("outlier_px", o.outlier_px);
  o.ambiguity_ratio = s.GetDouble("ambiguity_ratio", o.ambiguity_ratio);
  o.max_gap_s = s.GetPositiveDouble("max_gap_s", o.max_gap_s);
  o.min_sigma_px = s.GetDouble("min_sigma_px", o.min_sigma_px);
  o.max_start_markers = s.GetInt("max_start_markers", o.max_start_markers);
  o.status_period_s = s.GetDouble("status_period_s", o.status_period_s);
  try {
    o.Validate();
  } catch (const std::invalid_argument& e) {
    throw ConfigError(rig.path + ": tracker." + e.what());
  }
  return o;
}

void TrackerOptions::Validate() const {
  auto fail = [](const std::string& key, const std::string& what) {
    throw std::invalid_argument(key + ": " + what);
  };
  if (channel.empty()) fail("channel", "must not be empty");
  if (!(deadline_ms > 0)) fail("deadline_ms", "must be > 0");
  if (!(sync_tolerance_ms >= 0)) fail("sync_tolerance_ms", "must be >= 0");
  if (!(camera_timeout_s > 0)) fail("camera_timeout_s", "must be > 0");
  if (!(max_wait_ms >= 0)) fail("max_wait_ms", "must be >= 0 (0: only deadline_ms)");
  if (!(max_clock_jump_s >= 0)) fail("max_clock_jump_s", "must be >= 0 (0: no clock check)");
  if (max_iterations < 1) fail("max_iterations", "must be >= 1");
  if (!(huber_px > 0)) fail("huber_px", "must be > 0");
  if (!(outlier_px > 0)) fail("outlier_px", "must be > 0");
  if (!(ambiguity_ratio >= 1)) fail("ambiguity_ratio", "must be >= 1");
  if (!(max_gap_s > 0)) fail("max_gap_s", "must be > 0");
  if (!(min_sigma_px >= 0)) fail("min_sigma_px", "must be >= 0");
  if (max_start_markers < 1) fail("max_start_markers", "must be >= 1");
  if (!(status_period_s >= 0)) fail("status_period_s", "must be >= 0");
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
