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
#include "tests/support/process.h"
#include "tests/support/tagslam.h"
#include "tests/support/temp_dir.h"

namespace mcmt {
namespace {

const std::string kData = MCMT_SOURCE_DIR "/../shared/data/tagslam_test/";
const std::string kBin = MCMT_BIN_DIR "/";

using test::ReadTagslam;
using test::TagslamResult;

// Our map with TagSLAM's camera poses and tag layout (TagSLAM's tag frame taken as mcmt's marker frame:
// its tag corners are AprilTag's (-s/2,-s/2), (s/2,-s/2), (s/2,s/2), (-s/2,s/2)), for the tracker to
// measure how well TagSLAM's calibration explains the same detections.
RigMap TagslamMap(const RigMap& ours, const TagslamResult& t) {
  RigMap map = ours;
  for (MapCamera& c : map.cameras) c.rig_from_cam = t.rig_from_cam.at(c.name);
  const Rigid3 tag_from_perch = Inverse(t.perch_from_tag.at(ours.reference_marker));
  map.markers.clear();
  for (const MapMarker& m : ours.markers) {
    if (!t.perch_from_tag.count(m.id)) continue;
    map.markers.push_back(m);
    map.markers.back().object_from_marker = tag_from_perch * t.perch_from_tag.at(m.id);
  }
  return map;
}

// Tracks the session with a map; returns the RMS over frames of the per-frame reprojection RMS and the
// number of frames with a pose.
std::pair<double, size_t> TrackedRms(const std::string& dir, const std::string& map_path,
                                     const std::string& out) {
  std::string text;
  EXPECT_EQ(test::RunProgram({kBin + "mcmt-tracker", "--config", dir + "/session/rig.yaml", "--map", map_path,
                              "--log", dir + "/session/session.lcmlog", "--out", out},
                             out + ".txt", &text),
            0)
      << text;
  double sq = 0;
  const std::vector<TrajectoryRow> rows = ReadTrajectory(out);
  for (const TrajectoryRow& r : rows) sq += r.rms_px * r.rms_px;
  return {rows.empty() ? 0.0 : std::sqrt(sq / rows.size()), rows.size()};
}

// Inlier observations (residuals.csv) whose marker shows the camera its printed face (z out of the face
// towards the camera), and those seen from behind (a mirrored corner order would make them so).
std::pair<int, int> CountFacing(const std::string& dir, const RigMap& map) {
  std::map<int64_t, Rigid3> rig_from_object;
  for (const TrajectoryRow& r : ReadTrajectory(dir + "/map/trajectory.csv"))
    rig_from_object[r.utime] = r.rig_from_object;
  std::ifstream residuals(dir + "/map/residuals.csv");
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
  return {facing, away};
}

struct Limits {
  double mm, deg, rms_px;
};

void RunSession(const std::string& name, Limits limits) {
  const std::string src = kData + name + "/";
  if (!std::filesystem::exists(src + "tag_detections.bag.bz2"))
    GTEST_SKIP() << "no " << src << " (real data absent)";
  test::TempDir dir("import_" + name);
  std::string out;
  ASSERT_EQ(test::RunProgram({kBin + "mcmt-import", "--rosbag", src + "tag_detections.bag.bz2", "--cameras",
                              src + "cameras.yaml", "--out", dir / "session"},
                             dir / "import.txt", &out),
            0)
      << out;
  ASSERT_EQ(test::RunProgram({kBin + "mcmt-mapper", "--config", dir / "session/rig.yaml", "--log",
                              dir / "session/session.lcmlog", "--out", dir / "map"},
                             dir / "mapper.txt", &out, 4 * 60),
            0)
      << out;
  std::cout << out.substr(out.rfind("mapped ")) << std::flush;
  const RigMap map = ReadMap(dir / "map/map.yaml");
  EXPECT_LT(map.rms_px, limits.rms_px) << "the corner order conversion or the intrinsics are off";
  const TagslamResult ts = ReadTagslam(src + "reference.bag.bz2");
  const std::map<std::string, Rigid3>& tagslam = ts.rig_from_cam;
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
  const auto [facing, away] = CountFacing(dir.str(), map);
  EXPECT_GT(facing, 100);
  EXPECT_EQ(away, 0) << "markers seen from behind: corner order mirrored";
  // Which calibration explains the detections better: the same tracker on the same detections, with
  // mcmt's map and with TagSLAM's cameras and tag layout.
  const auto [ours_rms, tracked] = TrackedRms(dir.str(), dir / "map/map.yaml", dir / "poses.csv");
  WriteMap(dir / "tagslam_map.yaml", TagslamMap(map, ts));
  const auto [tagslam_rms, tagslam_tracked] =
      TrackedRms(dir.str(), dir / "tagslam_map.yaml", dir / "poses_tagslam.csv");
  std::printf(
      "%s: tracked with mcmt's map: %zu frames, rms %.3f px; with TagSLAM's cameras and tags: %zu frames, "
      "rms %.3f px\n",
      name.c_str(), tracked, ours_rms, tagslam_tracked, tagslam_rms);
  EXPECT_LE(ours_rms, tagslam_rms * 1.02);
  EXPECT_GE(tracked, 0.95 * map.num_frames);
}

TEST(ImportRealData, TagslamTest2StereoAgreesWithTagslam) { RunSession("test_2", {3.0, 0.1, 1.0}); }
TEST(ImportRealData, TagslamTest8FourCamerasLowFrameRateAgreesWithTagslam) {
  RunSession("test_8", {3.0, 0.1, 1.0});
}
TEST(ImportRealData, TagslamTest6FourCamerasBoardAgreesWithTagslam) {
  RunSession("test_6", {10.0, 0.5, 1.5});
}

}  // namespace
}  // namespace mcmt
