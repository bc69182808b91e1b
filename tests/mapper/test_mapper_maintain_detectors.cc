// Continuous calibration live from images (issue 17), every part its own process over udpm (ports
// 7990-7999):
//   mcmt-sim renders a 4-camera session to videos (640x480, 400 frames), cam2 bumped at frame 100 (0.5 deg,
//   3 mm);
//   one mcmt-detector per camera reads its video and publishes its detections at the recording's pace
//   (--fps 15, every detector started on one wall time);
//   mcmt-tracker tracks with the map of the session's start (its ground truth before the bump);
//   mcmt-mapper --maintain re-estimates cam2 once the tracker reports it (from 250 frames) and publishes
//   a new map;
//   a subscriber (this test) checks every pose against the truth, cam2's states and the new map.
// test_mapper_maintain_process is the same pipeline fed detections (a sixth camera added too).
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <iostream>
#include <map>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "core/files.h"
#include "core/lcm_util.h"
#include "sim/eval.h"
#include "sim/sim.h"
#include "tests/mapper/maintain_watch.h"
#include "tests/support/process.h"
#include "tests/support/temp_dir.h"

namespace mcmt {
namespace {

using namespace std::chrono_literals;

constexpr int kFrames = 400;
constexpr int kBumpFrame = 100;
constexpr double kFps = 15.0;  // the detectors' pace (half the recording's 30: four detectors, shared cores)

bool Built(const std::string& program) { return access(test::Bin(program).c_str(), X_OK) == 0; }

TEST(MapperMaintainDetectors, RenderedBumpFoundReestimatedAndNoPoseCorrupted) {
  for (const char* program : {"mcmt-sim", "mcmt-detector", "mcmt-tracker", "mcmt-mapper"})
    if (!Built(program)) GTEST_SKIP() << program << " not built in " << MCMT_BIN_DIR;
  test::TempDir dir("maintain_detectors");
  const test::ProcessResult sim = test::RunCommand(
      test::Bin("mcmt-sim") + " --out " + dir.str() + " --cameras 4 --frames " + std::to_string(kFrames) +
      " --seed 3 --video --threads 2 --quiet --move-camera cam2," + std::to_string(kBumpFrame) + ",0.5,3");
  ASSERT_EQ(sim.exit_code, 0) << sim.output;
  const sim::GroundTruth truth = sim::ReadGroundTruth(dir / "ground_truth.yaml");
  std::vector<TrajectoryRow> truth_rows;
  WriteMap(dir / "map.yaml", sim::MapFromGroundTruth(truth, 0, 0, &truth_rows));  // cam2 before the bump
  std::map<int64_t, Rigid3> truth_at;
  for (const TrajectoryRow& r : truth_rows) truth_at[r.seq] = r.rig_from_object;

  // cam2 is re-estimated from the default 200 frames (mapper.maintain_frames), within the 300
  // frames of the bump: 0.420 mm on this session (150 frames: 0.574, decided by two 10 px markers at
  // 74-75 deg; BENCHMARKS.md "Which corners moved").
  const std::string url = test::UdpmUrl(7990);
  test::Received got;
  test::Subscriber subscriber(url, &got);
  ASSERT_TRUE(subscriber.good());
  // The point here is what the poses and the maintained map are, not latency: a frame waits up to 2 s
  // for its cameras (complete frames go out at once). With 100 ms, four detectors of 640x480 videos on a
  // loaded machine (2 cores, load 10-15) lagged each other by more, the tracker dropped their views as late
  // and reported too few frames for a new map (helper speed2's run, 2026-12-04).
  test::Child tracker({test::Bin("mcmt-tracker"), "--config", dir / "rig.yaml", "--map", dir / "map.yaml",
                       "--lcm-url", url, "--deadline-ms", "2000"},
                      dir / "tracker.txt");
  test::Child maintainer({test::Bin("mcmt-mapper"), "--config", dir / "rig.yaml", "--map", dir / "map.yaml",
                          "--maintain", "--lcm-url", url, "--threads", "1"},
                         dir / "mapper.txt");
  ASSERT_TRUE(test::WaitForText(dir / "tracker.txt", "mcmt-tracker: ready", 20))
      << test::ReadText(dir / "tracker.txt");
  ASSERT_TRUE(test::WaitForText(dir / "mapper.txt", "maintain: keeping", 20))
      << test::ReadText(dir / "mapper.txt");
  // Every detector publishes frame k at the same wall time (start + k / fps).
  const std::string start = std::to_string(NowUtime() + 3000000);
  std::vector<std::unique_ptr<test::Child>> detectors;
  for (const sim::SimCamera& c : truth.cameras)
    detectors.push_back(std::make_unique<test::Child>(
        std::vector<std::string>{test::Bin("mcmt-detector"), "--config", dir / "rig.yaml", "--camera", c.name,
                                 "--lcm-url", url, "--rate", "realtime", "--fps", std::to_string(kFps),
                                 "--start-wall-utime", start, "--quiet"},
        dir / ("detector_" + c.name + ".txt")));
  const double run_s = 3.0 + kFrames / kFps;
  for (size_t i = 0; i < detectors.size(); ++i)
    EXPECT_EQ(detectors[i]->Wait(run_s + 60), 0)
        << test::ReadText(dir / ("detector_" + truth.cameras[i].name + ".txt"));
  std::this_thread::sleep_for(1s);
  tracker.Signal(SIGINT);
  maintainer.Signal(SIGINT);
  EXPECT_EQ(tracker.Wait(20), 0) << test::ReadText(dir / "tracker.txt");
  EXPECT_EQ(maintainer.Wait(20), 0) << test::ReadText(dir / "mapper.txt");
  const std::string logs =
      "tracker:\n" + test::ReadText(dir / "tracker.txt") + "\nmapper:\n" + test::ReadText(dir / "mapper.txt");
  std::lock_guard<std::mutex> lock(got.mutex);

  // One new map within 300 frames of the bump, cam2 where it went: within 0.5 mm and 0.05 deg.
  ASSERT_EQ(got.maps.size(), 1u) << logs;
  EXPECT_LE(got.maps[0].last_pose_seq, kBumpFrame + 300) << logs;
  const RigMap maintained = got.maps[0].msg.map;
  const sim::EvalResult eval = sim::Evaluate(sim::TruthAtEnd(truth), &maintained, nullptr);
  EXPECT_LT(eval.camera_position_mm.max, 0.5) << logs;
  EXPECT_LT(eval.camera_rotation_deg.max, 0.05) << logs;
  std::cout << "new map after pose " << got.maps[0].last_pose_seq << ": cameras within "
            << eval.camera_position_mm.max << " mm, " << eval.camera_rotation_deg.max << " deg\n";

  // cam2 suspect within 30 frames of the bump and excluded under the first map, ok under the new one; the
  // other cameras always ok.
  const int64_t frame_us = static_cast<int64_t>(1e6 / kFps);
  int64_t suspect_seq = -1;
  bool excluded = false, back_ok = false;
  for (const tracker_status_t& s : got.statuses) {
    for (const camera_health_t& h : s.cameras) {
      if (h.camera != "cam2") {
        EXPECT_EQ(h.state, camera_health_t::STATE_OK) << h.camera << ": " << s.message;
        continue;
      }
      if (s.map_utime == 0 && h.state != camera_health_t::STATE_OK && suspect_seq < 0)
        suspect_seq = (h.since_utime - sim::kStartUtime) / frame_us;
      excluded = excluded || (s.map_utime == 0 && h.state == camera_health_t::STATE_EXCLUDED);
      back_ok = back_ok || (s.map_utime == got.maps[0].msg.utime && h.state == camera_health_t::STATE_OK &&
                            h.frames > 30);
    }
  }
  EXPECT_TRUE(excluded) << logs;
  EXPECT_GE(suspect_seq, kBumpFrame) << logs;
  EXPECT_LE(suspect_seq, kBumpFrame + 30) << logs;
  EXPECT_TRUE(back_ok) << logs;
  std::cout << "cam2 suspect at frame " << suspect_seq << " (bumped at " << kBumpFrame << ")\n";

  // Every pose near the truth: none more than twice the largest error before the bump, each error in
  // units of the pose's own published uncertainty. In millimetres alone a frame that only two cameras see
  // after cam2 is excluded (seq 131 here: cam0 and cam3, two markers, 1.7 mm against 0.26 mm before the
  // bump) would count as corrupted although its covariance says it is 10x less certain; a pose pulled off
  // by the bumped camera keeps the covariance of a good frame and fails this bound.
  const test::PoseErrors errors = test::CheckPoses(got.poses, truth_at, kBumpFrame);
  EXPECT_LE(errors.worst_ratio, 2.0 * errors.normal_ratio)
      << "normal " << errors.normal_ratio << " of its sigma, worst at seq " << errors.worst_ratio_seq;
  EXPECT_GE(errors.tracked, kFrames - 9) << logs;  // udpm on loopback may drop a rare datagram
  std::cout << "poses: " << errors.tracked << " tracked, normal error " << errors.normal_mm << " mm, worst "
            << errors.worst_mm << " mm (seq " << errors.worst_seq << "); error / own sigma: normal "
            << errors.normal_ratio << ", worst " << errors.worst_ratio << " (seq " << errors.worst_ratio_seq
            << ")\n";
}

}  // namespace
}  // namespace mcmt
