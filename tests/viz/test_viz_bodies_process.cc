// mcmt-viz as a process with several rigid bodies (issue 16): a version 2 map with the mapper's OUTDIR
// (trajectory_<body>.csv), and live poses on MCMT_POSE_<BODY> over udpm (ports 7950-7959 belong to these
// tests); each body's colour measured where the viewer's own projection puts its markers.
#include <gtest/gtest.h>

#include <atomic>
#include <opencv2/imgcodecs.hpp>
#include <thread>
#include <tuple>

#include "core/lcm_util.h"
#include "core/log_writer.h"
#include "core/objects.h"
#include "tests/support/udpm.h"
#include "tests/viz/viz_test_util.h"
#include "viz/scene.h"

namespace mcmt::viz {
namespace {

using testing::MakeBodiesTestRig;
using testing::Outline;
using testing::OutlineHits;
using testing::RunCommand;
using testing::TempDir;
using testing::VizBin;

// The scene the program draws, for its projection: same library, same options as the command lines below.
VizScene SceneLike(const PanelInput& in, int w, int h) {
  SceneOptions o;
  o.width = w;
  o.height = h;
  o.grid = false;
  o.legend = false;
  o.rays = false;
  VizScene scene(o);
  scene.SetPanels({in});
  return scene;
}

void ExpectEveryBodyInItsColour(const VizScene& scene, const cv::Mat& img, const RigMap& map,
                                const std::vector<std::string>& bodies) {
  for (size_t k = 0; k < map.objects.size(); ++k) {
    if (std::find(bodies.begin(), bodies.end(), map.objects[k].name) == bodies.end()) continue;
    const OutlineHits h = Outline(scene, img, map, k);
    std::printf("%-8s outline points %d: own colour %d, another body's %d\n", map.objects[k].name.c_str(),
                h.points, h.own, h.other);
    ASSERT_GT(h.points, 0) << map.objects[k].name;
    EXPECT_GE(h.own, 0.5 * h.points) << map.objects[k].name;
    EXPECT_LE(h.other, h.points / 10) << map.objects[k].name;
  }
}

TEST(VizBodiesProcess, SnapshotOfAMapperFolderDrawsEveryBody) {
  TempDir dir("bodies_snapshot");
  const auto rig = MakeBodiesTestRig(24);
  const std::string out = dir.path().string() + "/out";
  std::filesystem::create_directories(out);
  WriteMap(out + "/map.yaml", rig.map);
  WriteTrajectory(out + "/trajectory_tool.csv", rig.trajectory);
  WriteTrajectory(out + "/trajectory_patient.csv", rig.bodies.at("patient"));
  const auto r = RunCommand("env -u DISPLAY -u WAYLAND_DISPLAY " + VizBin() + " --map " + out +
                            "/map.yaml --trajectory " + out + " --snapshot " + (dir / "bodies.png") +
                            " --size 1280x720 --frame 17 --no-grid --no-legend --no-rays");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const cv::Mat img = cv::imread(dir / "bodies.png", cv::IMREAD_COLOR);
  ASSERT_EQ(img.cols, 1280);
  const RigMap map = ReadMap(out + "/map.yaml");
  VizScene scene = SceneLike(PanelInput{"map",
                                        map,
                                        ReadTrajectory(out + "/trajectory_tool.csv"),
                                        {{"patient", ReadTrajectory(out + "/trajectory_patient.csv")}}},
                             1280, 720);
  scene.SetCurrentFrame(17);
  ExpectEveryBodyInItsColour(scene, img, map, {"tool", "patient", "floor"});

  // Control: the tool's trajectory alone leaves the patient out (and the check sees it).
  const auto alone =
      RunCommand("env -u DISPLAY -u WAYLAND_DISPLAY " + VizBin() + " --map " + out +
                 "/map.yaml --trajectory " + out + "/trajectory_tool.csv --snapshot " + (dir / "tool.png") +
                 " --size 1280x720 --frame 17 --no-grid --no-legend --no-rays");
  ASSERT_EQ(alone.exit_code, 0) << alone.output;
  const cv::Mat img1 = cv::imread(dir / "tool.png", cv::IMREAD_COLOR);
  EXPECT_EQ(testing::BodyPixelsIn(img1, 0, 0, 1280, 720, 1), 0);  // no patient drawn anywhere
  // A folder that is not a mapper OUTDIR: one line naming the missing file.
  std::filesystem::remove(out + "/trajectory_patient.csv");
  const auto bad = RunCommand(VizBin() + " --map " + out + "/map.yaml --trajectory " + out + " --snapshot " +
                              (dir / "x.png"));
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.output.find(out + "/trajectory_patient.csv: no such trajectory"), std::string::npos)
      << bad.output;
}

// Live: the tracker's per-body channels, each body named by the message's object field.
TEST(VizBodiesProcess, LivePosesOnPerBodyChannelsOverUdpm) {
  TempDir dir("bodies_live");
  const std::string url = test::UdpmUrl(7950);
  const auto rig = MakeBodiesTestRig(24);
  WriteMap(dir / "map.yaml", rig.map);
  std::atomic<bool> done{false};
  testing::ProcessResult result;
  std::thread viewer([&] {
    result = RunCommand(VizBin() + " --lcm-url '" + url + "' --map " + (dir / "map.yaml") + " --snapshot " +
                            (dir / "live.png") +
                            " --max-poses 12 --timeout 30 --size 1280x720 --no-grid --no-legend --no-rays",
                        60);
    done = true;
  });
  auto lcm = OpenLcm(url);
  const int frame = 17;
  auto pose_of = [&](const std::string& object, const TrajectoryRow& row, int k) {
    object_pose_t pose{};
    pose.object = object;
    pose.utime = 1000000 + 33333 * k;
    pose.seq = k;
    pose.rig_from_object = ToPose3d(row.rig_from_object);
    pose.status = object_pose_t::STATUS_TRACKING;
    return pose;
  };
  for (int k = 0; !done && k < 1200; ++k) {  // the viewer may still be starting: the same poses again
    const object_pose_t tool = pose_of("tool", rig.trajectory[frame], k);
    const object_pose_t patient = pose_of("patient", rig.bodies.at("patient")[frame], k);
    lcm->publish("MCMT_POSE_" + ChannelSuffix("tool"), &tool);
    lcm->publish("MCMT_POSE_" + ChannelSuffix("patient"), &patient);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  viewer.join();
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const cv::Mat img = cv::imread(dir / "live.png", cv::IMREAD_COLOR);
  ASSERT_EQ(img.cols, 1280);
  // Every pose received is the same: the scene's framing is that of one row per body.
  std::vector<TrajectoryRow> tool(1, rig.trajectory[frame]), patient(1, rig.bodies.at("patient")[frame]);
  tool[0].utime = patient[0].utime = 1000000;
  VizScene scene =
      SceneLike(PanelInput{"map", ReadMap(dir / "map.yaml"), tool, {{"patient", patient}}}, 1280, 720);
  scene.SetCurrentFrame(0);
  ExpectEveryBodyInItsColour(scene, img, rig.map, {"tool", "patient", "floor"});
}

// Replay: a log of the tracker's per-body channels (and a relative stream, not drawn), frame 17 shown.
TEST(VizBodiesProcess, ALogOfPerBodyChannelsDrawsEveryBodyAtTheFrame) {
  TempDir dir("bodies_log");
  const auto rig = MakeBodiesTestRig(24);
  WriteMap(dir / "map.yaml", rig.map);
  const std::string log = (dir / "poses.lcmlog");
  {
    EventLogWriter w(log);
    for (size_t k = 0; k < rig.trajectory.size(); ++k)
      for (const auto& [channel, object, row] :
           std::vector<std::tuple<std::string, std::string, TrajectoryRow>>{
               {"MCMT_POSE_TOOL", "tool", rig.trajectory[k]},
               {"MCMT_POSE_PATIENT", "patient", rig.bodies.at("patient")[k]},
               {"MCMT_POSE_TOOL_IN_PATIENT", "tool", rig.trajectory[0]}}) {
        object_pose_t pose{};
        pose.object = object;
        pose.utime = row.utime;
        pose.seq = row.seq;
        pose.rig_from_object = ToPose3d(row.rig_from_object);
        pose.status = object_pose_t::STATUS_TRACKING;
        const std::vector<uint8_t> data = Encode(pose);
        w.Write(row.utime, channel, data.data(), data.size());
      }
    w.Close();
  }
  const auto r = RunCommand("env -u DISPLAY -u WAYLAND_DISPLAY " + VizBin() + " --map " + (dir / "map.yaml") +
                            " --log " + log + " --snapshot " + (dir / "log.png") +
                            " --size 1280x720 --frame 17 --no-grid --no-legend --no-rays");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const cv::Mat img = cv::imread(dir / "log.png", cv::IMREAD_COLOR);
  ASSERT_EQ(img.cols, 1280);
  // Poses round-trip through pose3d_t: the scene from the decoded rows.
  std::vector<TrajectoryRow> tool, patient;
  for (size_t k = 0; k < rig.trajectory.size(); ++k) {
    tool.push_back(rig.trajectory[k]);
    tool.back().rig_from_object = FromPose3d(ToPose3d(rig.trajectory[k].rig_from_object));
    patient.push_back(rig.bodies.at("patient")[k]);
    patient.back().rig_from_object = FromPose3d(ToPose3d(patient.back().rig_from_object));
  }
  VizScene scene =
      SceneLike(PanelInput{"map", ReadMap(dir / "map.yaml"), tool, {{"patient", patient}}}, 1280, 720);
  scene.SetCurrentFrame(17);
  ExpectEveryBodyInItsColour(scene, img, rig.map, {"tool", "patient", "floor"});
}

}  // namespace
}  // namespace mcmt::viz
