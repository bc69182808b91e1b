// The three TagSLAM sessions (../shared/data/tagslam_test, real rigs, real AprilTag detections):
// each imports (mcmt-import), maps (mcmt-mapper) and tracks (mcmt-tracker) as separate processes; the
// camera poses agree with TagSLAM's own rig->camN estimates (reference.bag, /tf); every marker faces
// the cameras that see it (the corner order conversion, checked by geometry).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>

#include "core/files.h"
#include "core/se3.h"
#include "import/rosbag.h"
#include "tests/sim/temp_dir.h"
#include "tests/tracker/process_util.h"

namespace mcmt {
namespace {

const std::string kData = MCMT_SOURCE_DIR "/../shared/data/tagslam_test/";
const std::string kBin = MCMT_BIN_DIR "/";

// The last rig->camN transforms TagSLAM published on /tf (geometry_msgs/Transform: translation, then
// rotation as x, y, z, w), as rig_from_cam.
std::map<std::string, Rigid3> TagslamCameraPoses(const std::string& reference_bag) {
  const RosBag bag = RosBag::Open(reference_bag);
  std::map<std::string, Rigid3> poses;
  for (const BagMessage& m : bag.messages()) {
    if (bag.Connection(m.connection).topic != "/tf") continue;
    for (const RosValue& t : bag.Decode(m).At("transforms").items) {
      if (t.At("header.frame_id").text != "rig") continue;
      const RosValue& tr = t.At("transform");
      const Eigen::Vector3d p(tr.At("translation.x").AsDouble(), tr.At("translation.y").AsDouble(),
                              tr.At("translation.z").AsDouble());
      const std::array<double, 4> wxyz = {tr.At("rotation.w").AsDouble(), tr.At("rotation.x").AsDouble(),
                                          tr.At("rotation.y").AsDouble(), tr.At("rotation.z").AsDouble()};
      poses[t.At("child_frame_id").text] = RigidFromQuaternion(wxyz, p);
    }
  }
  return poses;
}

struct Limits {
  double mm, deg;
};

void RunSession(const std::string& name, Limits limits) {
  const std::string src = kData + name + "/";
  if (!std::filesystem::exists(src + "tag_detections.bag.bz2"))
    GTEST_SKIP() << "no " << src << " (real data absent)";
  sim::testing::TempDir dir("import_" + name);
  std::string out;
  ASSERT_EQ(tracker_test::RunProgram({kBin + "mcmt-import", "--rosbag", src + "tag_detections.bag.bz2",
                                      "--cameras", src + "cameras.yaml", "--out", dir / "session"},
                                     dir / "import.txt", &out),
            0)
      << out;
  ASSERT_EQ(tracker_test::RunProgram({kBin + "mcmt-mapper", "--config", dir / "session/rig.yaml", "--log",
                                      dir / "session/session.lcmlog", "--out", dir / "map"},
                                     dir / "mapper.txt", &out, std::chrono::minutes(4)),
            0)
      << out;
  std::cout << out.substr(out.rfind("mapped ")) << std::flush;
  const RigMap map = ReadMap(dir / "map/map.yaml");
  EXPECT_LT(map.rms_px, 1.0) << "the corner order conversion or the intrinsics are off";
  const std::map<std::string, Rigid3> tagslam = TagslamCameraPoses(src + "reference.bag.bz2");
  ASSERT_EQ(map.reference_camera, "cam0");
  for (const MapCamera& c : map.cameras) {
    ASSERT_TRUE(tagslam.count(c.name)) << c.name;
    const double mm = 1000 * TranslationDistance(c.rig_from_cam, tagslam.at(c.name));
    const double deg = RotationAngle(c.rig_from_cam, tagslam.at(c.name)) * 180 / M_PI;
    std::printf("%s %s: %.2f mm, %.3f deg from TagSLAM's rig->%s\n", name.c_str(), c.name.c_str(), mm, deg,
                c.name.c_str());
    EXPECT_LT(mm, limits.mm) << c.name;
    EXPECT_LT(deg, limits.deg) << c.name;
  }
  // Every inlier observation sees the printed face of its marker (z out of the face towards the camera).
  std::map<int64_t, Rigid3> rig_from_object;
  for (const TrajectoryRow& r : ReadTrajectory(dir / "map/trajectory.csv"))
    rig_from_object[r.utime] = r.rig_from_object;
  std::ifstream residuals(dir / "map/residuals.csv");
  std::string line;
  std::getline(residuals, line);
  int facing = 0, away = 0;
  while (std::getline(residuals, line)) {
    std::stringstream s(line);
    std::string utime, seq, camera, id, corner, status;
    std::getline(s, utime, ',');
    std::getline(s, seq, ',');
    std::getline(s, camera, ',');
    std::getline(s, id, ',');
    std::getline(s, corner, ',');
    if (corner != "0" || line.find(",inlier,") == std::string::npos) continue;
    const auto frame = rig_from_object.find(std::stoll(utime));
    if (frame == rig_from_object.end()) continue;
    const Rigid3 cam_from_marker = Inverse(map.FindCamera(camera)->rig_from_cam) * frame->second *
                                   map.FindMarker(std::stoi(id))->object_from_marker;
    const Eigen::Vector3d normal = cam_from_marker.linear().col(2);
    (normal.dot(cam_from_marker.translation()) < 0 ? facing : away)++;
  }
  EXPECT_GT(facing, 100);
  EXPECT_EQ(away, 0) << "markers seen from behind: corner order mirrored";
  ASSERT_EQ(tracker_test::RunProgram(
                {kBin + "mcmt-tracker", "--config", dir / "session/rig.yaml", "--map", dir / "map/map.yaml",
                 "--log", dir / "session/session.lcmlog", "--out", dir / "poses.csv"},
                dir / "tracker.txt", &out),
            0)
      << out;
  const size_t tracked = ReadTrajectory(dir / "poses.csv").size();
  std::printf("%s: tracker %zu poses, mapper %d frames\n", name.c_str(), tracked, map.num_frames);
  EXPECT_GE(tracked, 0.95 * map.num_frames);
}

TEST(ImportRealData, TagslamTest2StereoAgreesWithTagslam) { RunSession("test_2", {3.0, 0.1}); }
TEST(ImportRealData, TagslamTest8FourCamerasLowFrameRateAgreesWithTagslam) {
  RunSession("test_8", {3.0, 0.1});
}
TEST(ImportRealData, TagslamTest6FourCamerasBoardAgreesWithTagslam) { RunSession("test_6", {10.0, 0.5}); }

}  // namespace
}  // namespace mcmt
