// Per-camera health in the tracker (issue 17, tracker/health.h): a camera bumped during tracking is marked
// suspect within 30 frames and excluded, and no published pose is more than twice the normal error off the
// truth; no false alarm with noise only (fast motion, one marker hidden). On mcmt-sim sessions (its own
// generator, in-process) tracked from the ground truth's map with TrackerNode on the log.
#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <iostream>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/lcm_util.h"
#include "core/log_reader.h"
#include "core/stop.h"
#include "mcmt/tracker_status_t.hpp"
#include "sim/eval.h"
#include "sim/sim.h"
#include "tests/support/temp_dir.h"
#include "tracker/tracker.h"

namespace mcmt {
namespace {

struct TrackedRun {
  std::vector<double> error_mm;  // per tracked frame, object origin against the truth
  std::vector<int64_t> seq;      // per tracked frame
  std::vector<int64_t> utime;    // per tracked frame
  std::vector<CameraHealth> health;
  int64_t frames = 0;
};

// Rewrites every message of the session's log with `edit`.
void EditLog(const std::string& log, const std::function<void(detections_t*)>& edit) {
  std::string bytes;
  int64_t n = 0;
  for (const LogEvent& e : ReadEventLog(log)) {
    detections_t d;
    ASSERT_TRUE(Decode(e.data.data(), e.data.size(), &d));
    edit(&d);
    const std::vector<uint8_t> data = Encode(d);
    AppendEncodedEvent(n++, e.timestamp, e.channel, data.data(), data.size(), &bytes);
  }
  WriteFileAtomic(log, bytes);
}

// Drops marker `id` from every message of the session's log.
void HideMarker(const std::string& log, int id) {
  EditLog(log, [id](detections_t* d) {
    d->markers.erase(
        std::remove_if(d->markers.begin(), d->markers.end(), [&](const marker_t& m) { return m.id == id; }),
        d->markers.end());
    d->num_markers = static_cast<int32_t>(d->markers.size());
  });
}

struct StatusSink {
  std::vector<tracker_status_t>* out;
  void On(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    tracker_status_t msg;
    if (Decode(rbuf->data, rbuf->data_size, &msg)) out->push_back(msg);
  }
};

// Tracks the session written in `dir` with the map of its ground truth (the cameras before any move);
// statuses: where the MCMT_TRACKER_STATUS messages go (nullptr: nowhere).
TrackedRun Track(const std::string& dir, const sim::GroundTruth& truth, bool camera_health = true,
                 std::vector<tracker_status_t>* statuses = nullptr) {
  std::vector<TrajectoryRow> truth_rows;
  const RigMap map = sim::MapFromGroundTruth(truth, 0, 0, &truth_rows);
  std::map<int64_t, Rigid3> truth_at;
  for (const TrajectoryRow& r : truth_rows) truth_at[r.seq] = r.rig_from_object;
  const RigConfig rig = LoadRigConfig(dir + "/rig.yaml");
  TrackerNodeOptions options;
  options.log_mode = true;
  options.keep_trajectory = true;
  options.quiet = true;
  options.tracker.camera_health = camera_health;
  lcm::LCM lcm("memq://"), output("memq://");
  StatusSink sink{statuses};
  if (statuses) output.subscribe(kTrackerStatusChannel, &StatusSink::On, &sink)->setQueueCapacity(1 << 16);
  TrackerNode node(lcm, rig, options, map, statuses ? &output : nullptr);
  node.RunLog(dir + "/detections.lcmlog", StopToken());
  while (statuses && output.handleTimeout(0) > 0) {
  }
  TrackedRun run;
  for (const TrajectoryRow& r : node.trajectory()) {
    run.utime.push_back(r.utime);
    run.seq.push_back(r.seq);
    run.error_mm.push_back(1000.0 * TranslationDistance(r.rig_from_object, truth_at.at(r.seq)));
  }
  if (node.health()) run.health = node.health()->Snapshot();
  run.frames = node.stats().frames;
  return run;
}

double MaxError(const TrackedRun& run, int64_t from_seq, int64_t to_seq) {
  double worst = 0.0;
  for (size_t i = 0; i < run.seq.size(); ++i)
    if (run.seq[i] >= from_seq && run.seq[i] < to_seq) worst = std::max(worst, run.error_mm[i]);
  return worst;
}

struct Bump {
  double rotation_deg, translation_mm;
};

class TrackerHealthBump : public ::testing::TestWithParam<Bump> {};

TEST_P(TrackerHealthBump, SuspectWithin30FramesExcludedAndNoPoseCorrupted) {
  const Bump bump = GetParam();
  test::TempDir dir("health_bump");
  sim::DatasetOptions o = sim::DetectionsOnlySession(dir.str(), 900, 5);
  o.moves = {{"cam2", 450, bump.rotation_deg, bump.translation_mm}};
  const sim::GroundTruth truth = sim::GenerateDataset(o).truth;
  const TrackedRun run = Track(dir.str(), truth);
  ASSERT_EQ(run.health.size(), 5u);
  const double normal = MaxError(run, 0, 450);
  const double after = MaxError(run, 450, 900);
  EXPECT_LE(after, 2.0 * normal) << "normal " << normal << " mm";
  const int64_t bump_utime = sim::FrameUtime(450, 30.0);
  for (const CameraHealth& h : run.health) {
    if (h.camera != "cam2") {
      EXPECT_EQ(h.state, CameraState::kOk) << h.camera;
      EXPECT_EQ(h.first_suspect_utime, -1) << h.camera;
      continue;
    }
    EXPECT_EQ(h.state, CameraState::kExcluded);
    EXPECT_GE(h.first_suspect_utime, bump_utime);
    EXPECT_LE(h.first_suspect_utime, sim::FrameUtime(480, 30.0));
    std::cout << "cam2 (" << bump.rotation_deg << " deg, " << bump.translation_mm
              << " mm at frame 450) suspect at frame "
              << (h.first_suspect_utime - sim::FrameUtime(0, 30.0)) / 33333 << "\n";
  }
  EXPECT_GE(static_cast<double>(run.seq.size()), 0.95 * 900);

  // Without the health checks the bumped camera pulls the poses off (what the exclusion prevents).
  const TrackedRun unguarded = Track(dir.str(), truth, false);
  EXPECT_GT(MaxError(unguarded, 450, 900), 2.0 * normal);
}

INSTANTIATE_TEST_SUITE_P(Bumps, TrackerHealthBump, ::testing::Values(Bump{0.3, 0.0}, Bump{0.0, 3.0}));

// A camera that did not move but saw something misleading for 2 s (a reflection, a shaking tripod: its
// corners 3 px off from frame 450 to 509) is excluded, then comes back under the same map once its
// residuals are good again (hysteresis: health_recover_frames), and no pose is corrupted meanwhile.
TEST(TrackerHealth, ATransientExcludesACameraThatThenComesBackUnderTheSameMap) {
  test::TempDir dir("health_transient");
  sim::DatasetOptions o = sim::DetectionsOnlySession(dir.str(), 900, 5);
  const sim::GroundTruth truth = sim::GenerateDataset(o).truth;
  const int64_t from = sim::FrameUtime(450, 30.0), to = sim::FrameUtime(510, 30.0);
  EditLog(dir / "detections.lcmlog", [&](detections_t* d) {
    if (d->camera != "cam2" || d->utime < from || d->utime >= to) return;
    for (marker_t& m : d->markers)
      for (auto& corner : m.corners) corner[0] += 3.0;
  });
  const TrackedRun run = Track(dir.str(), truth);
  ASSERT_EQ(run.health.size(), 5u);
  const double normal = MaxError(run, 0, 450);
  EXPECT_LE(MaxError(run, 450, 900), 2.0 * normal) << "normal " << normal << " mm";
  EXPECT_GE(static_cast<double>(run.seq.size()), 0.95 * 900);
  for (const CameraHealth& h : run.health) {
    EXPECT_EQ(h.state, CameraState::kOk) << h.camera << " rms " << h.rms_px;
    if (h.camera != "cam2") {
      EXPECT_EQ(h.first_suspect_utime, -1) << h.camera;
      continue;
    }
    EXPECT_GE(h.first_suspect_utime, from);
    EXPECT_LE(h.first_suspect_utime, sim::FrameUtime(480, 30.0));
    // Back within the window and health_recover_frames (9 + 30 judged frames) after the transient.
    EXPECT_GT(h.since_utime, to);
    EXPECT_LE(h.since_utime, sim::FrameUtime(510 + 60, 30.0));
    std::cout << "cam2 suspect at frame " << (h.first_suspect_utime - sim::FrameUtime(0, 30.0)) / 33333
              << ", ok again at frame " << (h.since_utime - sim::FrameUtime(0, 30.0)) / 33333
              << " (transient frames 450-509)\n";
  }
  // A camera that moved stays excluded: the bump tests above (its residuals stay far above the threshold).
}

TEST(TrackerHealth, NoFalseAlarmWithNoiseOnlyFastMotionAndAHiddenMarker) {
  test::TempDir dir("health_quiet");
  sim::DatasetOptions o = sim::DetectionsOnlySession(dir.str(), 30000, 6);
  o.trajectory.turns = 200.0;  // 2 turns a second about the vertical (30 000 frames, 1000 s)
  const sim::GroundTruth truth = sim::GenerateDataset(o).truth;
  HideMarker(dir / "detections.lcmlog", 1);
  const TrackedRun run = Track(dir.str(), truth);
  ASSERT_EQ(run.health.size(), 5u);
  for (const CameraHealth& h : run.health) {
    EXPECT_EQ(h.first_suspect_utime, -1) << h.camera << " rms " << h.rms_px << " baseline " << h.baseline_px;
    EXPECT_GT(h.frames, 3000) << h.camera;
  }
}

// MCMT_TRACKER_STATUS from the first tracked frame on, then at least once a second of frames. Before, the
// "a second since the last status" test subtracted the INT64_MIN that stands for "none yet" (an overflow,
// undefined behaviour: UBSan stopped the tracker there) and wrapped to a negative difference: no status
// until a camera's state first changed.
TEST(TrackerHealth, StatusIsPublishedFromTheFirstFrameOn) {
  test::TempDir dir("health_status");
  const sim::GroundTruth truth = sim::GenerateDataset(sim::DetectionsOnlySession(dir.str(), 90, 7)).truth;
  std::vector<tracker_status_t> statuses;
  const TrackedRun run = Track(dir.str(), truth, true, &statuses);
  ASSERT_FALSE(run.utime.empty());
  ASSERT_FALSE(statuses.empty());
  EXPECT_EQ(statuses.front().utime, run.utime.front());
  for (size_t i = 1; i < statuses.size(); ++i)
    EXPECT_LE(statuses[i].utime - statuses[i - 1].utime, 1000000 + 33334) << i;
  EXPECT_LE(run.utime.back() - statuses.back().utime, 1000000 + 33334);
}

TEST(TrackerHealth, StatusMessageFingerprintsArePinned) {
  // Recorded 2026-12-02 from lcmtypes/tracker_status_t.lcm and camera_health_t.lcm (issue 17).
  EXPECT_EQ(camera_health_t::getHash(), static_cast<int64_t>(0x08dba288ba9b6bf5ULL));
  EXPECT_EQ(tracker_status_t::getHash(), static_cast<int64_t>(0x34009c5f23ac51a5ULL));
}

}  // namespace
}  // namespace mcmt
