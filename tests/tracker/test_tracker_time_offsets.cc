// The tracker applies the map's per-camera clock offsets (map.yaml time_offset_us, issue 18): a camera
// whose clock reads 15 ms late joins the frames it was captured in.
#include <gtest/gtest.h>

#include <lcm/lcm-cpp.hpp>
#include <set>

#include "core/lcm_util.h"
#include "tests/tracker/synthetic_rig.h"
#include "tracker/tracker.h"

namespace mcmt {
namespace {

TrackerNodeOptions LogMode() {
  TrackerNodeOptions o;
  o.log_mode = true;
  o.keep_trajectory = true;
  o.quiet = true;
  return o;
}

// Poses (seq, cameras used) from feeding the session with cam2's clock 15 ms late.
std::vector<TrajectoryRow> Track(const tracker_test::SyntheticSession& session, const RigMap& map,
                                 const RigConfig& rig) {
  lcm::LCM in("memq://");
  TrackerNode node(in, rig, LogMode(), map);
  std::vector<detections_t> all;
  for (const auto& frame : session.views)
    for (detections_t d : frame) {
      if (d.camera == "cam2") d.utime += 15000;
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
  const tracker_test::SyntheticSession session = tracker_test::MakeSession(tracker_test::SyntheticOptions{});
  const RigConfig rig =
      LoadRigConfig(tracker_test::WriteRigFiles(tracker_test::MakeTempDir("offsets"), session.map));
  RigMap with_offset = session.map;
  for (MapCamera& c : with_offset.cameras)
    if (c.name == "cam2") c.time_offset_us = 15000;
  const std::vector<TrajectoryRow> ignored = Track(session, session.map, rig);
  const std::vector<TrajectoryRow> applied = Track(session, with_offset, rig);
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
    EXPECT_EQ(applied[f].utime, session.utimes[f]) << f;  // the reference clock
    EXPECT_LT(tracker_test::TranslationError(applied[f].rig_from_object, session.rig_from_object[f]), 2e-3)
        << f;
  }
}

}  // namespace
}  // namespace mcmt
