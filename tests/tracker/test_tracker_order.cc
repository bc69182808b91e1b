// Results never depend on the order in which messages happen to arrive, nor on repeated or
// far-off-clock messages (issue 14), with the real programs on mcmt-sim recordings:
//  - a log recorded camera by camera (each detector's whole video one after the other) tracks within
//    0.05 mm of the mapper's per-frame poses, and exactly as the time-ordered log does;
//  - a log with its events shuffled gives byte-equal tracker output and mapper initialisation;
//  - every message twice: dropped and counted (report.json `duplicates`), the same outputs;
//  - one message stamped +100 s, or a camera whose clock runs 100 s ahead: rejected with a warning
//    naming the camera, every frame still tracked.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <random>

#include "core/files.h"
#include "core/lcm_util.h"
#include "core/log_reader.h"
#include "tests/support/process.h"
#include "tests/support/temp_dir.h"

namespace mcmt {
namespace {

using mcmt::test::ReadText;
using test::RunProgram;

const std::string kBin = MCMT_BIN_DIR;

bool HavePrograms() { return test::ProgramsBuilt({"mcmt-sim", "mcmt-mapper", "mcmt-tracker"}); }

void WriteEvents(const std::string& path, const std::vector<LogEvent>& events) {
  std::string bytes;
  for (size_t i = 0; i < events.size(); ++i)
    AppendEncodedEvent(static_cast<int64_t>(i), events[i].timestamp, events[i].channel, events[i].data.data(),
                       events[i].data.size(), &bytes);
  std::ofstream(path, std::ios::binary) << bytes;
}

// Rewrites the detections of a log through edit(); the events keep their order.
template <typename Edit>
std::vector<LogEvent> Edited(std::vector<LogEvent> events, Edit edit) {
  for (LogEvent& e : events) {
    detections_t d = DecodeOrThrow<detections_t>(e.data.data(), e.data.size());
    edit(&d);
    e.data = Encode(d);
  }
  return events;
}

struct Session {
  std::string dir, rig, log;
  std::vector<LogEvent> events;
};

Session Simulate(const std::string& name) {
  Session s;
  s.dir = test::MakeTempDir("tracker_order_" + name);
  std::string out;
  EXPECT_EQ(RunProgram({kBin + "/mcmt-sim", "--out", s.dir, "--object", "four_sided", "--radius", "1.0",
                        "--frames", "300", "--seed", "11", "--detections-only", "--quiet"},
                       s.dir + "/sim.txt", &out),
            0)
      << out;
  s.rig = s.dir + "/rig.yaml";
  s.log = s.dir + "/detections.lcmlog";
  s.events = ReadEventLog(s.log);
  return s;
}

// mcmt-mapper on `log` into dir/name; returns its exit code, *output its stderr.
int Map(const Session& s, const std::string& log, const std::string& name, std::string* output,
        bool refine = true, bool one_thread = false) {
  std::vector<std::string> argv = {kBin + "/mcmt-mapper", "--config", s.rig, "--log", log, "--out",
                                   s.dir + "/" + name};
  if (!refine) argv.push_back("--no-refine");
  if (one_thread) argv.insert(argv.end(), {"--threads", "1"});
  return RunProgram(argv, s.dir + "/" + name + ".txt", output);
}

int Track(const Session& s, const std::string& map, const std::string& log, const std::string& name,
          std::string* output) {
  return RunProgram({kBin + "/mcmt-tracker", "--config", s.rig, "--map", map, "--log", log, "--out",
                     s.dir + "/" + name + ".csv"},
                    s.dir + "/" + name + ".txt", output);
}

TEST(TrackerOrder, CameraByCameraLogTracksWithinFiveHundredthsOfAMillimetreOfTheMapper) {
  if (!HavePrograms()) GTEST_SKIP() << "mcmt-sim / mcmt-mapper / mcmt-tracker not built in " << kBin;
  const Session s = Simulate("bycam");
  std::string out;
  ASSERT_EQ(Map(s, s.log, "map", &out), 0) << out;
  // As when each camera's video is processed at --rate max one after the other.
  std::vector<LogEvent> by_camera = s.events;
  std::stable_sort(by_camera.begin(), by_camera.end(),
                   [](const LogEvent& a, const LogEvent& b) { return a.channel < b.channel; });
  WriteEvents(s.dir + "/by_camera.lcmlog", by_camera);
  ASSERT_EQ(Track(s, s.dir + "/map/map.yaml", s.dir + "/by_camera.lcmlog", "by_camera", &out), 0) << out;
  ASSERT_EQ(Track(s, s.dir + "/map/map.yaml", s.log, "ordered", &out), 0) << out;

  const std::vector<TrajectoryRow> mapper = ReadTrajectory(s.dir + "/map/trajectory.csv");
  const std::vector<TrajectoryRow> tracker = ReadTrajectory(s.dir + "/by_camera.csv");
  ASSERT_EQ(tracker.size(), mapper.size());
  double worst_mm = 0.0, worst_deg = 0.0;
  for (size_t i = 0; i < mapper.size(); ++i) {
    ASSERT_EQ(tracker[i].seq, mapper[i].seq);
    EXPECT_EQ(tracker[i].cameras, mapper[i].cameras) << "seq " << mapper[i].seq;
    const Rigid3 d = mapper[i].rig_from_object.inverse() * tracker[i].rig_from_object;
    worst_mm = std::max(
        worst_mm,
        1000.0 * (tracker[i].rig_from_object.translation() - mapper[i].rig_from_object.translation()).norm());
    worst_deg = std::max(worst_deg, Eigen::AngleAxisd(d.rotation()).angle() * 180.0 / M_PI);
  }
  std::cout << "[ order ] camera-by-camera log vs mapper: worst " << worst_mm << " mm, " << worst_deg
            << " deg over " << mapper.size() << " frames" << std::endl;
  EXPECT_LE(worst_mm, 0.05);
  EXPECT_LE(worst_deg, 0.01);
  EXPECT_EQ(ReadText(s.dir + "/by_camera.csv"), ReadText(s.dir + "/ordered.csv"));
}

TEST(TrackerOrder, ShuffledEventsGiveByteEqualOutputs) {
  if (!HavePrograms()) GTEST_SKIP() << "mcmt-sim / mcmt-mapper / mcmt-tracker not built in " << kBin;
  const Session s = Simulate("shuffled");
  std::vector<LogEvent> shuffled = s.events;
  std::shuffle(shuffled.begin(), shuffled.end(), std::mt19937(7));
  WriteEvents(s.dir + "/shuffled.lcmlog", shuffled);
  std::string out;
  ASSERT_EQ(Map(s, s.log, "map", &out), 0) << out;
  ASSERT_EQ(Map(s, s.log, "init", &out, /*refine=*/false), 0) << out;
  ASSERT_EQ(Map(s, s.dir + "/shuffled.lcmlog", "init_shuffled", &out, false), 0) << out;
  // The mapper's initialisation: byte-equal.
  for (const char* f : {"/map.yaml", "/trajectory.csv"})
    EXPECT_EQ(ReadText(s.dir + "/init" + f), ReadText(s.dir + "/init_shuffled" + f)) << f;
  // The refined map too, with one solver thread (several threads sum the Schur complement in varying
  // order): the bundle adjustment's blocks are ordered by what they are, not by their addresses.
  ASSERT_EQ(Map(s, s.log, "one", &out, true, true), 0) << out;
  ASSERT_EQ(Map(s, s.dir + "/shuffled.lcmlog", "one_shuffled", &out, true, true), 0) << out;
  for (const char* f : {"/map.yaml", "/trajectory.csv", "/residuals.csv"}) {
    EXPECT_FALSE(ReadText(s.dir + "/one" + f).empty()) << f;
    EXPECT_EQ(ReadText(s.dir + "/one" + f), ReadText(s.dir + "/one_shuffled" + f)) << f;
  }
  ASSERT_EQ(Track(s, s.dir + "/map/map.yaml", s.log, "ordered", &out), 0) << out;
  ASSERT_EQ(Track(s, s.dir + "/map/map.yaml", s.dir + "/shuffled.lcmlog", "shuffled", &out), 0) << out;
  EXPECT_EQ(ReadTrajectory(s.dir + "/ordered.csv").size(), 300u);
  EXPECT_EQ(ReadText(s.dir + "/ordered.csv"), ReadText(s.dir + "/shuffled.csv"));
}

TEST(TrackerOrder, RepeatedMessagesAreDroppedAndCounted) {
  if (!HavePrograms()) GTEST_SKIP() << "mcmt-sim / mcmt-mapper / mcmt-tracker not built in " << kBin;
  const Session s = Simulate("twice");
  std::vector<LogEvent> twice;
  for (const LogEvent& e : s.events) twice.insert(twice.end(), {e, e});
  WriteEvents(s.dir + "/twice.lcmlog", twice);
  std::string out;
  ASSERT_EQ(Map(s, s.log, "init", &out, false), 0) << out;
  ASSERT_EQ(Map(s, s.dir + "/twice.lcmlog", "init_twice", &out, false), 0) << out;
  EXPECT_NE(out.find("dropped 1500 repeated detections messages"), std::string::npos) << out;
  EXPECT_EQ(ReadText(s.dir + "/init/trajectory.csv"), ReadText(s.dir + "/init_twice/trajectory.csv"));
  EXPECT_EQ(ReadText(s.dir + "/init/map.yaml"), ReadText(s.dir + "/init_twice/map.yaml"));
  EXPECT_NE(ReadText(s.dir + "/init_twice/report.json").find("\"duplicates\": 1500,"), std::string::npos);
  EXPECT_NE(ReadText(s.dir + "/init/report.json").find("\"duplicates\": 0,"), std::string::npos);

  ASSERT_EQ(Map(s, s.log, "map", &out), 0) << out;
  ASSERT_EQ(Track(s, s.dir + "/map/map.yaml", s.log, "once", &out), 0) << out;
  ASSERT_EQ(Track(s, s.dir + "/map/map.yaml", s.dir + "/twice.lcmlog", "twice", &out), 0) << out;
  EXPECT_NE(out.find("1500 repeated messages dropped"), std::string::npos) << out;
  EXPECT_EQ(ReadText(s.dir + "/once.csv"), ReadText(s.dir + "/twice.csv"));
}

TEST(TrackerOrder, AFarOffUtimeIsRejectedNamingTheCameraAndMovesNoClock) {
  if (!HavePrograms()) GTEST_SKIP() << "mcmt-sim / mcmt-mapper / mcmt-tracker not built in " << kBin;
  const Session s = Simulate("future");
  std::string out;
  ASSERT_EQ(Map(s, s.log, "map", &out), 0) << out;
  ASSERT_EQ(Track(s, s.dir + "/map/map.yaml", s.log, "clean", &out), 0) << out;
  const std::vector<TrajectoryRow> clean = ReadTrajectory(s.dir + "/clean.csv");
  ASSERT_EQ(clean.size(), 300u);

  // One message of cam1 stamped +100 s, in the middle of the log.
  WriteEvents(s.dir + "/one.lcmlog", Edited(s.events, [](detections_t* d) {
                if (d->camera == "cam1" && d->seq == 150) d->utime += 100000000;
              }));
  ASSERT_EQ(Track(s, s.dir + "/map/map.yaml", s.dir + "/one.lcmlog", "one", &out), 0) << out;
  EXPECT_NE(out.find("camera 'cam1': utime"), std::string::npos) << out;
  const std::vector<TrajectoryRow> one = ReadTrajectory(s.dir + "/one.csv");
  ASSERT_EQ(one.size(), clean.size()) << out;
  EXPECT_EQ(one[150].cameras, clean[150].cameras - 1);  // frame 150 without cam1's view
  EXPECT_EQ(one[299].cameras, clean[299].cameras);

  // cam2's clock runs 100 s ahead of the others: its messages are rejected, the others tracked.
  WriteEvents(s.dir + "/ahead.lcmlog", Edited(s.events, [](detections_t* d) {
                if (d->camera == "cam2") d->utime += 100000000;
              }));
  ASSERT_EQ(Track(s, s.dir + "/map/map.yaml", s.dir + "/ahead.lcmlog", "ahead", &out), 0) << out;
  EXPECT_NE(out.find("camera 'cam2': utime"), std::string::npos) << out;
  EXPECT_NE(out.find("ahead of the other cameras' clocks"), std::string::npos) << out;
  const std::vector<TrajectoryRow> ahead = ReadTrajectory(s.dir + "/ahead.csv");
  ASSERT_EQ(ahead.size(), clean.size()) << out;
  for (size_t i = 0; i < ahead.size(); ++i) EXPECT_EQ(ahead[i].utime, clean[i].utime);
}

}  // namespace
}  // namespace mcmt
