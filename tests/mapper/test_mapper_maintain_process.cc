// Continuous calibration live (issue 17), every part its own process over udpm (ports 7980-7989):
//   a replayer (this test) publishes a detections session of mcmt-sim's generator at twice its speed:
//   cam2 bumped at frame 150 (0.5 deg, 3 mm), a sixth camera cam5 publishing from frame 400;
//   mcmt-tracker tracks with the map of the session's start (its ground truth before the bump, no cam5);
//   mcmt-mapper --maintain re-estimates cam2 once the tracker reports it, adds cam5, publishes new maps;
//   a subscriber (this test) checks every pose against the truth, the tracker's camera states, the maps.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "core/files.h"
#include "core/lcm_util.h"
#include "core/log_reader.h"
#include "mcmt/camera_health_t.hpp"
#include "mcmt/object_pose_t.hpp"
#include "mcmt/tracker_status_t.hpp"
#include "sim/eval.h"
#include "sim/sim.h"
#include "tests/mapper/maintain_watch.h"
#include "tests/support/process.h"
#include "tests/support/temp_dir.h"

namespace mcmt {
namespace {

using namespace std::chrono_literals;
using test::Health;
using test::Received;
using test::Subscriber;
using test::UdpmUrl;

constexpr int kFrames = 1050;  // margin: under load the sixth camera's map came as late as frame 899
constexpr int kBumpFrame = 150;
constexpr int kAddFrame = 400;
constexpr double kSpeed = 2.0;    // replay at 60 fps
constexpr int kTailFrames = 150;  // held back until the second map is in (Replay)

// Publishes the log's events at kSpeed times their pace (event time = message utime). The session's last
// kTailFrames frames wait (at most 60 s) until `got` holds the mapper's second map: under load it has come
// as late as the session's end (frame 1050 on a loaded CI machine), and the test judges the tracker with
// the new map, not the machine's load.
void Replay(const std::string& log, const std::string& url, Received* got) {
  lcm::LCM lcm(url);
  ASSERT_TRUE(lcm.good());
  const std::vector<LogEvent> events = ReadEventLog(log);
  ASSERT_FALSE(events.empty());
  auto start = std::chrono::steady_clock::now();
  const int64_t t0 = events.front().timestamp;
  const int64_t tail_utime = sim::FrameUtime(kFrames - kTailFrames, 30.0);
  bool held = false;
  for (const LogEvent& e : events) {
    if (!held && e.timestamp >= tail_utime) {
      held = true;
      const auto hold = std::chrono::steady_clock::now();
      while (std::chrono::steady_clock::now() - hold < 60s) {
        {
          std::lock_guard<std::mutex> lock(got->mutex);
          if (got->maps.size() >= 2) break;
        }
        std::this_thread::sleep_for(20ms);
      }
      start += std::chrono::steady_clock::now() - hold;  // the pace resumes after the hold
    }
    std::this_thread::sleep_until(
        start + std::chrono::microseconds(static_cast<int64_t>((e.timestamp - t0) / kSpeed)));
    lcm.publish(e.channel, e.data.data(), static_cast<unsigned>(e.data.size()));
  }
}

TEST(MapperMaintainProcess, BumpedCameraReestimatedNewCameraAddedNoPoseCorrupted) {
  test::TempDir dir("maintain_process");
  sim::DatasetOptions o = sim::DetectionsOnlySession(dir.str(), kFrames, 7);
  o.moves = {{"cam2", kBumpFrame, 0.5, 3.0}};
  o.add_camera_frame = kAddFrame;
  const sim::GroundTruth truth = sim::GenerateDataset(o).truth;
  // The map in use: the truth at the session's start, without the sixth camera.
  std::vector<TrajectoryRow> truth_rows;
  RigMap map = sim::MapFromGroundTruth(truth, 0, 0, &truth_rows);
  map.cameras.erase(std::remove_if(map.cameras.begin(), map.cameras.end(),
                                   [](const MapCamera& c) { return c.name == "cam5"; }),
                    map.cameras.end());
  ASSERT_EQ(map.cameras.size(), 5u);
  WriteMap(dir / "map.yaml", map);
  std::map<int64_t, Rigid3> truth_at;
  for (const TrajectoryRow& r : truth_rows) truth_at[r.seq] = r.rig_from_object;

  const std::string url = UdpmUrl(7980);
  Received got;
  Subscriber subscriber(url, &got);
  ASSERT_TRUE(subscriber.good());
  test::Child tracker(
      {test::Bin("mcmt-tracker"), "--config", dir / "rig.yaml", "--map", dir / "map.yaml", "--lcm-url", url},
      dir / "tracker.txt");
  test::Child maintainer({test::Bin("mcmt-mapper"), "--config", dir / "rig.yaml", "--map", dir / "map.yaml",
                          "--maintain", "--lcm-url", url, "--out", dir / "maintained", "--threads", "1"},
                         dir / "mapper.txt");
  ASSERT_TRUE(test::WaitForText(dir / "tracker.txt", "mcmt-tracker: ready", 20))
      << test::ReadText(dir / "tracker.txt");
  ASSERT_TRUE(test::WaitForText(dir / "mapper.txt", "maintain: keeping", 20))
      << test::ReadText(dir / "mapper.txt");
  Replay(dir / "detections.lcmlog", url, &got);
  std::this_thread::sleep_for(1s);
  tracker.Signal(SIGINT);
  maintainer.Signal(SIGINT);
  EXPECT_EQ(tracker.Wait(20), 0) << test::ReadText(dir / "tracker.txt");
  EXPECT_EQ(maintainer.Wait(20), 0) << test::ReadText(dir / "mapper.txt");
  const std::string logs =
      "tracker:\n" + test::ReadText(dir / "tracker.txt") + "\nmapper:\n" + test::ReadText(dir / "mapper.txt");
  std::lock_guard<std::mutex> lock(got.mutex);

  // Two new maps, each a higher version: cam2 re-estimated within 300 frames of the bump, then cam5 added.
  ASSERT_EQ(got.maps.size(), 2u) << logs;
  EXPECT_GT(got.maps[1].msg.utime, got.maps[0].msg.utime);
  EXPECT_LE(got.maps[0].last_pose_seq, kBumpFrame + 300) << logs;
  const sim::GroundTruth at_end = sim::TruthAtEnd(truth);
  {
    const RigMap first = got.maps[0].msg.map;
    EXPECT_EQ(first.cameras.size(), 5u);
    const sim::EvalResult e = sim::Evaluate(at_end, &first, nullptr);
    EXPECT_LT(e.camera_position_mm.max, 0.5) << logs;
    EXPECT_LT(e.camera_rotation_deg.max, 0.05) << logs;
    std::cout << "first map: cameras within " << e.camera_position_mm.max << " mm, "
              << e.camera_rotation_deg.max << " deg\n";
  }
  {
    const RigMap second = got.maps[1].msg.map;
    ASSERT_EQ(second.cameras.size(), 6u);
    const sim::EvalResult e = sim::Evaluate(at_end, &second, nullptr);
    EXPECT_LT(e.camera_position_mm.max, 1.0) << logs;
    EXPECT_LT(e.camera_rotation_deg.max, 0.05) << logs;
    std::cout << "second map: cameras within " << e.camera_position_mm.max << " mm, "
              << e.camera_rotation_deg.max << " deg\n";
    EXPECT_TRUE(ReadMap(dir / "maintained/map.yaml").FindCamera("cam5"));
  }
  bool noted = false;
  for (const std::string& m : got.mapper_messages)
    noted = noted || m.find("camera 'cam2' re-estimated") != std::string::npos;
  EXPECT_TRUE(noted) << logs;

  // The tracker: cam2 excluded under the first map, ok under the newer one; cam5 judged once added.
  bool excluded = false, back_ok = false, cam5_ok = false;
  int64_t suspect_seq = -1;  // frame at which cam2 left ok
  for (const tracker_status_t& s : got.statuses) {
    const camera_health_t* h = Health(s, "cam2");
    ASSERT_TRUE(h);
    if (s.map_utime == 0 && h->state != camera_health_t::STATE_OK && suspect_seq < 0)
      suspect_seq = (h->since_utime - sim::FrameUtime(0, 30.0)) / 33333;
    if (s.map_utime == 0 && h->state == camera_health_t::STATE_EXCLUDED) excluded = true;
    if (s.map_utime == got.maps[0].msg.utime && h->state == camera_health_t::STATE_OK && h->frames > 30)
      back_ok = true;
    const camera_health_t* h5 = Health(s, "cam5");
    if (h5 && h5->state == camera_health_t::STATE_OK && h5->frames > 30) cam5_ok = true;
    if (s.map_utime != 0) {
      EXPECT_NE(h->state, camera_health_t::STATE_EXCLUDED) << s.message;
    }
  }
  EXPECT_TRUE(excluded) << logs;
  EXPECT_GE(suspect_seq, kBumpFrame);
  EXPECT_LE(suspect_seq, kBumpFrame + 30);
  std::cout << "cam2 suspect at frame " << suspect_seq << " (bumped at " << kBumpFrame << ")\n";
  EXPECT_TRUE(back_ok) << logs;
  EXPECT_TRUE(cam5_ok) << logs;

  // Every pose near the truth: no more than twice the largest error before the bump.
  const test::PoseErrors errors = test::CheckPoses(got.poses, truth_at, kBumpFrame);
  ASSERT_GT(errors.normal_mm, 0.0);
  int with_cam5 = 0;
  for (const auto& [seq, p] : got.poses)
    with_cam5 += p.status == 0 && std::count(p.cameras.begin(), p.cameras.end(), "cam5") > 0;
  EXPECT_LE(errors.worst_mm, 2.0 * errors.normal_mm)
      << "normal " << errors.normal_mm << " mm, worst at seq " << errors.worst_seq;
  EXPECT_GE(errors.tracked, kFrames - 9) << logs;  // udpm on loopback may drop a rare datagram
  EXPECT_GT(with_cam5, 50);
  // No frame lost where the tracker switched maps.
  for (const Received::Map& m : got.maps)
    for (int64_t seq = m.last_pose_seq - 15; seq <= m.last_pose_seq + 15; ++seq)
      EXPECT_TRUE(got.poses.count(seq)) << "seq " << seq << " around a map switch";
  std::cout << "normal error " << errors.normal_mm << " mm, worst " << errors.worst_mm << " mm (seq "
            << errors.worst_seq << "); maps after poses " << got.maps[0].last_pose_seq << ", "
            << got.maps[1].last_pose_seq << "\n";
}

}  // namespace
}  // namespace mcmt
