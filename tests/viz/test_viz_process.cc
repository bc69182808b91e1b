// mcmt-viz as a separate process: headless snapshot of a known map, before/after, --video, a log,
// live LCM over udpm (ports 7780-7799 belong to viz), no display, and bad input.
#include <gtest/gtest.h>
#include <mrpt/opengl/CFrustum.h>
#include <mrpt/opengl/CTexturedPlane.h>

#include <atomic>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <thread>

#include "core/lcm_util.h"
#include "tests/support/udpm.h"
#include "tests/viz/viz_test_util.h"
#include "viz/scene.h"

namespace mcmt::viz {
namespace {

using mcmt::test::ReadText;
using testing::MakeTestRig;
using testing::NotBackgroundNear;
using testing::RunCommand;
using testing::TempDir;
using testing::VizBin;

// The background colour the program renders: the viewports' colour. Checked against the image's
// left edge, which the automatic view leaves empty when there is no grid.
cv::Vec3b CornerColour(const cv::Mat& img) {
  const cv::Vec3b bg = BackgroundBgr();
  EXPECT_FALSE(NotBackgroundNear(img, Eigen::Vector2d(1.5, img.rows / 2.0), bg, 1, 8)) << "background moved";
  return bg;
}

// The viewer's own projection for the map the program read: same library, same options.
VizScene SceneLike(const RigMap& map, const std::vector<TrajectoryRow>& rows, int w, int h,
                   const RigMap* initial = nullptr,
                   const std::vector<TrajectoryRow>* initial_rows = nullptr) {
  SceneOptions o;
  o.width = w;
  o.height = h;
  VizScene scene(o);
  std::vector<PanelInput> panels;
  if (initial) panels.push_back(PanelInput{"initial", *initial, *initial_rows});
  panels.push_back(PanelInput{"refined", map, rows});
  scene.SetPanels(panels);
  return scene;
}

TEST(VizProcess, SnapshotOfAKnownMapShowsCamerasAndObject) {
  TempDir dir("snapshot");
  const auto rig = MakeTestRig(4, 10);
  WriteMap(dir / "map.yaml", rig.map);
  WriteTrajectory(dir / "trajectory.csv", rig.trajectory);
  const auto r = RunCommand("env -u DISPLAY -u WAYLAND_DISPLAY " + VizBin() + " --map " + (dir / "map.yaml") +
                            " --trajectory " + (dir / "trajectory.csv") + " --snapshot " + (dir / "out.png") +
                            " --size 720x400 --frame 4 --no-grid");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  cv::Mat img = cv::imread(dir / "out.png", cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty());
  EXPECT_EQ(img.cols, 720);
  EXPECT_EQ(img.rows, 400);
  // Projection from the viewer camera, for the map as the program read it back.
  const RigMap map = ReadMap(dir / "map.yaml");
  const auto rows = ReadTrajectory(dir / "trajectory.csv");
  VizScene scene = SceneLike(map, rows, 720, 400);
  scene.SetCurrentFrame(4);
  const cv::Vec3b bg = CornerColour(img);
  for (const auto& cam : map.cameras) {
    Eigen::Vector2d px;
    ASSERT_TRUE(scene.ProjectRigPoint(0, cam.rig_from_cam.translation(), &px));
    EXPECT_TRUE(NotBackgroundNear(img, px, bg, 1)) << cam.name << " at " << px.transpose();
  }
  Eigen::Vector2d obj;
  ASSERT_TRUE(scene.ProjectRigPoint(0, rows[4].rig_from_object.translation(), &obj));
  EXPECT_TRUE(NotBackgroundNear(img, obj, bg, 1)) << "object at " << obj.transpose();
  EXPECT_FALSE(std::filesystem::exists(dir / "out.png.tmp"));
}

TEST(VizProcess, BeforeAfterAndSaveScene) {
  TempDir dir("before_after");
  const auto rig = MakeTestRig(3, 6);
  RigMap initial = rig.map;
  for (auto& c : initial.cameras) c.rig_from_cam.translation() += Eigen::Vector3d(0.08, 0.0, -0.05);
  std::vector<TrajectoryRow> initial_rows = rig.trajectory;
  for (auto& row : initial_rows) row.rig_from_object.translation() += Eigen::Vector3d(0.02, 0.02, 0);
  WriteMap(dir / "map.yaml", rig.map);
  WriteMap(dir / "map_initial.yaml", initial);
  WriteTrajectory(dir / "trajectory.csv", rig.trajectory);
  WriteTrajectory(dir / "trajectory_initial.csv", initial_rows);
  const auto r =
      RunCommand(VizBin() + " --map " + (dir / "map.yaml") + " --initial-map " + (dir / "map_initial.yaml") +
                 " --trajectory " + (dir / "trajectory.csv") + " --snapshot " + (dir / "ba.png") +
                 " --save-scene " + (dir / "scene.3Dscene") + " --size 900x360 --no-grid");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  cv::Mat img = cv::imread(dir / "ba.png", cv::IMREAD_COLOR);
  ASSERT_EQ(img.cols, 900);
  ASSERT_EQ(img.rows, 360);
  EXPECT_GT(std::filesystem::file_size(dir / "scene.3Dscene"), 1000u);
  {  // The saved scene loads back (as SceneViewer3D would) with both panels.
    mrpt::opengl::COpenGLScene loaded;
    ASSERT_TRUE(loaded.loadFromFile(dir / "scene.3Dscene"));
    ASSERT_TRUE(loaded.getViewport("main"));
    ASSERT_TRUE(loaded.getViewport("left"));
    for (const char* name : {"main", "left"}) {
      EXPECT_GE(loaded.getViewport(name)->size(), 2u) << name;  // the rig and the object
      EXPECT_TRUE(loaded.getViewport(name)->getByClass<mrpt::opengl::CFrustum>()) << name;
      EXPECT_TRUE(loaded.getViewport(name)->getByClass<mrpt::opengl::CTexturedPlane>()) << name;
    }
  }
  const RigMap map = ReadMap(dir / "map.yaml"), init = ReadMap(dir / "map_initial.yaml");
  const auto rows = ReadTrajectory(dir / "trajectory.csv");
  const auto irows = ReadTrajectory(dir / "trajectory_initial.csv");
  VizScene scene = SceneLike(map, rows, 900, 360, &init, &irows);
  const cv::Vec3b bg = CornerColour(img);
  for (int panel = 0; panel < 2; ++panel) {
    for (const auto& cam : (panel == 0 ? init : map).cameras) {
      Eigen::Vector2d px;
      ASSERT_TRUE(scene.ProjectRigPoint(panel, cam.rig_from_cam.translation(), &px));
      EXPECT_EQ(px.x() >= 450, panel == 1);
      EXPECT_TRUE(NotBackgroundNear(img, px, bg, 1)) << "panel " << panel << " " << cam.name;
    }
    Eigen::Vector2d obj;
    ASSERT_TRUE(
        scene.ProjectRigPoint(panel, (panel == 0 ? irows : rows).back().rig_from_object.translation(), &obj));
    EXPECT_TRUE(NotBackgroundNear(img, obj, bg, 1)) << "object in panel " << panel;
  }
}

TEST(VizProcess, VideoWritesOneImagePerFrame) {
  TempDir dir("video");
  const auto rig = MakeTestRig(3, 5);
  WriteMap(dir / "map.yaml", rig.map);
  WriteTrajectory(dir / "trajectory.csv", rig.trajectory);
  const auto r = RunCommand(VizBin() + " --map " + (dir / "map.yaml") + " --trajectory " +
                            (dir / "trajectory.csv") + " --video " + (dir / "frames") + " --size 320x240");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::vector<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(dir.path() / "frames"))
    names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  ASSERT_EQ(names.size(), 5u);
  cv::Mat previous;
  for (int i = 0; i < 5; ++i) {
    char expected[32];
    std::snprintf(expected, sizeof(expected), "frame_%06d.png", i);
    EXPECT_EQ(names[i], expected);
    cv::Mat img = cv::imread((dir.path() / "frames" / expected).string(), cv::IMREAD_COLOR);
    ASSERT_EQ(img.cols, 320);
    ASSERT_EQ(img.rows, 240);
    if (!previous.empty()) {
      EXPECT_GT(cv::norm(img, previous, cv::NORM_L1), 0.0) << "frame " << i << " unchanged";
    }
    previous = img;
  }
}

// Writes a log with LCM's own file provider: the map, poses and detections.
// A log of the rig: its map, detections and (with_poses) the object's poses.
void WriteLog(const std::string& path, const testing::TestRig& rig, bool with_poses = true) {
  lcm::LCM log("file://" + path + "?mode=w");
  ASSERT_TRUE(log.good());
  rig_map_t map = ToRigMapMsg(rig.map, 1);
  log.publish(kMapChannel, &map);
  for (const auto& row : rig.trajectory) {
    for (const auto& cam : rig.map.cameras) {
      detections_t d;
      d.utime = row.utime;
      d.seq = row.seq;
      d.camera = cam.name;
      d.dictionary = rig.map.dictionary;
      d.camera_model = ToCameraModelMsg(cam.model);
      for (int id : {0, 1}) {
        marker_t m{};
        m.id = id;
        d.markers.push_back(m);
      }
      d.num_markers = static_cast<int32_t>(d.markers.size());
      d.detection_ms = 1;
      log.publish(DetectionsChannel(cam.name), &d);
    }
    object_pose_t p{};
    p.utime = row.utime;
    p.seq = row.seq;
    p.object = "object";
    p.rig_from_object = ToPose3d(row.rig_from_object);
    p.rms_px = row.rms_px;
    p.status = object_pose_t::STATUS_TRACKING;
    if (with_poses) log.publish(kPoseChannel, &p);
  }
}

TEST(VizProcess, ReadsALogWithRays) {
  TempDir dir("log");
  const auto rig = MakeTestRig(3, 6);
  WriteLog(dir / "session.lcmlog", rig);
  for (const std::string rays : {"", " --no-rays"}) {
    const std::string out = dir / ("log" + std::string(rays.empty() ? "_rays" : "_norays") + ".png");
    const auto r = RunCommand(VizBin() + " --log " + (dir / "session.lcmlog") + " --snapshot " + out +
                              " --size 640x360 --no-legend" + rays);
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  cv::Mat with = cv::imread(dir / "log_rays.png", cv::IMREAD_COLOR);
  cv::Mat without = cv::imread(dir / "log_norays.png", cv::IMREAD_COLOR);
  ASSERT_FALSE(with.empty());
  ASSERT_FALSE(without.empty());
  // A point half-way along the ray from camera 1 to marker 1 (in the last frame) is drawn only
  // with rays.
  const RigMap map = FromRigMapMsg(ToRigMapMsg(rig.map, 1));
  VizScene scene = SceneLike(map, rig.trajectory, 640, 360);
  const Eigen::Vector3d a = map.cameras[1].rig_from_cam.translation();
  const Eigen::Vector3d b =
      (rig.trajectory.back().rig_from_object * map.FindMarker(1)->object_from_marker).translation();
  int differ = 0;
  for (double t : {0.3, 0.45, 0.6}) {
    Eigen::Vector2d px;
    ASSERT_TRUE(scene.ProjectRigPoint(0, a + t * (b - a), &px));
    const cv::Vec3b bg = without.at<cv::Vec3b>(static_cast<int>(px.y()), static_cast<int>(px.x()));
    differ += NotBackgroundNear(with, px, bg, 1, 20);
  }
  EXPECT_GE(differ, 2);
}

// A log recorded without mcmt-tracker has no poses: the snapshot showed no object and said nothing.
TEST(VizProcess, ALogWithoutPosesSaysToAddTheTrajectory) {
  TempDir dir("noposes");
  const auto rig = MakeTestRig(3, 6);
  WriteLog(dir / "session.lcmlog", rig, false);
  const std::string hint = "session.lcmlog has no MCMT_POSE";
  auto r = RunCommand(VizBin() + " --log " + (dir / "session.lcmlog") + " --snapshot " + (dir / "a.png") +
                      " --size 320x180");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find(hint), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("add --trajectory OUTDIR/trajectory.csv"), std::string::npos) << r.output;
  r = RunCommand(VizBin() + " --log " + (dir / "session.lcmlog") + " --video " + (dir / "frames"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find(hint), std::string::npos) << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  // With the trajectory: no note.
  WriteTrajectory(dir / "trajectory.csv", rig.trajectory);
  r = RunCommand(VizBin() + " --log " + (dir / "session.lcmlog") + " --trajectory " +
                 (dir / "trajectory.csv") + " --snapshot " + (dir / "b.png") + " --size 320x180");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find(hint), std::string::npos) << r.output;
}

TEST(VizProcess, LiveLcmOverUdpmWritesASnapshotAfterNPoses) {
  TempDir dir("live");
  const std::string url = test::UdpmUrl(7781);
  const auto rig = MakeTestRig(3, 1);
  std::atomic<bool> done{false};
  testing::ProcessResult result;
  std::thread viewer([&] {
    result = RunCommand(VizBin() + " --lcm-url '" + url + "' --snapshot " + (dir / "live.png") +
                            " --max-poses 5 --timeout 30 --size 480x320 --no-grid",
                        60);
    done = true;
  });
  auto lcm = OpenLcm(url);
  const rig_map_t map = ToRigMapMsg(rig.map, 1);
  object_pose_t pose{};
  pose.object = "object";
  pose.rig_from_object = ToPose3d(rig.trajectory[0].rig_from_object);
  pose.status = object_pose_t::STATUS_TRACKING;
  pose.rms_px = 0.3;
  pose.latency_ms = 2.0;
  // The viewer may still be starting: keep publishing (same pose) until it is done.
  for (int k = 0; !done && k < 1200; ++k) {
    lcm->publish(kMapChannel, &map);
    pose.utime = 1000000 + 33333 * k;
    pose.seq = k;
    lcm->publish(kPoseChannel, &pose);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  viewer.join();
  ASSERT_EQ(result.exit_code, 0) << result.output;
  cv::Mat img = cv::imread(dir / "live.png", cv::IMREAD_COLOR);
  ASSERT_EQ(img.cols, 480);
  ASSERT_EQ(img.rows, 320);
  const RigMap got = FromRigMapMsg(map);
  std::vector<TrajectoryRow> rows(5, rig.trajectory[0]);
  for (auto& row : rows) row.rig_from_object = FromPose3d(pose.rig_from_object);
  VizScene scene = SceneLike(got, rows, 480, 320);
  const cv::Vec3b bg = CornerColour(img);
  for (const auto& cam : got.cameras) {
    Eigen::Vector2d px;
    ASSERT_TRUE(scene.ProjectRigPoint(0, cam.rig_from_cam.translation(), &px));
    EXPECT_TRUE(NotBackgroundNear(img, px, bg, 1)) << cam.name;
  }
  Eigen::Vector2d obj;
  ASSERT_TRUE(scene.ProjectRigPoint(0, rows[0].rig_from_object.translation(), &obj));
  EXPECT_TRUE(NotBackgroundNear(img, obj, bg, 1));
}

// LCM keeps 30 messages per subscription unless told otherwise and drops the rest without a word: poses
// arriving in bursts (a tracker catching up, several bodies at once) must all be counted. Bursts of 50,
// 100 ms apart, stay well under the kernel's socket buffer (the mapper's burst test says why).
TEST(VizProcess, LiveHeadlessCountsEveryPoseOfABurst) {
  TempDir dir("burst");
  const std::string url = test::UdpmUrl(7783);
  auto lcm = OpenLcm(url);
  const auto rig = MakeTestRig(3, 1);
  constexpr int kBursts = 6, kBurst = 50;
  mcmt::test::Child viewer(
      {VizBin(), "--lcm-url", url, "--snapshot", dir / "burst.png", "--max-poses",
       std::to_string(kBursts * kBurst), "--timeout", "15", "--size", "320x240", "--no-grid"},
      dir / "viz.out");
  // It says when it listens (subscribed from then on).
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (ReadText(dir / "viz.out").find("listening") == std::string::npos && viewer.Running() &&
         std::chrono::steady_clock::now() < end)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ASSERT_NE(ReadText(dir / "viz.out").find("listening"), std::string::npos) << ReadText(dir / "viz.out");
  const rig_map_t map = ToRigMapMsg(rig.map, 1);
  lcm->publish(kMapChannel, &map);
  object_pose_t pose{};
  pose.object = "object";
  pose.rig_from_object = ToPose3d(rig.trajectory[0].rig_from_object);
  pose.status = object_pose_t::STATUS_TRACKING;
  for (int k = 0; k < kBursts * kBurst; ++k) {
    pose.utime = 1000000 + 33333 * k;
    pose.seq = k;
    lcm->publish(kPoseChannel, &pose);
    if ((k + 1) % kBurst == 0) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  EXPECT_EQ(viewer.Wait(30), 0) << ReadText(dir / "viz.out");
  EXPECT_TRUE(std::filesystem::exists(dir / "burst.png"));
}

TEST(VizProcess, LiveHeadlessWithoutAMapTimesOutWithAClearMessage) {
  TempDir dir("timeout");
  const auto r = RunCommand(VizBin() + " --lcm-url '" + test::UdpmUrl(7787) + "' --snapshot " +
                                (dir / "never.png") + " --timeout 1",
                            30);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("timed out"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("no MCMT_MAP"), std::string::npos) << r.output;
  // What it waits for, then the error: one line each.
  EXPECT_EQ(r.output.find("mcmt-viz: listening for MCMT_MAP (at most 1 s)\nmcmt-viz: error: timed out"), 0u)
      << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 2) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "never.png"));
}

TEST(VizProcess, LiveWindowWithoutDisplayExitsWithAClearMessage) {
  TempDir dir("nodisplay");
  const auto rig = MakeTestRig(2, 2);
  WriteMap(dir / "map.yaml", rig.map);
  const auto r = RunCommand("env -u DISPLAY -u WAYLAND_DISPLAY " + VizBin() + " --map " + (dir / "map.yaml") +
                                " --lcm-url '" + test::UdpmUrl(7782) + "'",
                            30);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.exit_code, 124) << "timed out: " << r.output;  // coreutils timeout
  EXPECT_NE(r.output.find("no display"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--snapshot"), std::string::npos) << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
}

// The first of `tools` not on the PATH, or "" when all are there.
std::string MissingTool(std::initializer_list<const char*> tools) {
  for (const char* tool : tools)
    if (RunCommand(std::string("sh -c 'command -v ") + tool + "'", 5).exit_code != 0) return tool;
  return "";
}

// The live window's last line, "window closed after S s: N poses shown, R repaints", read from `output`.
struct WindowSummary {
  double seconds = 0;
  long long shown = 0, repaints = 0;
};
std::optional<WindowSummary> ClosedWindowSummary(const std::string& output) {
  const size_t at = output.find("window closed after");
  WindowSummary w;
  if (at == std::string::npos ||
      std::sscanf(output.c_str() + at, "window closed after %lf s: %lld poses shown, %lld repaints",
                  &w.seconds, &w.shown, &w.repaints) != 3)
    return std::nullopt;
  return w;
}

// The live window itself needs an X server: xvfb-run (scripts/setup installs it; skipped where it is
// missing). Poses arrive at ~200 Hz; repaints stay within --redraw-hz.
TEST(VizProcess, LiveWindowUnderXvfbShowsPosesWithBoundedRedraws) {
  if (const std::string tool = MissingTool({"xvfb-run"}); !tool.empty())
    GTEST_SKIP() << tool << " not installed (scripts/setup installs it)";
  TempDir dir("window");
  const auto rig = MakeTestRig(3, 1);
  WriteMap(dir / "map.yaml", rig.map);
  const std::string url = test::UdpmUrl(7788);
  std::atomic<bool> done{false};
  testing::ProcessResult result;
  std::thread viewer([&] {
    result = RunCommand("xvfb-run -a -s '-screen 0 800x600x24' " + VizBin() + " --map " + (dir / "map.yaml") +
                            " --lcm-url '" + url + "' --max-seconds 4 --redraw-hz 10 --size 640x400",
                        60);
    done = true;
  });
  auto lcm = OpenLcm(url);
  object_pose_t pose{};
  pose.object = "object";
  pose.status = object_pose_t::STATUS_TRACKING;
  for (int k = 0; !done && k < 12000; ++k) {
    Rigid3 p = rig.trajectory[0].rig_from_object;
    p.translation().x() += 1e-4 * (k % 100);
    pose.rig_from_object = ToPose3d(p);
    pose.utime = 1000000 + 5000 * k;
    pose.seq = k;
    lcm->publish(kPoseChannel, &pose);
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  viewer.join();
  if (result.output.find("cannot open the live window") != std::string::npos)
    GTEST_SKIP() << "no X server could start here: " << result.output;
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const std::optional<WindowSummary> summary = ClosedWindowSummary(result.output);
  ASSERT_TRUE(summary) << result.output;
  EXPECT_GT(summary->shown, 10) << result.output;
  EXPECT_GT(summary->repaints, 0);
  // Each loop turn waits a full 1/10 s: never more repaints than that, however fast poses come.
  EXPECT_LE(summary->repaints, static_cast<long long>(summary->seconds * 10) + 2) << result.output;
}

// The share of pixels of rows [row_begin, row_end) whose colour differs by more than `tol` in a channel.
double ShareDiffering(const cv::Mat& a, const cv::Mat& b, int row_begin, int row_end, int tol) {
  cv::Mat diff;
  cv::absdiff(a.rowRange(row_begin, row_end), b.rowRange(row_begin, row_end), diff);
  cv::Mat channels[3];
  cv::split(diff, channels);
  const cv::Mat worst = cv::max(cv::max(channels[0], channels[1]), channels[2]);
  return cv::countNonZero(worst > tol) / static_cast<double>(worst.total());
}

// The live window as a user sees it: under Xvfb, captured with ffmpeg's x11grab and driven with
// xdotool's keys (all three installed by scripts/setup; skipped where one is missing). It draws the scene
// the headless snapshot draws, ',' steps back a frame, 'q' closes it long before --max-seconds.
TEST(VizProcess, LiveWindowDrawsTheSnapshotsSceneAndAnswersKeys) {
  if (const std::string tool = MissingTool({"xvfb-run", "xdotool", "ffmpeg"}); !tool.empty())
    GTEST_SKIP() << tool << " not installed (scripts/setup installs it)";
  TempDir dir("window_keys");
  const auto rig = MakeTestRig(4, 10);
  WriteMap(dir / "map.yaml", rig.map);
  WriteTrajectory(dir / "trajectory.csv", rig.trajectory);
  const std::string files = " --map " + (dir / "map.yaml") + " --trajectory " + (dir / "trajectory.csv");
  const auto headless = RunCommand("env -u DISPLAY -u WAYLAND_DISPLAY " + VizBin() + files + " --snapshot " +
                                   (dir / "snapshot.png") + " --size 640x400");
  ASSERT_EQ(headless.exit_code, 0) << headless.output;
  // The window's canvas is the window named mcmt-viz that takes the keyboard focus.
  {
    std::ofstream script(dir / "window.sh");
    script
        << "cd '" << dir.path().string() << "'\n"
        << VizBin() << files << " --size 640x400 --max-seconds 30 > viz.out 2>&1 &\n"
        << "pid=$!\n"
           "for i in $(seq 100); do xdotool search --name mcmt-viz >/dev/null 2>&1 && break; sleep 0.1; "
           "done\n"
           "sleep 2\n"
           "win=''\n"
           "for w in $(xdotool search --name mcmt-viz); do xdotool windowfocus --sync $w 2>/dev/null && "
           "win=$w; done\n"
           "grab() { ffmpeg -loglevel error -y -f x11grab -draw_mouse 0 -window_id \"$win\" -i \"$DISPLAY\" "
           "-frames:v 1 \"$1\"; }\n"
           "grab last_frame.png\n"
           "xdotool key comma\n"
           "sleep 1\n"
           "grab frame_before.png\n"
           "xdotool key q\n"
           "wait $pid\n"
           "echo \"viz exit $?\"\n";
  }
  const auto r = RunCommand("xvfb-run -a -s '-screen 0 800x600x24' sh " + (dir / "window.sh") + " 2>&1", 60);
  const std::string viz_output = ReadText(dir / "viz.out");
  if (viz_output.find("cannot open the live window") != std::string::npos)
    GTEST_SKIP() << "no X server could start here: " << viz_output;
  ASSERT_NE(r.output.find("viz exit 0"), std::string::npos) << r.output << viz_output;
  const std::optional<WindowSummary> summary = ClosedWindowSummary(viz_output);
  ASSERT_TRUE(summary) << viz_output;
  EXPECT_LT(summary->seconds, 15) << "'q' did not close the window: " << viz_output;
  EXPECT_EQ(summary->shown, 10);

  const cv::Mat snapshot = cv::imread(dir / "snapshot.png", cv::IMREAD_COLOR);
  const cv::Mat last = cv::imread(dir / "last_frame.png", cv::IMREAD_COLOR);
  const cv::Mat before = cv::imread(dir / "frame_before.png", cv::IMREAD_COLOR);
  ASSERT_FALSE(last.empty()) << r.output;
  ASSERT_FALSE(before.empty()) << r.output;
  ASSERT_EQ(last.size(), snapshot.size()) << "the window's canvas is not --size 640x400";
  // The same scene from the same automatic view, below the overlay's lines and above the legend (placed
  // differently in the window). Measured: 0.7 % of those pixels differ (antialiasing).
  const double differing = ShareDiffering(last, snapshot, 45, 300, 30);
  EXPECT_LT(differing, 0.03);
  // ',' showed the frame before: its overlay line and the object's pose changed, nothing else.
  const double stepped = ShareDiffering(last, before, 0, last.rows, 30);
  std::printf(
      "window vs snapshot: %.2f %% of the pixels differ; after ',': %.2f %% changed; closed after %.1f s\n",
      100 * differing, 100 * stepped, summary->seconds);
  EXPECT_GT(stepped, 0.0005);
  EXPECT_LT(stepped, 0.05);
}

TEST(VizProcess, BadInputGivesOneLineErrors) {
  TempDir dir("bad");
  const auto rig = MakeTestRig(2, 3);
  WriteMap(dir / "map.yaml", rig.map);
  {
    std::ofstream f(dir / "bad.csv");
    f << kTrajectoryHeader << "\n1000,0,0.1,0.2,not_a_number,1,0,0,0,0.1,2,3\n";
  }
  struct Case {
    std::string args, expect;
    int code;
  };
  const std::vector<Case> cases = {
      {"--map " + (dir / "missing.yaml") + " --snapshot " + (dir / "a.png"), "missing.yaml", 1},
      {"--map " + (dir / "map.yaml") + " --trajectory " + (dir / "bad.csv") + " --snapshot " +
           (dir / "b.png"),
       "bad.csv", 1},
      {"--map " + (dir / "map.yaml") + " --snapshot " + (dir / "c.png") + " --size 12x", "--size", 2},
      {"--log " + (dir / "nolog.lcmlog") + " --snapshot " + (dir / "d.png"), "nolog.lcmlog", 1},
      {"--map " + (dir / "map.yaml") + " --snapshot " + (dir / "e.png") + " --frame 7", "--frame", 1},
      {"--map " + (dir / "map.yaml") + " --snapshot " + (dir / "f.png") + " --dictionary DICT_NOPE",
       "DICT_NOPE", 1},
  };
  for (const auto& c : cases) {
    const auto r = RunCommand("env -u DISPLAY " + VizBin() + " " + c.args, 30);
    SCOPED_TRACE(c.args);
    EXPECT_EQ(r.exit_code, c.code) << r.output;
    EXPECT_NE(r.output.find(c.expect), std::string::npos) << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  }
  for (const char* name : {"a.png", "b.png", "c.png", "d.png", "e.png", "f.png"})
    EXPECT_FALSE(std::filesystem::exists(dir / name)) << name;
}

TEST(VizProcess, HelpListsTheOptions) {
  const auto r = RunCommand(VizBin() + " --help", 10);
  EXPECT_EQ(r.exit_code, 0);
  for (const char* opt :
       {"--map", "--initial-map", "--trajectory", "--log", "--lcm-url", "--snapshot", "--size",
        "--save-scene", "--video", "--frame", "--dictionary", "--no-rays", "--max-poses"})
    EXPECT_NE(r.output.find(opt), std::string::npos) << opt;
}

}  // namespace
}  // namespace mcmt::viz
