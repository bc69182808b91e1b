// The tracker applies the map's per-camera clock offsets and drifts (map.yaml time_offset_us,
// time_drift_ppm, issue 18): a camera whose clock reads 15 ms late (and drifts) joins the frames it was
// captured in.
#include <gtest/gtest.h>

#include <lcm/lcm-cpp.hpp>
#include <map>
#include <set>
#include <string>

#include "core/lcm_util.h"
#include "core/se3.h"
#include "sim/sim.h"
#include "tests/support/temp_dir.h"
#include "tests/support/tracker_sim.h"
#include "tracker/tracker.h"

namespace mcmt {
namespace {

// The simulator's session: 5 cameras on a 1 m circle, the cube (one 4 cm marker per face), 150 frames at
// 30 fps, 0.1 px corner noise, sim's defaults otherwise (no distortion); the map and the truth in the
// tracker's frames (tests/support/tracker_sim.h: rig = cam0, object = marker 0).
struct Rig {
  test::TrackerSim sim;
  RigConfig config;
};

Rig MakeRig(const std::string& name) {
  sim::SessionOptions o;
  o.object.kind = sim::ObjectKind::kCube;
  o.trajectory.frames = 150;
  Rig r;
  r.sim = test::SimulateTracking(o);
  r.config = LoadRigConfig(sim::WriteSessionRig(test::MakeTempDir("tracker_" + name), r.sim.session));
  return r;
}

TrackerNodeOptions LogMode() {
  TrackerNodeOptions o;
  o.log_mode = true;
  o.keep_trajectory = true;
  o.quiet = true;
  return o;
}

// Poses (seq, cameras used) from feeding the session with cam2's clock 15 ms late, drifting by drift_ppm
// from the session's middle on.
// set_tolerance: the 2 ms sync tolerance as set by hand (no window chosen from the cameras' phases).
std::vector<TrajectoryRow> Track(const sim::Session& session, const RigMap& map, const RigConfig& rig,
                                 double drift_ppm = 0.0, bool set_tolerance = false) {
  lcm::LCM in("memq://");
  TrackerNodeOptions options = LogMode();
  options.tracker.sync_tolerance_set = set_tolerance;
  TrackerNode node(in, rig, options, map);
  std::vector<detections_t> all;
  const int64_t middle = session.frames()[session.frames().size() / 2].utime;
  for (const auto& frame : session.views)
    for (detections_t d : frame) {
      if (d.camera == "cam2")
        d.utime += 15000 + std::llround(1e-6 * drift_ppm * static_cast<double>(d.utime - middle));
      all.push_back(d);
    }
  std::stable_sort(all.begin(), all.end(),
                   [](const detections_t& a, const detections_t& b) { return a.utime < b.utime; });
  for (const detections_t& d : all) {
    const auto bytes = Encode(d);
    node.OnDetections(DetectionsChannel(d.camera), bytes.data(), bytes.size());
  }
  node.Flush();
  return node.trajectory();
}

TEST(TrackerTimeOffsets, LateCameraJoinsItsFramesWithTheMapsOffset) {
  const Rig r = MakeRig("offsets");
  const sim::Session& session = r.sim.session;
  const RigConfig& rig = r.config;
  RigMap with_offset = r.sim.map;
  for (MapCamera& c : with_offset.cameras)
    if (c.name == "cam2") c.time_offset_us = 15000;
  const std::vector<TrajectoryRow> ignored = Track(session, r.sim.map, rig);
  testing::internal::CaptureStderr();
  const std::vector<TrajectoryRow> applied = Track(session, with_offset, rig);
  const std::string log = testing::internal::GetCapturedStderr();
  // The map has an offset, so the cameras' phases were measured: once corrected they are triggered
  // together and the window stays at the default 2 ms (the poses below are those of a synchronised rig).
  EXPECT_NE(log.find("mcmt-tracker: sync window 2 ms"), std::string::npos) << log;
  EXPECT_NE(log.find("triggered together"), std::string::npos) << log;
  const std::vector<TrajectoryRow> set_by_hand = Track(session, with_offset, rig, 0.0, true);
  ASSERT_EQ(set_by_hand.size(), applied.size());
  for (size_t f = 0; f < applied.size(); ++f) {
    EXPECT_EQ(set_by_hand[f].cameras, applied[f].cameras) << f;
    EXPECT_EQ(set_by_hand[f].rig_from_object.matrix(), applied[f].rig_from_object.matrix()) << f;
  }
  auto max_cameras = [](const std::vector<TrajectoryRow>& rows) {
    int m = 0;
    for (const TrajectoryRow& r : rows) m = std::max(m, r.cameras);
    return m;
  };
  // Without the offset cam2's views miss their frames (15 ms > the 2 ms sync tolerance).
  EXPECT_LT(max_cameras(ignored), 5);
  ASSERT_EQ(applied.size(), session.views.size());
  EXPECT_EQ(max_cameras(applied), 5);
  for (size_t f = 0; f < applied.size(); ++f) {
    EXPECT_EQ(applied[f].utime, r.sim.truth[f].utime) << f;  // the reference clock
    EXPECT_LT(TranslationDistance(applied[f].rig_from_object, r.sim.truth[f].rig_from_object), 2e-3) << f;
  }
}

// A clock that also drifts (5000 ppm: +-5 ms at the ends of a 2 s session): the offset alone leaves cam2's
// views at the ends outside their frames; with time_drift_ppm and time_reference_utime every frame has all
// five cameras.
TEST(TrackerTimeOffsets, DriftingCameraJoinsItsFramesWithTheMapsDrift) {
  const Rig r = MakeRig("drift");
  const sim::Session& session = r.sim.session;
  const RigConfig& rig = r.config;
  const double drift_ppm = 5000;
  ASSERT_GT(
      1e-6 * drift_ppm * static_cast<double>(session.frames().back().utime - session.frames().front().utime),
      2 * 2500.0)
      << "session too short for the drift to matter";
  RigMap offset_only = r.sim.map;
  for (MapCamera& c : offset_only.cameras)
    if (c.name == "cam2") c.time_offset_us = 15000;
  RigMap with_drift = offset_only;
  with_drift.time_reference_utime = session.frames()[session.frames().size() / 2].utime;
  for (MapCamera& c : with_drift.cameras)
    if (c.name == "cam2") c.time_drift_ppm = drift_ppm;
  auto full_frames = [](const std::vector<TrajectoryRow>& rows) {
    int n = 0;
    for (const TrajectoryRow& r : rows) n += r.cameras == 5;
    return n;
  };
  // At the 2 ms tolerance set by hand (a chosen window would take in the drifted views too).
  const std::vector<TrajectoryRow> offset_applied = Track(session, offset_only, rig, drift_ppm, true);
  const std::vector<TrajectoryRow> drift_applied = Track(session, with_drift, rig, drift_ppm, true);
  EXPECT_LT(full_frames(offset_applied), static_cast<int>(0.9 * session.views.size()));
  ASSERT_EQ(drift_applied.size(), session.views.size());
  EXPECT_EQ(full_frames(drift_applied), static_cast<int>(session.views.size()));
  for (size_t f = 0; f < drift_applied.size(); ++f)
    EXPECT_EQ(drift_applied[f].utime, r.sim.truth[f].utime) << f;
}

// Capture times of `cameras` cameras at `fps`, camera c `phase_ms[c]` after camera 0, n frames.
std::map<std::string, std::vector<int64_t>> Times(double fps, const std::vector<double>& phase_ms, int n) {
  std::map<std::string, std::vector<int64_t>> out;
  for (size_t c = 0; c < phase_ms.size(); ++c)
    for (int f = 0; f < n; ++f)
      out["cam" + std::to_string(c)].push_back(std::llround(
          1e6 * f / fps + 1e3 * phase_ms[c] + 300.0 * ((f * 7 + static_cast<int>(c) * 3) % 5 - 2) / 2.0));
  return out;
}

TEST(TrackerSyncWindow, CamerasTriggeredTogetherKeepTheTolerance) {
  const SyncWindowChoice c = ChooseSyncWindow(Times(30, {0, 0, 0, 0}, 12), 2.0);
  EXPECT_FALSE(c.widened) << c.reason;
  EXPECT_EQ(c.tolerance_ms, 2.0);
  EXPECT_LE(c.spread_ms, 1.0);
  EXPECT_NEAR(c.slowest_interval_ms, 33.3, 0.7);
  EXPECT_NE(c.reason.find("triggered together"), std::string::npos) << c.reason;
}

TEST(TrackerSyncWindow, StaggeredCamerasGetHalfTheSlowestFrameInterval) {
  // caliscope's webcams: 6 fps, cam1 45 ms after cam0, cam2 and cam3 24-27 ms before.
  const SyncWindowChoice c = ChooseSyncWindow(Times(6, {0, 45, -24, -27}, 12), 2.0);
  EXPECT_TRUE(c.widened) << c.reason;
  EXPECT_NEAR(c.spread_ms, 72.0, 1.0) << c.reason;  // cam1 against cam3
  EXPECT_NEAR(c.tolerance_ms, 0.5 * 1000.0 / 6, 0.5) << c.reason;
  EXPECT_NE(c.reason.find("cam1 and cam3"), std::string::npos) << c.reason;
  // A slow rig: capped.
  const SyncWindowChoice slow = ChooseSyncWindow(Times(2, {0, 300}, 12), 2.0);
  EXPECT_TRUE(slow.widened);
  EXPECT_EQ(slow.tolerance_ms, kMaxAutoSyncWindowMs);
  EXPECT_NE(slow.reason.find("exceeds the window"), std::string::npos) << slow.reason;
  // One camera only: nothing to measure.
  EXPECT_FALSE(ChooseSyncWindow(Times(6, {0}, 12), 2.0).widened);
}

}  // namespace
}  // namespace mcmt
