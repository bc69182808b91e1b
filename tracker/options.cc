// TrackerOptions from the rig YAML, map/rig consistency, constant-velocity motion model.
#include "core/options.h"

#include <yaml-cpp/yaml.h>

#include <map>
#include <sstream>
#include <stdexcept>

#include "core/marker.h"
#include "core/objects.h"
#include "tracker/tracker.h"

namespace mcmt {

const OptionTable<TrackerOptions>& TrackerOptionTable() {
  using O = TrackerOptions;
  const auto H = [](auto HealthOptions::*member) { return OptionTable<O>::Of(&O::health, member); };
  static const OptionTable<O>* table =
      &(*new OptionTable<O>("tracker"))
           .Add("channel", &O::channel,
                "output channel of object_pose_t (several bodies: their prefix, channel_NAME)", NotEmpty())
           .Add("object", &O::object, "object name put in object_pose_t")
           .Add("deadline_ms", &O::deadline_ms, "ms",
                "solve a frame at the latest this long after its first detection "
                "(default: sync.deadline_ms)",
                Above(0))
           .Add("sync_tolerance_ms", &O::sync_tolerance_ms, "ms",
                "detections this close in utime form one frame (default: sync.tolerance_ms; neither set and "
                "the map has clock offsets: chosen from the cameras' phases over their first frames, half "
                "the slowest frame interval, at most 100, when they are not triggered together)",
                AtLeast(0))
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
           .Add("corner_weights", OptionTable<O>::Of(&O::corner_weighting, &CornerWeighting::mode),
                kCornerWeightsHelp, OneOf({"equal", "sides"}))
           .Add("corner_weight_floor", OptionTable<O>::Of(&O::corner_weighting, &CornerWeighting::floor), "",
                kCornerWeightFloorHelp, AtLeast(0))
           .Add("ambiguity_ratio", &O::ambiguity_ratio, "",
                "tau_e: a single square is ambiguous when its IPPE ratio, or the RMS ratio of its best other "
                "refined pose (> 1 deg away) to the published one, is below it",
                AtLeast(1))
           .Add("max_gap_s", &O::max_gap_s, "s", "no prediction across a longer gap (re-initialise)",
                Above(0))
           .Add("min_sigma_px", &O::min_sigma_px, "px",
                "floor of the residual standard deviation of the covariance", AtLeast(0))
           .Add("noise_prior_residuals", &O::noise_prior_residuals, "",
                "the covariance's noise variance pools the frame's residuals with this many pseudo-residuals "
                "at the map's noise (its cameras' rms_px^2 / 2 per coordinate): "
                "sigma^2 = (RSS + nu0 sigma0^2) / (N - 6 + nu0); a single square alone has N - 6 = 2 "
                "(0: the frame's residuals alone)",
                AtLeast(0))
           .Add("map_uncertainty", &O::map_uncertainty,
                "the published covariance holds the map's error (the map file's covariance, written by "
                "mcmt-mapper) as well as the frame's noise; false: the frame's noise alone")
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
                AtLeast(1))
           .Add("health_unjudged_frames", H(&HealthOptions::unjudged_frames), "frames",
                "a camera that reported in this many frames and was never judged (never with two other "
                "cameras within the sync tolerance) is 'not judged', said once with the cure",
                AtLeast(1))
           .Other("channels", "",
                  "several bodies: channel per pose stream by its name, e.g. {tool: TOOL_POSE, "
                  "tool_in_patient: NAV} (default: channel_NAME, channel_OF_IN_IN)")
           .Other("relative", "",
                  "several bodies: relative poses to publish, e.g. [{of: tool, in: patient}] -> "
                  "MCMT_POSE_TOOL_IN_PATIENT (patient_from_tool, covariance from both)");
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

void CheckStreamOptions(const TrackerOptions& o, const std::string& file) {
  for (const auto& [name, channel] : o.channels)
    if (channel.empty()) TrackerOptionTable().Fail(file, "channels." + name, "must not be empty");
  for (size_t i = 0; i < o.relative.size(); ++i) {
    const std::string key = "relative[" + std::to_string(i) + "]";
    if (o.relative[i].of.empty()) TrackerOptionTable().Fail(file, key + ".of", "missing (a body's name)");
    if (o.relative[i].in.empty()) TrackerOptionTable().Fail(file, key + ".in", "missing (a body's name)");
    if (o.relative[i].of == o.relative[i].in)
      TrackerOptionTable().Fail(file, key, "'" + o.relative[i].of + "' relative to itself");
  }
}

// tracker.channels: {name: channel} and tracker.relative: [{of: A, in: B}] (OptionTable Other keys).
void LoadStreamOptions(const YamlSection& section, TrackerOptions* o) {
  if (section.Has("channels")) {
    const YamlSection channels = section.Child("channels");
    for (auto it = channels.node().begin(); it != channels.node().end(); ++it) {
      const std::string name = it->first.Scalar();
      if (!it->second.IsScalar()) channels.Fail(name, "expected a channel name");
      o->channels[name] = it->second.Scalar();
    }
  }
  if (section.Has("relative")) {
    const YAML::Node list = section.node()["relative"];
    if (!list.IsSequence()) section.Fail("relative", "expected a list like [{of: tool, in: patient}]");
    for (size_t i = 0; i < list.size(); ++i) {
      const YamlSection item(list[i], section.file(), section.KeyName("relative[" + std::to_string(i) + "]"));
      if (!list[i].IsMap()) item.Fail("of", "expected {of: BODY, in: BODY}");
      item.CheckKnownKeys({"of", "in"});
      o->relative.push_back({item.GetString("of", ""), item.GetString("in", "")});
    }
  }
}

std::string Names(const std::vector<BodyName>& bodies) {
  std::string out;
  for (size_t i = 0; i < bodies.size(); ++i) out += (i ? ", " : "") + bodies[i].name;
  return out;
}

}  // namespace

std::vector<BodyName> MapBodies(const RigMap& map, const std::string& single_name) {
  if (map.objects.empty()) return {{single_name, false}};
  std::vector<BodyName> out;
  for (const MapObject& o : map.objects) out.push_back({o.name, o.is_static});
  return out;
}

std::vector<PoseStreamPlan> PlanPoseStreams(const TrackerOptions& o, const std::vector<BodyName>& bodies,
                                            bool single, const std::string& file) {
  const auto& table = TrackerOptionTable();
  auto find = [&](const std::string& key, const std::string& name) {
    for (size_t k = 0; k < bodies.size(); ++k)
      if (bodies[k].name == name) return static_cast<int>(k);
    table.Fail(file, key, "no body named '" + name + "' (bodies: " + Names(bodies) + ")");
  };
  std::vector<PoseStreamPlan> plan;
  std::vector<std::string> keys;  // the key that set each stream's channel
  auto channel_of = [&](const std::string& name, const std::string& fallback, const std::string& key) {
    const auto it = o.channels.find(name);
    keys.push_back(it != o.channels.end() ? "channels." + name : key);
    return it != o.channels.end() ? it->second : fallback;
  };
  for (size_t k = 0; k < bodies.size(); ++k) {
    if (bodies[k].is_static) continue;
    PoseStreamPlan p;
    p.name = bodies[k].name;
    p.body = static_cast<int>(k);
    p.channel = channel_of(p.name, single ? o.channel : o.channel + "_" + ChannelSuffix(p.name), "channel");
    plan.push_back(p);
  }
  if (plan.empty())
    table.Fail(file, "relative", "the map has no moving body to track (" + Names(bodies) + ")");
  for (size_t i = 0; i < o.relative.size(); ++i) {
    const std::string key = "relative[" + std::to_string(i) + "]";
    PoseStreamPlan p;
    p.of = find(key + ".of", o.relative[i].of);
    p.in = find(key + ".in", o.relative[i].in);
    if (bodies[p.of].is_static)
      table.Fail(file, key + ".of", "'" + o.relative[i].of + "' is a static body (not tracked)");
    p.name = o.relative[i].of + "_in_" + o.relative[i].in;
    p.channel = channel_of(
        p.name, o.channel + "_" + ChannelSuffix(o.relative[i].of) + "_IN_" + ChannelSuffix(o.relative[i].in),
        key);
    plan.push_back(p);
  }
  for (const auto& [name, channel] : o.channels) {
    bool known = false;
    for (const PoseStreamPlan& p : plan) known = known || p.name == name;
    if (known) continue;
    const int k = find("channels." + name, name);
    table.Fail(file, "channels." + name, "'" + bodies[k].name + "' is a static body (not tracked)");
  }
  const std::vector<std::string> reserved = {kMapChannel, kMapperStatusChannel, kMapperCommandChannel,
                                             kTrackerStatusChannel};
  for (size_t a = 0; a < plan.size(); ++a) {
    for (const std::string& r : reserved)
      if (plan[a].channel == r)
        table.Fail(file, keys[a],
                   "channel " + r + " of '" + plan[a].name + "' is an mcmt channel of another type");
    if (IsDetectionsChannel(plan[a].channel))
      table.Fail(file, keys[a],
                 "channel " + plan[a].channel + " of '" + plan[a].name + "' is a detections channel");
    for (size_t b = 0; b < a; ++b)
      if (plan[a].channel == plan[b].channel) {
        // Name the key that was set by hand (channels.NAME) when one was.
        const bool b_set = keys[b].rfind("channels.", 0) == 0 && keys[a].rfind("channels.", 0) != 0;
        table.Fail(file, b_set ? keys[b] : keys[a],
                   "channel " + plan[a].channel + " of '" + plan[b_set ? b : a].name + "' is also '" +
                       plan[b_set ? a : b].name + "''s (two pose streams on one channel)");
      }
  }
  return plan;
}

TrackerOptions TrackerOptions::FromConfig(const RigConfig& rig) {
  TrackerOptions o;
  // The shared sync: section gives the defaults; tracker: keys override.
  const SyncOptions sync = LoadSyncOptions(rig);
  o.sync_tolerance_ms = sync.tolerance_ms;
  o.deadline_ms = sync.deadline_ms;
  o.camera_timeout_s = sync.camera_timeout_s;
  TrackerOptionTable().Load(rig.tracker, &o);
  o.sync_tolerance_set = rig.tracker.Has("sync_tolerance_ms") || rig.sync.Has("tolerance_ms");
  LoadStreamOptions(rig.tracker, &o);
  CheckBetweenOptions(o, rig.tracker.file());
  CheckStreamOptions(o, rig.tracker.file());
  // Bodies declared in the rig: relative poses and channels are checked against them now (a map's bodies
  // are checked again when it arrives).
  if (rig.objects.declared && !rig.objects.auto_objects) {
    std::vector<BodyName> bodies;
    bool any_auto = false;
    for (const ObjectConfig& c : rig.objects.objects) {
      bodies.push_back({c.name, c.is_static});
      any_auto = any_auto || c.auto_ids;
    }
    // (One declared object is mapped as a single object: a version 1 map.)
    if (!any_auto && bodies.size() >= 2) PlanPoseStreams(o, bodies, false, rig.tracker.file());
  }
  return o;
}

void TrackerOptions::Validate() const {
  TrackerOptionTable().Check(*this);
  CheckBetweenOptions(*this, "");
  CheckStreamOptions(*this, "");
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

bool MotionModel::Motion(int64_t from, int64_t to, Rigid3* rig_motion) const {
  const int64_t dt_prev = utime_[0] - utime_[1];
  if (count_ < 2 || dt_prev <= 0 || dt_prev > max_gap_us_) return false;
  Rigid3 at_from, at_to;
  if (!Predict(from, &at_from) || !Predict(to, &at_to)) return false;
  *rig_motion = at_to * Inverse(at_from);
  return true;
}

}  // namespace mcmt
