// mcmt-tracker as a real process: --log mode, live over udpm on loopback (ports 7741-7747), replay by the
// real lcm-logplayer, bad command lines and inputs.
#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <thread>

#include "core/files.h"
#include "core/lcm_util.h"
#include "sim/sim.h"
#include "tests/support/process.h"
#include "tests/support/temp_dir.h"
#include "tests/support/tracker_sim.h"
#include "tests/support/udpm.h"
#include "tracker/tracker.h"

namespace mcmt {
namespace {

using namespace std::chrono_literals;
using test::ReadText;
using test::RunProgram;
using test::WaitForText;

const std::string kTracker = test::Bin("mcmt-tracker");

using test::UdpmUrl;
// This test's own LCM instances: a large receive buffer, since they see every message on the group
// (their own detections included) and a burst of small datagrams fills the default buffer quickly.
std::string TestUrl(int port) { return UdpmUrl(port) + "&recv_buf_size=4194304"; }

// One session on disk (the simulator's, tests/support/tracker_sim.h, 90 frames): rig.yaml, map.yaml (exact),
// detections.lcmlog.
struct Session {
  test::TrackerSim s;
  const std::vector<std::vector<detections_t>>& views() const { return s.session.views; }
  std::string dir, rig, map, log;
  static const Session& Get() {
    static Session* session = [] {
      auto* x = new Session;
      x->s = test::SimulateTracking(test::TrackerSession(90));
      x->dir = test::MakeTempDir("tracker_process");
      x->rig = sim::WriteSessionRig(x->dir, x->s.session);
      x->map = x->dir + "/map.yaml";
      WriteMap(x->map, x->s.map);
      x->log = x->dir + "/detections.lcmlog";
      sim::WriteMessagesLog(x->log, x->s.session.Messages());
      return x;
    }();
    return *session;
  }
};

class PoseCollector {
 public:
  explicit PoseCollector(lcm::LCM& lcm) {
    lcm.subscribe(kPoseChannel, &PoseCollector::Handle, this)->setQueueCapacity(100000);  // default: 30
  }
  std::vector<object_pose_t> poses;

 private:
  void Handle(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    poses.push_back(DecodeOrThrow<object_pose_t>(rbuf->data, rbuf->data_size));
  }
};

void Receive(lcm::LCM& lcm, const std::function<bool()>& done, std::chrono::milliseconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (!done() && std::chrono::steady_clock::now() < end) lcm.handleTimeout(20);
}

// The real tracker, live on `port`, writing --out out_csv, once it has subscribed; null (killed) when it
// never says so.
std::unique_ptr<test::Child> StartLiveTracker(const Session& x, int port, const std::string& out_csv,
                                              const std::string& err) {
  auto tracker =
      std::make_unique<test::Child>(std::vector<std::string>{kTracker, "--config", x.rig, "--map", x.map,
                                                             "--lcm-url", UdpmUrl(port), "--out", out_csv},
                                    err);
  if (WaitForText(err, "ready", 20)) return tracker;
  return nullptr;  // killed by Child's destructor
}

// --log mode's poses of the session, written to DIR/NAME.csv: the path, or "" when the tracker failed.
std::string LogModePoses(const Session& x, const std::string& name) {
  const std::string csv = x.dir + "/" + name + ".csv";
  std::string unused;
  const int code =
      RunProgram({kTracker, "--config", x.rig, "--map", x.map, "--log", x.log, "--out", csv, "--quiet"},
                 x.dir + "/" + name + ".txt", &unused);
  return code == 0 ? csv : "";
}

TEST(TrackerProcess, Help) {
  std::string out;
  EXPECT_EQ(RunProgram({kTracker, "--help"}, Session::Get().dir + "/help.txt", &out), 0);
  EXPECT_NE(out.find("--map"), std::string::npos);
  EXPECT_NE(out.find("--log"), std::string::npos);
}

TEST(TrackerProcess, LogModeIsAccurateAndDeterministic) {
  const Session& x = Session::Get();
  std::string out;
  const std::string poses1 = x.dir + "/poses_log1.csv", poses2 = x.dir + "/poses_log2.csv";
  ASSERT_EQ(RunProgram({kTracker, "--config", x.rig, "--map", x.map, "--log", x.log, "--out", poses1},
                       x.dir + "/o1.txt", &out),
            0)
      << out;
  ASSERT_EQ(
      RunProgram({kTracker, "--config", x.rig, "--map", x.map, "--log", x.log, "--out", poses2, "--quiet"},
                 x.dir + "/o2.txt", &out),
      0)
      << out;
  const auto rows = ReadTrajectory(poses1);
  ASSERT_EQ(rows.size(), x.views().size());
  double mean_t = 0, mean_r = 0;
  for (size_t f = 0; f < rows.size(); ++f) {
    EXPECT_EQ(rows[f].seq, static_cast<int64_t>(f));
    EXPECT_EQ(rows[f].utime, x.s.truth[f].utime);
    mean_t += TranslationDistance(rows[f].rig_from_object, x.s.truth[f].rig_from_object);
    mean_r += RotationAngle(rows[f].rig_from_object, x.s.truth[f].rig_from_object);
  }
  EXPECT_LT(mean_t / rows.size(), 0.5e-3);
  EXPECT_LT(mean_r / rows.size(), 0.3 * M_PI / 180);
  EXPECT_EQ(ReadText(poses1), ReadText(poses2));  // byte-equal
}

// Live: the real tracker over udpm, fed by a publisher (with garbage and a stranger camera mixed in); a
// subscriber receives one object_pose_t per frame, in order, equal to --log mode's poses.
TEST(TrackerProcess, LiveOverUdpmOnePosePerFrameInOrder) {
  const Session& x = Session::Get();
  const int port = 7741;
  const std::string err = x.dir + "/live.txt", out_csv = x.dir + "/poses_live.csv";
  const auto tracker = StartLiveTracker(x, port, out_csv, err);
  ASSERT_TRUE(tracker) << ReadText(err);
  lcm::LCM lcm(TestUrl(port));
  ASSERT_TRUE(lcm.good());
  PoseCollector collector(lcm);
  const std::vector<uint8_t> garbage(33, 0x5a);
  lcm.publish("MCMT_DETECTIONS_CAM0", garbage.data(), garbage.size());
  for (size_t f = 0; f < x.views().size(); ++f) {
    for (const auto& d : x.views()[f]) lcm.publish(DetectionsChannel(d.camera), &d);
    detections_t stranger = x.views()[f][0];
    stranger.camera = "stranger";
    lcm.publish(DetectionsChannel(stranger.camera), &stranger);
    lcm.handleTimeout(3);  // ~300 frames/s, and take the poses in
  }
  Receive(
      lcm, [&] { return collector.poses.size() >= x.views().size(); }, 10s);
  tracker->Signal(SIGINT);
  EXPECT_EQ(tracker->Wait(20), 0) << ReadText(err);
  ASSERT_EQ(collector.poses.size(), x.views().size()) << ReadText(err);
  for (size_t f = 0; f < collector.poses.size(); ++f) {
    EXPECT_EQ(collector.poses[f].seq, static_cast<int64_t>(f));
    EXPECT_EQ(collector.poses[f].status, object_pose_t::STATUS_TRACKING);
    EXPECT_LT(
        TranslationDistance(FromPose3d(collector.poses[f].rig_from_object), x.s.truth[f].rig_from_object),
        2e-3);
  }
  const std::string log = ReadText(err);
  auto count = [&](const std::string& needle) {
    size_t n = 0;
    for (size_t p = log.find(needle); p != std::string::npos; p = log.find(needle, p + 1)) ++n;
    return n;
  };
  EXPECT_EQ(count("undecodable message on MCMT_DETECTIONS_CAM0"), 1u) << log;
  EXPECT_EQ(count("camera 'stranger'"), 1u) << log;
  // SIGINT wrote the trajectory, the same as --log mode's.
  const auto live = ReadTrajectory(out_csv);
  ASSERT_EQ(live.size(), x.views().size());
  const std::string log_csv = LogModePoses(x, "poses_log_for_live");
  ASSERT_FALSE(log_csv.empty());
  EXPECT_EQ(ReadText(out_csv), ReadText(log_csv));
  EXPECT_FALSE(std::ifstream(out_csv + ".partial")) << "a clean exit removes the partial trajectory";
}

// Issue 14, live: one camera's messages lag the others by ~5 frames (detectors drifting apart) and one
// message is stamped +100 s. The lag is measured and waited for (within tracker.max_wait_ms), the future
// message is rejected naming its camera: every frame is solved with every camera, exactly as --log mode.
TEST(TrackerProcess, LiveWaitsForALaggingCameraAndIgnoresAFutureUtime) {
  const Session& x = Session::Get();
  const int port = 7747;
  const std::string err = x.dir + "/lagging.txt", out_csv = x.dir + "/poses_lagging.csv";
  const auto tracker = StartLiveTracker(x, port, out_csv, err);
  ASSERT_TRUE(tracker) << ReadText(err);
  lcm::LCM lcm(TestUrl(port));
  ASSERT_TRUE(lcm.good());
  PoseCollector collector(lcm);
  constexpr size_t kLagFrames = 4;  // x 8 ms: ~32 ms, beyond the 15 ms deadline, within 100 ms
  const size_t frames = x.views().size();
  for (size_t f = 0; f < frames + kLagFrames; ++f) {
    if (f < frames)
      for (size_t c = 0; c + 1 < x.views()[f].size(); ++c)
        lcm.publish(DetectionsChannel(x.views()[f][c].camera), &x.views()[f][c]);
    if (f >= kLagFrames) {
      const detections_t& late = x.views()[f - kLagFrames].back();
      lcm.publish(DetectionsChannel(late.camera), &late);
    }
    if (f == 40) {
      detections_t future = x.views()[f][0];
      future.utime += 100000000;
      lcm.publish(DetectionsChannel(future.camera), &future);
    }
    const auto next = std::chrono::steady_clock::now() + 8ms;  // paced: 8 ms per frame
    while (std::chrono::steady_clock::now() < next) lcm.handleTimeout(1);
  }
  Receive(
      lcm, [&] { return collector.poses.size() >= frames; }, 10s);
  tracker->Signal(SIGINT);
  EXPECT_EQ(tracker->Wait(20), 0) << ReadText(err);
  const std::string log = ReadText(err);
  EXPECT_NE(log.find("camera '" + x.views()[40][0].camera + "': utime"), std::string::npos) << log;
  ASSERT_EQ(collector.poses.size(), frames) << log;
  const std::string log_csv = LogModePoses(x, "poses_log_for_lagging");
  ASSERT_FALSE(log_csv.empty());
  EXPECT_EQ(ReadText(out_csv), ReadText(log_csv)) << log;
}

// kill -9 mid-run: every pose published before the kill is in OUT.partial (appended and flushed as it is
// computed), equal to --log mode's rows; OUT itself is not written half.
TEST(TrackerProcess, KilledTrackerLeavesEveryPoseInThePartialFile) {
  const Session& x = Session::Get();
  const int port = 7746;
  const std::string err = x.dir + "/killed.txt", out_csv = x.dir + "/poses_killed.csv";
  const auto tracker = StartLiveTracker(x, port, out_csv, err);
  ASSERT_TRUE(tracker) << ReadText(err);
  lcm::LCM lcm(TestUrl(port));
  ASSERT_TRUE(lcm.good());
  PoseCollector collector(lcm);
  const size_t half = x.views().size() / 2;
  for (size_t f = 0; f < half; ++f) {
    for (const auto& d : x.views()[f]) lcm.publish(DetectionsChannel(d.camera), &d);
    lcm.handleTimeout(3);
  }
  Receive(
      lcm, [&] { return collector.poses.size() >= half; }, 10s);
  ASSERT_EQ(collector.poses.size(), half) << ReadText(err);
  tracker->Signal(SIGKILL);
  tracker->Wait(20);
  EXPECT_FALSE(std::ifstream(out_csv));
  const auto partial = ReadTrajectory(out_csv + ".partial");
  ASSERT_EQ(partial.size(), half);
  const std::string log_csv = LogModePoses(x, "poses_log_for_killed");
  ASSERT_FALSE(log_csv.empty());
  const auto full = ReadTrajectory(log_csv);
  for (size_t f = 0; f < half; ++f) EXPECT_EQ(TrajectoryCsvLine(partial[f]), TrajectoryCsvLine(full[f]));
}

// The same log replayed by the real lcm-logplayer into a live tracker gives the same poses as --log.
TEST(TrackerProcess, LogplayerReplayGivesTheSamePosesAsLogMode) {
  const Session& x = Session::Get();
  const int port = 7742;
  const std::string err = x.dir + "/replay.txt", out_csv = x.dir + "/poses_replay.csv";
  const auto tracker = StartLiveTracker(x, port, out_csv, err);
  ASSERT_TRUE(tracker) << ReadText(err);
  lcm::LCM lcm(TestUrl(port));
  ASSERT_TRUE(lcm.good());
  PoseCollector collector(lcm);
  // Receive while the player plays (udpm delivers every message on the group to every socket: an idle
  // receiver would overflow its buffer).
  test::Child player({"/usr/bin/lcm-logplayer", "--speed=3", "--lcm-url=" + UdpmUrl(port), x.log},
                     x.dir + "/player.txt");
  Receive(
      lcm, [&] { return collector.poses.size() >= x.views().size(); }, 20s);
  EXPECT_EQ(player.Wait(20), 0) << ReadText(x.dir + "/player.txt");
  tracker->Signal(SIGINT);
  EXPECT_EQ(tracker->Wait(20), 0) << ReadText(err);
  EXPECT_EQ(collector.poses.size(), x.views().size());
  const std::string log_csv = LogModePoses(x, "poses_log_for_replay");
  ASSERT_FALSE(log_csv.empty());
  EXPECT_EQ(ReadText(out_csv), ReadText(log_csv));
}

TEST(TrackerProcess, BadInputGivesOneLineErrors) {
  const Session& x = Session::Get();
  std::string out;
  // A map of another rig (camera names differ).
  RigMap other = x.s.map;
  other.cameras[1].name = "north";
  const std::string other_map = x.dir + "/other_map.yaml";
  WriteMap(other_map, other);
  EXPECT_EQ(
      RunProgram({kTracker, "--config", x.rig, "--map", other_map, "--log", x.log}, x.dir + "/b1.txt", &out),
      1);
  EXPECT_NE(out.find("mcmt-tracker: error:"), std::string::npos) << out;
  EXPECT_NE(out.find("'north'"), std::string::npos) << out;
  EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
  // Missing log, missing map file, missing --config.
  EXPECT_EQ(RunProgram({kTracker, "--config", x.rig, "--map", x.map, "--log", x.dir + "/nope.lcmlog"},
                       x.dir + "/b2.txt", &out),
            1);
  EXPECT_NE(out.find("nope.lcmlog"), std::string::npos) << out;
  EXPECT_EQ(RunProgram({kTracker, "--config", x.rig, "--map", x.dir + "/nomap.yaml", "--log", x.log},
                       x.dir + "/b3.txt", &out),
            1);
  EXPECT_NE(out.find("nomap.yaml"), std::string::npos) << out;
  EXPECT_EQ(RunProgram({kTracker, "--map", x.map}, x.dir + "/b4.txt", &out), 2);
  EXPECT_NE(out.find("--config"), std::string::npos) << out;
  // Nothing written on failure.
  const std::string never = x.dir + "/never.csv";
  EXPECT_EQ(RunProgram({kTracker, "--config", x.rig, "--map", other_map, "--log", x.log, "--out", never},
                       x.dir + "/b5.txt", &out),
            1);
  EXPECT_FALSE(std::ifstream(never).good());
  EXPECT_FALSE(std::ifstream(never + ".partial").good());
  // An --out that cannot be written is refused at the start, not after a day of tracking.
  EXPECT_EQ(RunProgram({kTracker, "--config", x.rig, "--map", x.map, "--log", x.log, "--out",
                        x.dir + "/no_such_dir/poses.csv"},
                       x.dir + "/b6.txt", &out),
            1);
  EXPECT_NE(out.find("no_such_dir/poses.csv.partial: cannot write"), std::string::npos) << out;
  EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
}

// --log with --lcm-url: the poses of a log are also published.
TEST(TrackerProcess, LogModePublishesWithLcmUrl) {
  const Session& x = Session::Get();
  const int port = 7745;
  lcm::LCM lcm(TestUrl(port));
  ASSERT_TRUE(lcm.good());
  PoseCollector collector(lcm);
  const std::string err = x.dir + "/logpub.txt";
  test::Child tracker(
      {kTracker, "--config", x.rig, "--map", x.map, "--log", x.log, "--lcm-url", UdpmUrl(port)}, err);
  Receive(
      lcm, [&] { return collector.poses.size() >= x.views().size(); }, 20s);
  EXPECT_EQ(tracker.Wait(20), 0) << ReadText(err);
  ASSERT_EQ(collector.poses.size(), x.views().size()) << ReadText(err);
  for (size_t f = 0; f < collector.poses.size(); ++f)
    EXPECT_EQ(collector.poses[f].seq, static_cast<int64_t>(f));
}

// No --map: the tracker waits for MCMT_MAP, then tracks.
TEST(TrackerProcess, LiveWaitsForMapMessage) {
  const Session& x = Session::Get();
  const int port = 7743;
  const std::string err = x.dir + "/waitmap.txt";
  test::Child tracker({kTracker, "--config", x.rig, "--lcm-url", UdpmUrl(port)}, err);
  ASSERT_TRUE(WaitForText(err, "ready", 20)) << ReadText(err);
  lcm::LCM lcm(TestUrl(port));
  PoseCollector collector(lcm);
  const rig_map_t map_msg = ToRigMapMsg(x.s.map, 42);
  lcm.publish(kMapChannel, &map_msg);
  ASSERT_TRUE(WaitForText(err, "using map from MCMT_MAP", 10)) << ReadText(err);
  for (size_t f = 0; f < 30; ++f) {
    for (const auto& d : x.views()[f]) lcm.publish(DetectionsChannel(d.camera), &d);
    lcm.handleTimeout(3);
  }
  Receive(
      lcm, [&] { return collector.poses.size() >= 30; }, 10s);
  tracker.Signal(SIGINT);
  EXPECT_EQ(tracker.Wait(20), 0) << ReadText(err);
  ASSERT_EQ(collector.poses.size(), 30u) << ReadText(err);
  for (size_t f = 0; f < 30; ++f) EXPECT_EQ(collector.poses[f].seq, static_cast<int64_t>(f));
}

}  // namespace
}  // namespace mcmt
