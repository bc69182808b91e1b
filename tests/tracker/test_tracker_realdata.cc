// The tracker on real footage (caliscope ChArUco session, ../shared/data/caliscope): the project's
// detector, the mapper's map, then every frame tracked by TrackerNode (log mode). With the map fixed,
// the tracker solves the bundle adjustment's per-frame sub-problem: its poses must agree with the
// mapper's refined trajectory, with sub-pixel residuals, and every frame with a mapped marker is posed.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <map>

#include "core/config.h"
#include "core/lcm_util.h"
#include "core/math.h"
#include "detector/detector.h"
#include "mapper/mapper.h"
#include "tracker/tracker.h"

namespace mcmt {
namespace {

const std::string kData = std::string(MCMT_SOURCE_DIR) + "/../shared/data/caliscope";

TEST(TrackerRealData, CharucoSessionAgreesWithTheMappersTrajectory) {
  if (!std::filesystem::exists(kData + "/charuco_calibration/cam_0.mp4"))
    GTEST_SKIP() << "real data not found at " << kData << " (the caliscope sessions of ../shared/data)";
  const RigConfig rig = LoadRigConfig(std::string(MCMT_SOURCE_DIR) + "/configs/caliscope_charuco.yaml");
  std::vector<detections_t> detections;
  for (const CameraConfig& c : rig.cameras) {
    std::vector<detections_t> d = DetectRecording(rig, c.name);
    detections.insert(detections.end(), d.begin(), d.end());
  }
  // As a log would hold them: by capture time, cameras in turn.
  std::stable_sort(detections.begin(), detections.end(),
                   [](const detections_t& a, const detections_t& b) { return a.utime < b.utime; });
  Mapper mapper(MapperOptions::FromConfig(rig));
  for (const auto& d : detections) mapper.Add(d);
  const MapResult mapped = mapper.Solve();

  lcm::LCM lcm("memq://");
  TrackerNodeOptions options;
  options.tracker = TrackerOptions::FromConfig(rig);
  options.log_mode = true;
  options.keep_trajectory = true;
  options.quiet = true;
  TrackerNode node(lcm, rig, options, mapped.map);
  std::set<int64_t> with_marker;  // frame utimes where a mapped camera saw a mapped marker
  for (const auto& d : detections) {
    const auto bytes = Encode(d);
    node.OnDetections(DetectionsChannel(d.camera), bytes.data(), bytes.size());
    if (!mapped.map.FindCamera(d.camera)) continue;
    for (const auto& m : d.markers)
      if (mapped.map.FindMarker(m.id)) with_marker.insert(d.utime);
  }
  node.Flush();

  // A pose for every frame with a mapped marker (frames are keyed by the utime that opened them; the
  // session's cameras share one time per synchronised frame).
  std::set<int64_t> posed;
  for (const auto& row : node.trajectory()) posed.insert(row.utime);
  EXPECT_EQ(posed, with_marker);

  std::map<int64_t, Rigid3> mapper_pose;
  for (const auto& row : mapped.trajectory) mapper_pose[row.utime] = row.rig_from_object;
  std::vector<double> dt, dr, rms;
  for (const auto& row : node.trajectory()) {
    rms.push_back(row.rms_px);
    auto it = mapper_pose.find(row.utime);
    if (it == mapper_pose.end()) continue;
    dt.push_back(TranslationDistance(row.rig_from_object, it->second));
    dr.push_back(RotationAngle(row.rig_from_object, it->second) * 180 / M_PI);
  }
  ASSERT_GT(dt.size(), 50u);
  std::cout << "[ tracker ] caliscope charuco: " << node.trajectory().size() << " poses, " << dt.size()
            << " compared with the mapper: median difference " << Median(dt) * 1000 << " mm, " << Median(dr)
            << " deg; median rms " << Median(rms) << " px" << std::endl;
  EXPECT_LT(Median(dt), 0.5e-3);
  EXPECT_LT(Median(dr), 0.05);
  EXPECT_LT(Median(rms), 1.0);
  RecordProperty("median_difference_to_mapper_mm", std::to_string(Median(dt) * 1000));
}

}  // namespace
}  // namespace mcmt
