// Process tests: the real mcmt-logger, lcm-logplayer, lcm-logger and mcmt-export over UDP multicast on
// loopback (ports 7760-7769), reading back what they wrote.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <lcm/lcm-cpp.hpp>
#include <thread>

#include "core/config.h"
#include "core/lcm_util.h"
#include "core/log_writer.h"
#include "logger/export.h"
#include "test_util.h"

using namespace mcmt;
using namespace mcmt_test;

namespace {

struct Msg {
  std::string channel;
  std::vector<uint8_t> data;
};

// 3 cameras x frames, poses, one large (image-sized, fragmented by udpm) message every 10 frames.
std::vector<Msg> MakeTraffic(int frames) {
  std::vector<Msg> out;
  for (int64_t seq = 0; seq < frames; ++seq) {
    for (int c = 0; c < 3; ++c) {
      const std::string cam = "cam" + std::to_string(c);
      out.push_back({DetectionsChannel(cam), Encode(MakeDetections(cam, seq, (seq + c) % 5))});
    }
    out.push_back({kPoseChannel, Encode(MakePose(seq, object_pose_t::STATUS_TRACKING))});
    if (seq % 10 == 0) {
      std::vector<uint8_t> image(150000);
      for (size_t i = 0; i < image.size(); ++i) image[i] = static_cast<uint8_t>((i * 31 + seq) & 0xff);
      out.push_back({ImageChannel("cam0"), image});
    }
  }
  return out;
}

void Publish(int port, const std::vector<Msg>& msgs, int pause_every = 4) {
  lcm::LCM lcm(UdpmUrl(port));
  ASSERT_TRUE(lcm.good());
  for (size_t i = 0; i < msgs.size(); ++i) {
    lcm.publish(msgs[i].channel, msgs[i].data.data(), static_cast<unsigned>(msgs[i].data.size()));
    if (pause_every > 0 && i % pause_every == 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

std::vector<Msg> ReadMessages(const std::string& log) {
  std::vector<Msg> out;
  for (const std::string& part : LogParts(log))
    for (const LogEvent& e : ReadEventLog(part)) out.push_back({e.channel, e.data});
  return out;
}

void ExpectSameMessages(const std::vector<Msg>& a, const std::vector<Msg>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].channel, b[i].channel) << "message " << i;
    ASSERT_TRUE(a[i].data == b[i].data) << "message " << i << " on " << a[i].channel;
  }
}

std::vector<Msg> WithoutProbes(const std::vector<Msg>& msgs) {
  std::vector<Msg> out;
  for (const Msg& m : msgs)
    if (m.channel != kProbeChannel) out.push_back(m);
  return out;
}

class LoggerProcessTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = MakeTempDir("proc"); }
  void TearDown() override { RemoveTree(dir_); }
  std::vector<std::string> LoggerArgs(const std::string& out, int port) {
    return {Bin("mcmt-logger"), "--out", out, "--lcm-url", UdpmUrl(port), "--status-seconds", "0"};
  }
  std::string dir_;
};

}  // namespace

// Record live traffic, replay the log with the real lcm-logplayer into a second logger: same messages.
TEST_F(LoggerProcessTest, RecordThenReplayThroughLcmLogplayerGivesIdenticalMessages) {
  const auto traffic = MakeTraffic(60);
  const std::string a = dir_ + "/a.lcmlog", b = dir_ + "/b.lcmlog";
  {
    auto args = LoggerArgs(a, 7760);
    args.insert(args.end(), {"--max-messages", std::to_string(traffic.size()), "--max-seconds", "60"});
    Child logger(args, dir_ + "/a.out", dir_ + "/a.err");
    ASSERT_TRUE(WaitFor(dir_ + "/a.yaml", 10)) << ReadText(dir_ + "/a.err");
    Publish(7760, traffic);
    // Not recorded: another system's channel.
    lcm::LCM(UdpmUrl(7760)).publish("OTHER_SYSTEM", "x", 1);
    ASSERT_EQ(logger.Wait(60), 0) << ReadText(dir_ + "/a.err");
  }
  ExpectSameMessages(ReadMessages(a), traffic);
  {
    auto args = LoggerArgs(b, 7761);
    args.insert(args.end(), {"--max-messages", std::to_string(traffic.size()), "--max-seconds", "60"});
    Child logger(args, dir_ + "/b.out", dir_ + "/b.err");
    ASSERT_TRUE(WaitFor(dir_ + "/b.yaml", 10));
    std::string err;
    ASSERT_EQ(
        RunProgram({"/usr/bin/lcm-logplayer", "--speed=1", "--lcm-url=" + UdpmUrl(7761), a}, nullptr, &err),
        0)
        << err;
    ASSERT_EQ(logger.Wait(60), 0) << ReadText(dir_ + "/b.err");
  }
  ExpectSameMessages(ReadMessages(b), ReadMessages(a));
  // The sidecar says what happened.
  YAML::Node side = YAML::LoadFile(dir_ + "/a.yaml");
  EXPECT_EQ(side["state"].as<std::string>(), "closed");
  EXPECT_EQ(side["messages"]["written"].as<int64_t>(), static_cast<int64_t>(traffic.size()));
  EXPECT_EQ(side["channels"]["MCMT_POSE"]["messages"].as<int>(), 60);
  EXPECT_EQ(side["channels"]["MCMT_IMAGE_CAM0"]["messages"].as<int>(), 6);
  EXPECT_FALSE(side["channels"]["OTHER_SYSTEM"]);
  EXPECT_EQ(side["loss"]["detections_missing"].as<int>(), 0);
  EXPECT_EQ(side["loss"]["cameras"]["cam1"]["frames"].as<int>(), 60);
}

// lcm-logger's files are read by mcmt-export; lcm-logplayer plays mcmt-logger's files into LCM's log writer.
TEST_F(LoggerProcessTest, InteroperatesWithLcmLoggerBothWays) {
  const auto traffic = MakeTraffic(30);
  // lcm-logger records; mcmt-export reads.
  const std::string theirs = dir_ + "/theirs.lcmlog";
  {
    Child lcm_logger({"/usr/bin/lcm-logger", "-q", "--channel=MCMT_.*",
                      "--lcm-url=" + UdpmUrl(7765) + "&recv_buf_size=4000000", "--flush-interval=20", theirs},
                     dir_ + "/l.out", dir_ + "/l.err");
    ASSERT_TRUE(PublishIntoLcmLogger(7765, theirs, traffic))
        << CountNonProbeEvents(theirs) << " of " << traffic.size()
        << " messages recorded: " << ReadText(dir_ + "/l.err");
    lcm_logger.Signal(SIGINT);
    ASSERT_EQ(lcm_logger.Wait(20), 0) << ReadText(dir_ + "/l.err");
  }
  ExpectSameMessages(WithoutProbes(ReadMessages(theirs)), traffic);
  std::string out, err;
  ASSERT_EQ(RunProgram({Bin("mcmt-export"), "--summary", theirs}, &out, &err), 0) << err;
  EXPECT_NE(out.find("cameras: 3"), std::string::npos) << out;
  EXPECT_NE(out.find("cam2: 30 frames, seq 0..29"), std::string::npos) << out;
  EXPECT_NE(out.find("seq gaps: none"), std::string::npos) << out;
  EXPECT_NE(out.find("poses: 30 (tracking 30"), std::string::npos) << out;
  ASSERT_EQ(
      RunProgram({Bin("mcmt-export"), "--log", theirs, "--detections", dir_ + "/theirs.csv"}, &out, &err), 0)
      << err;

  // mcmt-logger's file (the same traffic via mcmt-logger) played by lcm-logplayer into lcm-logger.
  const std::string ours = dir_ + "/ours.lcmlog";
  {
    auto args = LoggerArgs(ours, 7766);
    args.insert(args.end(), {"--max-messages", std::to_string(traffic.size()), "--max-seconds", "60"});
    Child logger(args, dir_ + "/o.out", dir_ + "/o.err");
    ASSERT_TRUE(WaitFor(dir_ + "/ours.yaml", 10));
    Publish(7766, traffic);
    ASSERT_EQ(logger.Wait(60), 0) << ReadText(dir_ + "/o.err");
  }
  ASSERT_EQ(RunProgram({Bin("mcmt-export"), "--log", ours, "--detections", dir_ + "/ours.csv"}, &out, &err),
            0)
      << err;
  EXPECT_EQ(ReadText(dir_ + "/ours.csv"), ReadText(dir_ + "/theirs.csv"));
  // Into LCM's own log writer (lcm-logger's, here without UDP: lcm-logger itself cannot be fed by
  // lcm-logplayer without loss on a loaded machine, see PublishIntoLcmLogger).
  const std::string again = dir_ + "/again.lcmlog";
  ASSERT_EQ(RunProgram({"/usr/bin/lcm-logplayer", "--speed=1", "--lcm-url=file://" + again + "?mode=w", ours},
                       nullptr, &err),
            0)
      << err;
  ExpectSameMessages(ReadMessages(again), traffic);
}

// kill -9 in the middle of recording: every event on disk decodes, and nothing before the last flush is lost.
TEST_F(LoggerProcessTest, KillNineLeavesADecodableLog) {
  const std::string log = dir_ + "/k.lcmlog";
  auto args = LoggerArgs(log, 7762);
  args.insert(args.end(), {"--flush-ms", "20"});
  Child logger(args, dir_ + "/k.out", dir_ + "/k.err");
  ASSERT_TRUE(WaitFor(dir_ + "/k.yaml", 10));
  lcm::LCM lcm(UdpmUrl(7762));
  std::vector<std::vector<uint8_t>> sent;
  long long first_batch_bytes = 0;
  int64_t seq = 0;
  for (; seq < 300; ++seq) {
    sent.push_back(Encode(MakeDetections("cam0", seq, 4)));
    lcm.publish(DetectionsChannel("cam0"), sent.back().data(), static_cast<unsigned>(sent.back().size()));
    first_batch_bytes +=
        static_cast<long long>(kLcmEventHeaderBytes + DetectionsChannel("cam0").size() + sent.back().size());
    if (seq % 4 == 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  // Wait until the first batch is flushed, then kill while a second batch is streaming.
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (FileSize(log) < first_batch_bytes && std::chrono::steady_clock::now() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  ASSERT_GE(FileSize(log), first_batch_bytes);
  std::thread killer([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    logger.Signal(SIGKILL);
  });
  for (; seq < 800; ++seq) {
    sent.push_back(Encode(MakeDetections("cam0", seq, 4)));
    lcm.publish(DetectionsChannel("cam0"), sent.back().data(), static_cast<unsigned>(sent.back().size()));
    if (seq % 2 == 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  killer.join();
  EXPECT_EQ(logger.Wait(10), 128 + SIGKILL);

  EventLogReader reader(log);  // strict: any damage throws
  LogEvent e;
  size_t n = 0;
  while (reader.Next(&e)) {
    ASSERT_LT(n, sent.size());
    detections_t d;
    ASSERT_TRUE(Decode(e.data.data(), e.data.size(), &d)) << "event " << n;
    EXPECT_EQ(e.data, sent[n]) << "event " << n;  // in order, no hole
    ++n;
  }
  EXPECT_GE(n, 300u);
  EXPECT_EQ(reader.truncated_tail_bytes(), 0u) << "events are written whole";
  // LCM's own reader agrees.
  lcm::LogFile f(log, "r");
  size_t m = 0;
  while (f.readNextEvent()) ++m;
  EXPECT_EQ(m, n);
  // The sidecar still describes a session (state: recording, as it was never closed).
  YAML::Node side = YAML::LoadFile(dir_ + "/k.yaml");
  EXPECT_EQ(side["state"].as<std::string>(), "recording");
}

// SIGTERM closes cleanly; the sidecar holds the config, intrinsics, counts and the frames lost.
TEST_F(LoggerProcessTest, SigtermClosesAndSidecarCountsLoss) {
  CameraModel model = CameraModel::Pinhole(640, 480, 500, 320, 240);
  WriteIntrinsicsOpenCv(dir_ + "/left.yml", model);
  WriteIntrinsicsOpenCv(dir_ + "/right.yml", model);
  const std::string rig_text =
      "markers:\n  dictionary: DICT_4X4_50\n  size: 0.05\ncameras:\n  - name: left\n    intrinsics: "
      "left.yml\n"
      "  - name: right\n    intrinsics: right.yml\nlogger:\n  flush_ms: 50\n";
  WriteText(dir_ + "/rig.yaml", rig_text);
  const std::string log = dir_ + "/s.lcmlog";
  auto args = LoggerArgs(log, 7763);
  args.insert(args.end(), {"--config", dir_ + "/rig.yaml"});
  Child logger(args, dir_ + "/s.out", dir_ + "/s.err");
  ASSERT_TRUE(WaitFor(dir_ + "/s.yaml", 10)) << ReadText(dir_ + "/s.err");
  std::vector<Msg> traffic;
  for (int64_t seq = 0; seq < 20; ++seq) {
    if (seq < 10 || seq >= 15)
      traffic.push_back({DetectionsChannel("left"), Encode(MakeDetections("left", seq, 2))});
    if (seq != 7) traffic.push_back({DetectionsChannel("right"), Encode(MakeDetections("right", seq, 1))});
  }
  Publish(7763, traffic);
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (ReadMessages(log).size() < traffic.size() && std::chrono::steady_clock::now() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  logger.Signal(SIGTERM);
  ASSERT_EQ(logger.Wait(20), 0) << ReadText(dir_ + "/s.err");
  ExpectSameMessages(ReadMessages(log), traffic);

  YAML::Node side = YAML::LoadFile(dir_ + "/s.yaml");
  EXPECT_EQ(side["state"].as<std::string>(), "closed");
  EXPECT_GE(side["end_utime"].as<int64_t>(), side["start_utime"].as<int64_t>());
  EXPECT_EQ(side["channels"]["MCMT_DETECTIONS_LEFT"]["messages"].as<int>(), 15);
  EXPECT_EQ(side["channels"]["MCMT_DETECTIONS_RIGHT"]["messages"].as<int>(), 19);
  EXPECT_EQ(side["loss"]["cameras"]["left"]["missing"].as<int>(), 5);
  EXPECT_EQ(side["loss"]["cameras"]["left"]["gaps"].as<int>(), 1);
  EXPECT_EQ(side["loss"]["cameras"]["right"]["missing"].as<int>(), 1);
  EXPECT_EQ(side["loss"]["detections_missing"].as<int>(), 6);
  EXPECT_EQ(side["parts"][0]["events"].as<int>(), static_cast<int>(traffic.size()));
  EXPECT_EQ(side["config"]["text"].as<std::string>(), rig_text);
  ASSERT_EQ(side["config"]["intrinsics"].size(), 2u);
  EXPECT_EQ(side["config"]["intrinsics"][1]["name"].as<std::string>(), "right.yml");
  EXPECT_EQ(side["config"]["intrinsics"][1]["text"].as<std::string>(), ReadText(dir_ + "/right.yml"));
  // The summary sees the same gaps.
  std::string out, err;
  ASSERT_EQ(RunProgram({Bin("mcmt-export"), "--summary", log}, &out, &err), 0) << err;
  EXPECT_NE(out.find("seq gaps: 1, 5 frames missing: 10..14"), std::string::npos) << out;
  EXPECT_NE(out.find("seq gaps: 1, 1 frames missing: 7"), std::string::npos) << out;
}

// Rotation by size: whole events in numbered parts, nothing overwritten, nothing lost.
TEST_F(LoggerProcessTest, SplitWritesNumberedPartsAndNeverOverwrites) {
  const auto traffic = MakeTraffic(40);  // ~1.1 MB with the images
  const std::string log = dir_ + "/r.lcmlog";
  auto args = LoggerArgs(log, 7764);
  args.insert(args.end(),
              {"--split-mb", "0.1", "--max-messages", std::to_string(traffic.size()), "--max-seconds", "60"});
  {
    Child logger(args, dir_ + "/r.out", dir_ + "/r.err");
    ASSERT_TRUE(WaitFor(dir_ + "/r.yaml", 10)) << ReadText(dir_ + "/r.err");
    Publish(7764, traffic);
    ASSERT_EQ(logger.Wait(60), 0) << ReadText(dir_ + "/r.err");
  }
  EXPECT_FALSE(FileExists(log));
  const auto parts = LogParts(log);
  ASSERT_GE(parts.size(), 4u);
  EXPECT_EQ(parts[0], dir_ + "/r.00.lcmlog");
  for (size_t i = 0; i + 1 < parts.size(); ++i) {
    const auto events = ReadEventLog(parts[i]);
    ASSERT_FALSE(events.empty());
    // A part is closed at the first event that takes it to the limit.
    const long long last_size = static_cast<long long>(kLcmEventHeaderBytes + events.back().channel.size() +
                                                       events.back().data.size());
    EXPECT_LT(FileSize(parts[i]) - last_size, 100000) << parts[i];
    EXPECT_GE(FileSize(parts[i]), 100000) << parts[i];
  }
  ExpectSameMessages(ReadMessages(log), traffic);
  YAML::Node side = YAML::LoadFile(dir_ + "/r.yaml");
  EXPECT_EQ(side["parts"].size(), parts.size());

  // Starting again on the same name is refused, and nothing is touched.
  const std::string before = ReadText(parts[0]);
  std::string out, err;
  auto again = LoggerArgs(log, 7764);
  again.insert(again.end(), {"--split-mb", "0.1", "--max-seconds", "1"});
  EXPECT_EQ(RunProgram(again, &out, &err), 1);
  EXPECT_NE(err.find("r.00.lcmlog: exists; refusing to overwrite"), std::string::npos) << err;
  EXPECT_EQ(ReadText(parts[0]), before);
  // Same for an unsplit log.
  WriteText(dir_ + "/plain.lcmlog", "keep me");
  EXPECT_EQ(RunProgram(LoggerArgs(dir_ + "/plain.lcmlog", 7764), &out, &err), 1);
  EXPECT_NE(err.find("plain.lcmlog: exists"), std::string::npos) << err;
  EXPECT_EQ(ReadText(dir_ + "/plain.lcmlog"), "keep me");
}

// Rotation by time: parts follow each other without loss.
TEST_F(LoggerProcessTest, SplitByMinutesRotatesOnTime) {
  const std::string log = dir_ + "/t.lcmlog";
  auto args = LoggerArgs(log, 7764);
  args.insert(args.end(), {"--split-minutes", "0.005"});  // 0.3 s
  Child logger(args, dir_ + "/t.out", dir_ + "/t.err");
  ASSERT_TRUE(WaitFor(dir_ + "/t.yaml", 10)) << ReadText(dir_ + "/t.err");
  std::vector<Msg> traffic;
  lcm::LCM lcm(UdpmUrl(7764));
  // Publish until three parts exist (time-based, so no fixed count), then a last message.
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  for (int64_t seq = 0; !FileExists(LogPartName(log, 2)) && std::chrono::steady_clock::now() < until; ++seq) {
    traffic.push_back({DetectionsChannel("cam0"), Encode(MakeDetections("cam0", seq, 1))});
    lcm.publish(traffic.back().channel, traffic.back().data.data(),
                static_cast<unsigned>(traffic.back().data.size()));
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_TRUE(FileExists(LogPartName(log, 2)));
  const auto wait_until = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (ReadMessages(log).size() < traffic.size() && std::chrono::steady_clock::now() < wait_until)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  logger.Signal(SIGINT);
  ASSERT_EQ(logger.Wait(20), 0) << ReadText(dir_ + "/t.err");
  EXPECT_GE(LogParts(log).size(), 3u);
  ExpectSameMessages(ReadMessages(log), traffic);
}

// scripts/mcmt-replay plays a split session part after part, into a live logger.
TEST_F(LoggerProcessTest, McmtReplayPlaysSplitSessions) {
  const auto traffic = MakeTraffic(20);
  const std::string session = dir_ + "/split.lcmlog";
  {
    const size_t half = traffic.size() / 2;
    for (int part = 0; part < 2; ++part) {
      EventLogWriter w(LogPartName(session, part));
      for (size_t i = part == 0 ? 0 : half; i < (part == 0 ? half : traffic.size()); ++i)
        w.Write(1700000000000000LL + static_cast<int64_t>(i) * 2000, traffic[i].channel,
                traffic[i].data.data(), traffic[i].data.size());
      w.Close();
    }
  }
  const std::string replay = std::string(MCMT_SOURCE_DIR) + "/scripts/mcmt-replay";
  const std::string out = dir_ + "/played.lcmlog";
  auto args = LoggerArgs(out, 7764);
  args.insert(args.end(), {"--max-messages", std::to_string(traffic.size()), "--max-seconds", "60"});
  Child logger(args, dir_ + "/p.out", dir_ + "/p.err");
  ASSERT_TRUE(WaitFor(dir_ + "/played.yaml", 10));
  std::string stdout_text, err;
  ASSERT_EQ(RunProgram({replay, session, "--speed", "1", "--lcm-url", UdpmUrl(7764)}, &stdout_text, &err), 0)
      << err;
  EXPECT_NE(err.find("split.00.lcmlog"), std::string::npos) << err;
  EXPECT_NE(err.find("split.01.lcmlog"), std::string::npos) << err;
  ASSERT_EQ(logger.Wait(60), 0) << ReadText(dir_ + "/p.err");
  ExpectSameMessages(ReadMessages(out), traffic);
  // Bad input: one line, exit 1.
  WriteText(dir_ + "/text.lcmlog", "not a log");
  EXPECT_EQ(RunProgram({replay, dir_ + "/text.lcmlog"}, &stdout_text, &err), 1);
  EXPECT_NE(err.find("text.lcmlog: byte 0: not an LCM event log"), std::string::npos) << err;
  EXPECT_EQ(RunProgram({replay, dir_ + "/none.lcmlog"}, &stdout_text, &err), 1);
  EXPECT_NE(err.find("none.lcmlog: no such file"), std::string::npos) << err;
}

// Bad input gives one clear line and a non-zero exit.
TEST_F(LoggerProcessTest, BadInputGivesOneClearLine) {
  std::string out, err;
  auto one_line_error = [&](const std::vector<std::string>& args, const std::string& needle) {
    EXPECT_NE(RunProgram(args, &out, &err), 0) << args[1];
    EXPECT_NE(err.find(needle), std::string::npos) << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  };
  one_line_error({Bin("mcmt-export"), "--summary", dir_ + "/missing.lcmlog"}, "missing.lcmlog: cannot open");
  WriteText(dir_ + "/text.lcmlog", "hello, I am not a log\n");
  one_line_error({Bin("mcmt-export"), "--summary", dir_ + "/text.lcmlog"},
                 "text.lcmlog: byte 0 (event 0): not an LCM event log");
  one_line_error({Bin("mcmt-export"), "--log", dir_ + "/text.lcmlog", "--detections", dir_ + "/d.csv"},
                 "not an LCM event log");
  EXPECT_FALSE(FileExists(dir_ + "/d.csv"));
  one_line_error({Bin("mcmt-export"), "--log", dir_ + "/text.lcmlog"}, "say what to export");
  one_line_error({Bin("mcmt-export"), "--map", dir_ + "/nomap.yaml", "--ply", dir_ + "/o.ply"}, "nomap.yaml");
  one_line_error({Bin("mcmt-logger"), "--out", dir_ + "/x.lcmlog", "--flush-ms", "0"}, "--flush-ms");
  one_line_error({Bin("mcmt-logger"), "--out", dir_ + "/x.lcmlog", "--recv-buf-mb", "-1"},
                 "--recv-buf-mb: must be in [0, 1000000], got '-1'");
  one_line_error({Bin("mcmt-logger"), "--out", dir_ + "/x.lcmlog", "--config", dir_ + "/norig.yaml"},
                 "norig.yaml");
  CameraModel model = CameraModel::Pinhole(640, 480, 500, 320, 240);
  WriteIntrinsicsOpenCv(dir_ + "/c.yml", model);
  WriteText(
      dir_ + "/typo.yaml",
      "markers:\n  size: 0.05\ncameras:\n  - name: c\n    intrinsics: c.yml\nlogger:\n  flush_msx: 50\n");
  one_line_error({Bin("mcmt-logger"), "--out", dir_ + "/x.lcmlog", "--config", dir_ + "/typo.yaml"},
                 "logger.flush_msx");
  EXPECT_FALSE(FileExists(dir_ + "/x.lcmlog"));
  EXPECT_FALSE(FileExists(dir_ + "/x.yaml"));
}

// Issue 14: an invalid --channels regex (or logger.channels) segfaulted inside LCM and left an empty log
// that blocked the next start. Now: one line naming the regex, no file, and the next start records.
TEST_F(LoggerProcessTest, InvalidChannelRegexIsRefusedBeforeAnyFileExists) {
  std::string out, err;
  const std::string log = dir_ + "/regex.lcmlog";
  for (const char* regex : {"([", "MCMT_(", "*"}) {
    const int code = RunProgram(
        {Bin("mcmt-logger"), "--out", log, "--channels", regex, "--lcm-url", UdpmUrl(7777)}, &out, &err);
    EXPECT_EQ(code, 1) << regex << ": " << err;
    EXPECT_NE(err.find("invalid regex '" + std::string(regex) + "'"), std::string::npos) << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
    EXPECT_FALSE(FileExists(log)) << regex;
    EXPECT_FALSE(FileExists(dir_ + "/regex.yaml")) << regex;
  }
  EXPECT_EQ(RunProgram({Bin("mcmt-logger"), "--out", log, "--channels", "MCMT_.*", "--lcm-url", UdpmUrl(7777),
                        "--max-seconds", "0.3"},
                       &out, &err),
            0)
      << err;
  EXPECT_TRUE(FileExists(log));
}
