// The mapper's result on a recorded log is pinned: tests/data/mapper_pin/detections.lcmlog (made once by
// `mcmt-sim --out D --object pentagon --detections-only --cameras 5 --frames 100 --distortion radtan
// --intrinsics-spread 0.02 --corner-noise-px 0.3 --false-rate 0.3 --drop-rate 0.05 --seed 13`; its rig.yaml
// without the id whitelist and with outlier_px 0.55, so that false ids are rejected by the marker graph and
// gross residuals by the re-solves) mapped with that rig must give the maps and trajectories in
// tests/data/mapper_pin/expected/ (initial and refined) to 1e-9. A refactoring of the mapper must not move
// them; a change that means to (a better initialisation, a different stopping rule) re-records them with
// MCMT_PIN_RECORD=1 and says so in its commit.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <lcm/lcm-cpp.hpp>

#include "core/config.h"
#include "core/files.h"
#include "core/lcm_util.h"
#include "mapper/mapper.h"

namespace mcmt {
namespace {

const std::string kPin = std::string(MCMT_SOURCE_DIR) + "/tests/data/mapper_pin";
constexpr double kTolerance = 1e-9;

std::vector<detections_t> ReadDetections(const std::string& path) {
  std::vector<detections_t> out;
  lcm::LogFile log(path, "r");
  if (!log.good()) return out;
  for (const lcm::LogEvent* e = log.readNextEvent(); e; e = log.readNextEvent()) {
    if (std::string(e->channel).rfind("MCMT_DETECTIONS_", 0) != 0) continue;
    detections_t d;
    if (d.decode(e->data, 0, e->datalen) >= 0) out.push_back(d);
  }
  return out;
}

MapResult MapThePinnedLog() {
  const RigConfig rig = LoadRigConfig(kPin + "/rig.yaml");
  MapperOptions options = MapperOptions::FromConfig(rig);
  options.threads = 1;  // the same sums in the same order
  Mapper mapper(options);
  for (const detections_t& d : ReadDetections(kPin + "/detections.lcmlog")) mapper.Add(d);
  return mapper.Solve();
}

void ExpectSamePose(const Rigid3& got, const Rigid3& want, const std::string& what) {
  EXPECT_LT((got.matrix() - want.matrix()).cwiseAbs().maxCoeff(), kTolerance) << what;
}

void ExpectSameMap(const RigMap& got, const RigMap& want, const std::string& what) {
  EXPECT_EQ(got.reference_camera, want.reference_camera) << what;
  EXPECT_EQ(got.reference_marker, want.reference_marker) << what;
  EXPECT_EQ(got.num_frames, want.num_frames) << what;
  EXPECT_EQ(got.num_observations, want.num_observations) << what;
  EXPECT_NEAR(got.rms_px, want.rms_px, kTolerance) << what;
  ASSERT_EQ(got.cameras.size(), want.cameras.size()) << what;
  for (size_t i = 0; i < got.cameras.size(); ++i) {
    const std::string c = what + " camera " + want.cameras[i].name;
    EXPECT_EQ(got.cameras[i].name, want.cameras[i].name) << c;
    EXPECT_EQ(got.cameras[i].observations, want.cameras[i].observations) << c;
    EXPECT_NEAR(got.cameras[i].rms_px, want.cameras[i].rms_px, kTolerance) << c;
    ExpectSamePose(got.cameras[i].rig_from_cam, want.cameras[i].rig_from_cam, c);
  }
  ASSERT_EQ(got.markers.size(), want.markers.size()) << what;
  for (size_t i = 0; i < got.markers.size(); ++i) {
    const std::string m = what + " marker " + std::to_string(want.markers[i].id);
    EXPECT_EQ(got.markers[i].id, want.markers[i].id) << m;
    EXPECT_EQ(got.markers[i].observations, want.markers[i].observations) << m;
    ExpectSamePose(got.markers[i].object_from_marker, want.markers[i].object_from_marker, m);
  }
}

void ExpectSameTrajectory(const std::vector<TrajectoryRow>& got, const std::vector<TrajectoryRow>& want,
                          const std::string& what) {
  ASSERT_EQ(got.size(), want.size()) << what;
  for (size_t i = 0; i < got.size(); ++i) {
    const std::string f = what + " seq " + std::to_string(want[i].seq);
    EXPECT_EQ(got[i].seq, want[i].seq) << f;
    EXPECT_EQ(got[i].cameras, want[i].cameras) << f;
    EXPECT_EQ(got[i].markers, want[i].markers) << f;
    EXPECT_NEAR(got[i].rms_px, want[i].rms_px, kTolerance) << f;
    ExpectSamePose(got[i].rig_from_object, want[i].rig_from_object, f);
  }
}

TEST(MapperPinned, RecordedLogGivesThePinnedMaps) {
  ASSERT_TRUE(std::filesystem::exists(kPin + "/detections.lcmlog")) << kPin;
  const MapResult result = MapThePinnedLog();
  const std::string expected = kPin + "/expected";
  if (std::getenv("MCMT_PIN_RECORD")) {
    std::filesystem::create_directories(expected);
    WriteMap(expected + "/map.yaml", result.map);
    WriteMap(expected + "/map_initial.yaml", result.initial_map);
    WriteTrajectory(expected + "/trajectory.csv", result.trajectory);
    WriteTrajectory(expected + "/trajectory_initial.csv", result.initial_trajectory);
    GTEST_SKIP() << "recorded the pinned maps in " << expected;
  }
  // The log exercises the paths a refactoring could break: false ids, duplicates, weak frames, rejected
  // observations and re-solves.
  EXPECT_GT(result.report.rejected_markers.size(), 10u);
  EXPECT_GT(result.report.duplicates, 0);
  EXPECT_GT(result.report.weak_frames, 0);
  EXPECT_GT(result.report.rejected_observations.size(), 10u);
  EXPECT_GT(result.report.solves, 2);
  ExpectSameMap(result.initial_map, ReadMap(expected + "/map_initial.yaml"), "initial");
  ExpectSameTrajectory(result.initial_trajectory, ReadTrajectory(expected + "/trajectory_initial.csv"),
                       "initial");
  ExpectSameMap(result.map, ReadMap(expected + "/map.yaml"), "refined");
  ExpectSameTrajectory(result.trajectory, ReadTrajectory(expected + "/trajectory.csv"), "refined");
}

}  // namespace
}  // namespace mcmt
