// The real caliscope recording (../shared/data/caliscope): four real mcmt-detector processes publish over
// udpm while mcmt-logger records; scripts/mcmt-replay plays the log into a second mcmt-logger: identical
// messages. Ports 7775-7776. Skipped when the data or the detector is absent.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "core/log_writer.h"
#include "test_util.h"

using namespace mcmt;
using namespace mcmt_test;

TEST(LoggerRealData, CaliscopeDetectorsRecordedAndReplayedIdentically) {
  const std::string data = std::string(MCMT_SOURCE_DIR) + "/../shared/data/caliscope/charuco_calibration";
  const std::string rig = std::string(MCMT_SOURCE_DIR) + "/configs/caliscope_charuco.yaml";
  if (!FileExists(data + "/cam_0.mp4") || !FileExists(rig))
    GTEST_SKIP() << "real data not found (" << data << ", " << rig << ")";
  if (access(Bin("mcmt-detector").c_str(), X_OK) != 0)
    GTEST_SKIP() << "mcmt-detector not built in " << MCMT_BIN_DIR;
  const std::string dir = MakeTempDir("real");
  const int kCameras = 4, kFrames = 30, kTotal = kCameras * kFrames;
  const std::string a = dir + "/a.lcmlog", b = dir + "/b.lcmlog";
  {
    Child logger({Bin("mcmt-logger"), "--out", a, "--config", rig, "--lcm-url", UdpmUrl(7775),
                  "--status-seconds", "0", "--max-messages", std::to_string(kTotal), "--max-seconds", "120"},
                 dir + "/a.out", dir + "/a.err");
    ASSERT_TRUE(WaitFor(dir + "/a.yaml", 10)) << ReadText(dir + "/a.err");
    std::vector<std::unique_ptr<Child>> detectors;
    for (int c = 0; c < kCameras; ++c) {
      const std::string cam = "cam" + std::to_string(c);
      detectors.push_back(std::make_unique<Child>(
          std::vector<std::string>{Bin("mcmt-detector"), "--config", rig, "--camera", cam, "--lcm-url",
                                   UdpmUrl(7775), "--rate", "max", "--max-frames", std::to_string(kFrames),
                                   "--quiet"},
          dir + "/" + cam + ".out", dir + "/" + cam + ".err"));
    }
    for (int c = 0; c < kCameras; ++c)
      ASSERT_EQ(detectors[c]->Wait(120), 0) << ReadText(dir + "/cam" + std::to_string(c) + ".err");
    ASSERT_EQ(logger.Wait(60), 0) << ReadText(dir + "/a.err");
  }
  const auto recorded = ReadEventLog(a);
  ASSERT_EQ(static_cast<int>(recorded.size()), kTotal);
  YAML::Node side = YAML::LoadFile(dir + "/a.yaml");
  EXPECT_EQ(side["loss"]["detections_missing"].as<int>(), 0);
  for (int c = 0; c < kCameras; ++c)
    EXPECT_EQ(side["loss"]["cameras"]["cam" + std::to_string(c)]["frames"].as<int>(), kFrames);
  EXPECT_EQ(side["config"]["intrinsics"].size(), static_cast<size_t>(kCameras));
  {
    Child logger({Bin("mcmt-logger"), "--out", b, "--lcm-url", UdpmUrl(7776), "--status-seconds", "0",
                  "--max-messages", std::to_string(kTotal), "--max-seconds", "120"},
                 dir + "/b.out", dir + "/b.err");
    ASSERT_TRUE(WaitFor(dir + "/b.yaml", 10)) << ReadText(dir + "/b.err");
    std::string out, err;
    ASSERT_EQ(
        RunProgram({std::string(MCMT_SOURCE_DIR) + "/scripts/mcmt-replay", a, "--lcm-url", UdpmUrl(7776)},
                   &out, &err, 120),
        0)
        << err;
    ASSERT_EQ(logger.Wait(60), 0) << ReadText(dir + "/b.err");
  }
  const auto replayed = ReadEventLog(b);
  ASSERT_EQ(replayed.size(), recorded.size());
  for (size_t i = 0; i < recorded.size(); ++i) {
    EXPECT_EQ(replayed[i].channel, recorded[i].channel) << i;
    EXPECT_TRUE(replayed[i].data == recorded[i].data) << i;
  }
  RemoveTree(dir);
}
