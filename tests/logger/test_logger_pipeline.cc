// The logger with the other real programs: mcmt-detector processes publishing over udpm while mcmt-logger
// records (ports 7768-7769), and the export round trip through mcmt-mapper. Skipped (with a message) when
// those programs are not built in MCMT_BIN_DIR.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <thread>

#include "core/files.h"
#include "core/lcm_util.h"
#include "core/log_writer.h"
#include "test_util.h"

using namespace mcmt;
using namespace mcmt_test;

namespace {

struct Msg {
  std::string channel;
  std::vector<uint8_t> data;
};

std::vector<Msg> ReadMessages(const std::string& log) {
  std::vector<Msg> out;
  for (const LogEvent& e : ReadEventLog(log)) out.push_back({e.channel, e.data});
  return out;
}

class LoggerPipelineTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = MakeTempDir("pipe"); }
  void TearDown() override { RemoveTree(dir_); }
  bool Have(const std::string& program) { return access(Bin(program).c_str(), X_OK) == 0; }
  std::string dir_;
};

}  // namespace

// Real detectors -> mcmt-logger; lcm-logplayer -> a second mcmt-logger: byte-identical messages, in order.
TEST_F(LoggerPipelineTest, RealDetectorsRecordedThenReplayedGiveIdenticalLogs) {
  if (!Have("mcmt-sim") || !Have("mcmt-detector"))
    GTEST_SKIP() << "mcmt-sim or mcmt-detector not built in " << MCMT_BIN_DIR;
  const int kCameras = 3, kFrames = 15;
  std::string out, err;
  ASSERT_EQ(
      RunProgram({Bin("mcmt-sim"), "--out", dir_ + "/sim", "--cameras", std::to_string(kCameras), "--frames",
                  std::to_string(kFrames), "--image-size", "320x240", "--seed", "3", "--quiet"},
                 &out, &err, 120),
      0)
      << err;
  const std::string rig = dir_ + "/sim/rig.yaml";
  const std::string a = dir_ + "/a.lcmlog", b = dir_ + "/b.lcmlog";
  const int total = kCameras * kFrames;
  {
    Child logger({Bin("mcmt-logger"), "--out", a, "--config", rig, "--lcm-url", UdpmUrl(7768),
                  "--status-seconds", "0", "--max-messages", std::to_string(total), "--max-seconds", "120"},
                 dir_ + "/a.out", dir_ + "/a.err");
    ASSERT_TRUE(WaitFor(dir_ + "/a.yaml", 10)) << ReadText(dir_ + "/a.err");
    std::vector<std::unique_ptr<Child>> detectors;
    for (int c = 0; c < kCameras; ++c) {
      const std::string cam = "cam" + std::to_string(c);
      detectors.push_back(std::make_unique<Child>(
          std::vector<std::string>{Bin("mcmt-detector"), "--config", rig, "--camera", cam, "--lcm-url",
                                   UdpmUrl(7768), "--rate", "max", "--quiet"},
          dir_ + "/" + cam + ".out", dir_ + "/" + cam + ".err"));
    }
    for (int c = 0; c < kCameras; ++c)
      ASSERT_EQ(detectors[c]->Wait(120), 0) << ReadText(dir_ + "/cam" + std::to_string(c) + ".err");
    ASSERT_EQ(logger.Wait(60), 0) << ReadText(dir_ + "/a.err");
  }
  const auto recorded = ReadMessages(a);
  ASSERT_EQ(static_cast<int>(recorded.size()), total);
  YAML::Node side = YAML::LoadFile(dir_ + "/a.yaml");
  EXPECT_EQ(side["loss"]["detections_missing"].as<int>(), 0);
  for (int c = 0; c < kCameras; ++c) {
    const YAML::Node cam = side["loss"]["cameras"]["cam" + std::to_string(c)];
    EXPECT_EQ(cam["frames"].as<int>(), kFrames);
    EXPECT_EQ(cam["first_seq"].as<int>(), 0);
    EXPECT_EQ(cam["last_seq"].as<int>(), kFrames - 1);
  }
  EXPECT_EQ(side["config"]["text"].as<std::string>(), ReadText(rig));
  EXPECT_EQ(side["config"]["intrinsics"].size(), static_cast<size_t>(kCameras));
  {
    Child logger({Bin("mcmt-logger"), "--out", b, "--lcm-url", UdpmUrl(7769), "--status-seconds", "0",
                  "--max-messages", std::to_string(total), "--max-seconds", "120"},
                 dir_ + "/b.out", dir_ + "/b.err");
    ASSERT_TRUE(WaitFor(dir_ + "/b.yaml", 10)) << ReadText(dir_ + "/b.err");
    ASSERT_EQ(
        RunProgram({"/usr/bin/lcm-logplayer", "--speed=1", "--lcm-url=" + UdpmUrl(7769), a}, nullptr, &err),
        0)
        << err;
    ASSERT_EQ(logger.Wait(60), 0) << ReadText(dir_ + "/b.err");
  }
  const auto replayed = ReadMessages(b);
  ASSERT_EQ(replayed.size(), recorded.size());
  for (size_t i = 0; i < recorded.size(); ++i) {
    EXPECT_EQ(replayed[i].channel, recorded[i].channel) << i;
    EXPECT_TRUE(replayed[i].data == recorded[i].data) << i;
  }
  // The detections are real: they decode, and the summary sees every camera without gaps.
  ASSERT_EQ(RunProgram({Bin("mcmt-export"), "--summary", b}, &out, &err), 0) << err;
  EXPECT_NE(out.find("cameras: 3"), std::string::npos) << out;
  EXPECT_EQ(out.find("frames missing"), std::string::npos) << out;
}

// Log -> det.csv -> log -> det.csv is byte-identical, and mcmt-mapper maps both logs to the same map; a
// log recorded by lcm-logger itself (from an lcm-logplayer replay) maps to the same map too; mcmt-tracker
// reads all three to the same poses.
TEST_F(LoggerPipelineTest, DetectionsCsvRoundTripGivesTheSameMap) {
  if (!Have("mcmt-sim") || !Have("mcmt-mapper"))
    GTEST_SKIP() << "mcmt-sim or mcmt-mapper not built in " << MCMT_BIN_DIR;
  std::string out, err;
  ASSERT_EQ(RunProgram({Bin("mcmt-sim"), "--out", dir_ + "/sim", "--cameras", "4", "--frames", "100",
                        "--detections-only", "--seed", "5", "--quiet"},
                       &out, &err, 120),
            0)
      << err;
  const std::string rig = dir_ + "/sim/rig.yaml", log = dir_ + "/sim/detections.lcmlog";
  const std::string csv1 = dir_ + "/det1.csv", csv2 = dir_ + "/det2.csv", back = dir_ + "/back.lcmlog";
  ASSERT_EQ(RunProgram({Bin("mcmt-export"), "--log", log, "--detections", csv1}, &out, &err), 0) << err;
  ASSERT_EQ(RunProgram({Bin("mcmt-export"), "--detections-to-log", csv1, "--out", back, "--config", rig},
                       &out, &err),
            0)
      << err;
  ASSERT_EQ(RunProgram({Bin("mcmt-export"), "--log", back, "--detections", csv2}, &out, &err), 0) << err;
  const std::string text1 = ReadText(csv1);
  EXPECT_EQ(text1, ReadText(csv2));
  EXPECT_GT(std::count(text1.begin(), text1.end(), '\n'), 300);

  // lcm-logger's own recording of the same log's messages.
  const std::string theirs = dir_ + "/theirs.lcmlog";
  {
    Child lcm_logger({"/usr/bin/lcm-logger", "-q", "--lcm-url=" + UdpmUrl(7769) + "&recv_buf_size=4000000",
                      "--flush-interval=20", theirs},
                     dir_ + "/l.out", dir_ + "/l.err");
    const std::vector<LogEvent> events = ReadEventLog(log);
    ASSERT_TRUE(PublishIntoLcmLogger(7769, theirs, events))
        << CountNonProbeEvents(theirs) << " of " << events.size()
        << " messages recorded: " << ReadText(dir_ + "/l.err");
    lcm_logger.Signal(SIGINT);
    ASSERT_EQ(lcm_logger.Wait(20), 0);
  }

  auto map_of = [&](const std::string& input, const std::string& name) {
    const std::string outdir = dir_ + "/" + name;
    EXPECT_EQ(
        RunProgram({Bin("mcmt-mapper"), "--config", rig, "--log", input, "--out", outdir, "--threads", "1"},
                   &out, &err, 180),
        0)
        << err;
    return outdir;
  };
  const std::string m1 = map_of(log, "map_original"), m2 = map_of(back, "map_from_csv"),
                    m3 = map_of(theirs, "map_from_lcm_logger");
  for (const std::string& other : {m2, m3}) {
    const RigMap a = ReadMap(m1 + "/map.yaml"), b = ReadMap(other + "/map.yaml");
    ASSERT_EQ(a.cameras.size(), 4u);
    ASSERT_EQ(b.cameras.size(), a.cameras.size());
    ASSERT_EQ(b.markers.size(), a.markers.size());
    EXPECT_EQ(b.reference_camera, a.reference_camera);
    EXPECT_EQ(b.num_observations, a.num_observations);
    EXPECT_EQ(b.rms_px, a.rms_px);
    for (size_t i = 0; i < a.cameras.size(); ++i)
      EXPECT_TRUE(a.cameras[i].rig_from_cam.matrix() == b.cameras[i].rig_from_cam.matrix())
          << other << " " << i;
    for (size_t i = 0; i < a.markers.size(); ++i)
      EXPECT_TRUE(a.markers[i].object_from_marker.matrix() == b.markers[i].object_from_marker.matrix())
          << other;
    EXPECT_EQ(ReadText(m1 + "/trajectory.csv"), ReadText(other + "/trajectory.csv")) << other;
  }

  // mcmt-tracker reads the three logs to the same poses.
  if (!Have("mcmt-tracker")) {
    std::cout << "mcmt-tracker not built: tracker part skipped\n";
    return;
  }
  std::vector<std::string> poses;
  for (const std::string& input : {log, back, theirs}) {
    poses.push_back(dir_ + "/poses" + std::to_string(poses.size()) + ".csv");
    ASSERT_EQ(RunProgram({Bin("mcmt-tracker"), "--config", rig, "--map", m1 + "/map.yaml", "--log", input,
                          "--out", poses.back(), "--quiet"},
                         &out, &err, 120),
              0)
        << err;
  }
  // The poses it publishes, recorded by mcmt-logger and exported, are its own trajectory file.
  {
    const std::string tracked = dir_ + "/tracked.lcmlog";
    Child logger({Bin("mcmt-logger"), "--out", tracked, "--lcm-url", UdpmUrl(7768), "--channels", "MCMT_POSE",
                  "--status-seconds", "0"},
                 dir_ + "/t.out", dir_ + "/t.err");
    ASSERT_TRUE(WaitFor(dir_ + "/tracked.yaml", 10)) << ReadText(dir_ + "/t.err");
    const std::string direct = dir_ + "/poses_direct.csv";
    ASSERT_EQ(RunProgram({Bin("mcmt-tracker"), "--config", rig, "--map", m1 + "/map.yaml", "--log", log,
                          "--out", direct, "--lcm-url", UdpmUrl(7768), "--quiet"},
                         &out, &err, 120),
              0)
        << err;
    const size_t expected = ReadTrajectory(direct).size();
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (CountNonProbeEvents(tracked) < expected && std::chrono::steady_clock::now() < until)
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    logger.Signal(SIGINT);
    ASSERT_EQ(logger.Wait(20), 0) << ReadText(dir_ + "/t.err");
    ASSERT_EQ(RunProgram({Bin("mcmt-export"), "--log", tracked, "--poses", dir_ + "/poses_exported.csv"},
                         &out, &err),
              0)
        << err;
    EXPECT_EQ(ReadText(dir_ + "/poses_exported.csv"), ReadText(direct));
  }
  const std::vector<TrajectoryRow> rows = ReadTrajectory(poses[0]);
  EXPECT_GT(rows.size(), 90u);
  EXPECT_EQ(ReadText(poses[0]), ReadText(poses[1]));
  EXPECT_EQ(ReadText(poses[0]), ReadText(poses[2]));
}
