// The tracker on mcmt-sim recordings with the map made by mcmt-mapper (real programs), measured with
// the simulator's evaluation (rigid alignments of the map's frames to the ground truth):
// accuracy at radius 1.0 m, a pose for every frame where a mapped marker is seen, a camera killed
// mid-run, false markers (mapped ids placed where they are not) injected.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <set>
#include <tuple>

#include "core/files.h"
#include "core/lcm_util.h"
#include "sim/eval.h"
#include "sim/sim.h"
#include "tests/support/process.h"
#include "tests/support/temp_dir.h"
#include "tests/support/udpm.h"

namespace mcmt {
namespace {

using test::RunProgram;

const std::string kBin = MCMT_BIN_DIR;

bool HavePrograms() { return test::ProgramsBuilt({"mcmt-sim", "mcmt-mapper", "mcmt-tracker"}); }

struct Recording {
  std::string dir, rig, log, map, truth;
  RigMap rig_map;
};

// mcmt-sim --detections-only + mcmt-mapper, once per object.
Recording Record(const std::string& object, int frames, uint64_t seed) {
  Recording r;
  r.dir = test::MakeTempDir("tracker_sim_" + object);
  std::string out;
  EXPECT_EQ(
      RunProgram({kBin + "/mcmt-sim", "--out", r.dir, "--object", object, "--radius", "1.0", "--frames",
                  std::to_string(frames), "--seed", std::to_string(seed), "--detections-only", "--quiet"},
                 r.dir + "/sim.txt", &out),
      0)
      << out;
  r.rig = r.dir + "/rig.yaml";
  r.log = r.dir + "/detections.lcmlog";
  r.truth = r.dir + "/ground_truth.yaml";
  EXPECT_EQ(RunProgram({kBin + "/mcmt-mapper", "--config", r.rig, "--log", r.log, "--out", r.dir + "/map"},
                       r.dir + "/mapper.txt", &out),
            0)
      << out;
  r.map = r.dir + "/map/map.yaml";
  r.rig_map = ReadMap(r.map);
  return r;
}

// Rewrites a detections log through `edit` (return false to drop the message).
template <typename Edit>
void RewriteLog(const std::string& in, const std::string& out, Edit edit) {
  lcm::LogFile src(in, "r");
  lcm::LogFile dst(out, "w");
  ASSERT_TRUE(src.good() && dst.good());
  while (const lcm::LogEvent* e = src.readNextEvent()) {
    detections_t d;
    if (!Decode(e->data, e->datalen, &d)) continue;
    if (!edit(&d)) continue;
    std::vector<uint8_t> bytes = Encode(d);
    lcm::LogEvent copy = *e;
    copy.data = bytes.data();
    copy.datalen = static_cast<int32_t>(bytes.size());
    dst.writeEvent(&copy);
  }
}

// Frame seqs in which some camera of the map saw a marker of the map.
std::set<int64_t> FramesWithMappedMarker(const std::string& log, const RigMap& map) {
  std::set<int64_t> out;
  lcm::LogFile src(log, "r");
  while (const lcm::LogEvent* e = src.readNextEvent()) {
    detections_t d;
    if (!Decode(e->data, e->datalen, &d) || !map.FindCamera(d.camera)) continue;
    for (const auto& m : d.markers)
      if (map.FindMarker(m.id)) out.insert(d.seq);
  }
  return out;
}

std::vector<TrajectoryRow> Track(const Recording& r, const std::string& log, const std::string& name) {
  const std::string poses = r.dir + "/" + name + ".csv";
  std::string out;
  EXPECT_EQ(
      RunProgram({kBin + "/mcmt-tracker", "--config", r.rig, "--map", r.map, "--log", log, "--out", poses},
                 r.dir + "/" + name + ".txt", &out),
      0)
      << out;
  return ReadTrajectory(poses);
}

void ExpectAccurate(const Recording& r, const std::vector<TrajectoryRow>& rows, const std::string& what) {
  const sim::GroundTruth truth = sim::ReadGroundTruth(r.truth);
  const sim::EvalResult e = sim::Evaluate(truth, &r.rig_map, &rows);
  std::cout << "[ tracker ] " << what << ": " << e.frames_with_pose << "/" << e.gt_frames
            << " frames, object translation mean " << e.object_translation_mm.mean << " mm (max "
            << e.object_translation_mm.max << "), rotation mean " << e.object_rotation_deg.mean
            << " deg (max " << e.object_rotation_deg.max << ")" << std::endl;
  EXPECT_LE(e.object_translation_mm.mean, 0.5) << what;
  EXPECT_LE(e.object_rotation_deg.mean, 0.3) << what;
}

std::set<int64_t> Seqs(const std::vector<TrajectoryRow>& rows) {
  std::set<int64_t> out;
  for (const auto& r : rows) out.insert(r.seq);
  return out;
}

class TrackerSim : public ::testing::TestWithParam<std::string> {};

TEST_P(TrackerSim, AccurateWithAPoseForEveryFrameWithAMappedMarker) {
  if (!HavePrograms()) GTEST_SKIP() << "mcmt-sim / mcmt-mapper not built in " << kBin;
  const Recording r = Record(GetParam(), 300, 11);
  const auto rows = Track(r, r.log, "poses");
  EXPECT_EQ(Seqs(rows), FramesWithMappedMarker(r.log, r.rig_map));
  ExpectAccurate(r, rows, GetParam());
}

INSTANTIATE_TEST_SUITE_P(Objects, TrackerSim, ::testing::Values("four_sided", "box"));

TEST(TrackerSimRobustness, CameraKilledMidRunAndFalseMarkers) {
  if (!HavePrograms()) GTEST_SKIP() << "mcmt-sim / mcmt-mapper not built in " << kBin;
  const Recording r = Record("four_sided", 240, 5);
  const auto clean = Track(r, r.log, "clean");

  // cam2's messages stop at frame 120: the others carry on, every frame with a mapped marker still posed.
  const std::string killed_log = r.dir + "/killed.lcmlog";
  RewriteLog(r.log, killed_log, [](detections_t* d) { return !(d->camera == "cam2" && d->seq >= 120); });
  const auto killed = Track(r, killed_log, "killed");
  EXPECT_EQ(Seqs(killed), FramesWithMappedMarker(killed_log, r.rig_map));
  ExpectAccurate(r, killed, "cam2 killed at frame 120");
  const std::string killed_err = mcmt::test::ReadText(r.dir + "/killed.txt");
  EXPECT_NE(killed_err.find("camera 'cam2' stopped reporting"), std::string::npos) << killed_err;

  // False markers: in every message of cam1 and cam3 with a marker, a copy of that marker's corners
  // (shifted 2 px) under another mapped id that is not seen there. The poses must not move.
  std::vector<int> ids;
  for (const auto& m : r.rig_map.markers) ids.push_back(m.id);
  const std::string false_log = r.dir + "/false.lcmlog";
  int injected = 0;
  RewriteLog(r.log, false_log, [&](detections_t* d) {
    if ((d->camera != "cam1" && d->camera != "cam3") || d->markers.empty()) return true;
    std::set<int> seen;
    for (const auto& m : d->markers) seen.insert(m.id);
    for (int id : ids) {
      if (seen.count(id)) continue;
      marker_t fake = d->markers[0];
      fake.id = id;
      for (auto& c : fake.corners) c[0] += 2.0;
      d->markers.push_back(fake);
      d->num_markers++;
      ++injected;
      break;
    }
    return true;
  });
  EXPECT_GT(injected, 100);
  const auto dirty = Track(r, false_log, "false");
  ASSERT_EQ(Seqs(dirty), Seqs(clean));
  for (size_t i = 0; i < clean.size(); ++i) {
    EXPECT_LT(TranslationDistance(clean[i].rig_from_object, dirty[i].rig_from_object), 1e-6)
        << "seq " << clean[i].seq;
    EXPECT_LT(RotationAngle(clean[i].rig_from_object, dirty[i].rig_from_object), 1e-5)
        << "seq " << clean[i].seq;
  }
  const std::string err = mcmt::test::ReadText(r.dir + "/false.txt");
  EXPECT_NE(err.find("outliers rejected"), std::string::npos);
  EXPECT_EQ(err.find(" 0 outliers rejected"), std::string::npos) << err;
}

// The published covariance holds the map's error (map.yaml's covariance, core/map_covariance.h;
// PoseEstimator::MapShare): a map calibrated on a short, noisy session (60 frames, 0.5 px corners: cameras
// about 3.5 mm off) tracks a long, clean session of the same rig (300 frames, 0.05 px). Each pose's error is
// then mostly the map's, which every pose shares: from the frame's noise alone (f059f18, and a map file
// without the covariance still) 100 % of the positions were beyond 3 sigma. With the map's share at most a
// few %, and the sigma not hugely wider than the error (its median below twice the mean error). Measured:
// cameras 3.46 mm off, object 1.29 mm (mean); sigma median 0.104 mm -> 1.87 mm, beyond 3 sigma position
// 100 % -> 0.0 %, rotation 0.3 % -> 0.0 %.
TEST(TrackerSimCovariance, HoldsTheMapsErrorNotOnlyTheFramesNoise) {
  if (!HavePrograms()) GTEST_SKIP() << "mcmt-sim / mcmt-mapper not built in " << kBin;
  Recording r;
  r.dir = test::MakeTempDir("tracker_sim_covariance");
  std::string out;
  for (const auto& [name, frames, noise] : {std::tuple<std::string, int, std::string>{"cal", 60, "0.5"},
                                            std::tuple<std::string, int, std::string>{"trk", 300, "0.05"}})
    ASSERT_EQ(RunProgram({kBin + "/mcmt-sim", "--out", r.dir + "/" + name, "--object", "four_sided",
                          "--radius", "1.0", "--frames", std::to_string(frames), "--seed", "3",
                          "--detections-only", "--corner-noise-px", noise, "--quiet"},
                         r.dir + "/sim_" + name + ".txt", &out),
              0)
        << out;
  ASSERT_EQ(RunProgram({kBin + "/mcmt-mapper", "--config", r.dir + "/cal/rig.yaml", "--log",
                        r.dir + "/cal/detections.lcmlog", "--out", r.dir + "/map"},
                       r.dir + "/mapper.txt", &out),
            0)
      << out;
  r.rig = r.dir + "/trk/rig.yaml";
  r.truth = r.dir + "/trk/ground_truth.yaml";
  r.map = r.dir + "/map/map.yaml";
  r.rig_map = ReadMap(r.map);
  const std::string log = r.dir + "/trk/detections.lcmlog";
  const sim::GroundTruth truth = sim::ReadGroundTruth(r.truth);
  auto evaluate = [&](const std::string& name, std::vector<double>* sigma_mm) {
    const std::vector<TrajectoryRow> rows = Track(r, log, name);
    for (const TrajectoryRow& row : rows)
      if (row.quality) sigma_mm->push_back(1e3 * row.quality->sigma_position_m);
    std::sort(sigma_mm->begin(), sigma_mm->end());
    const sim::EvalResult e = sim::Evaluate(truth, &r.rig_map, &rows);
    std::printf(
        "[ tracker ] %s: camera position error %.3f mm, object translation error mean %.3f mm (max %.3f), "
        "sigma median %.3f mm; beyond 3 sigma: position %.1f %%, rotation %.1f %%\n",
        name.c_str(), e.camera_position_mm.mean, e.object_translation_mm.mean, e.object_translation_mm.max,
        sigma_mm->empty() ? NAN : (*sigma_mm)[sigma_mm->size() / 2], 100 * e.beyond_3sigma_position,
        100 * e.beyond_3sigma_rotation);
    EXPECT_EQ(e.frames_with_sigma, 300) << name;
    return e;
  };
  std::vector<double> sigma_mm;
  const sim::EvalResult with_map = evaluate("poses", &sigma_mm);
  EXPECT_GT(with_map.camera_position_mm.mean, 1.5);  // the map's error is what this is about
  EXPECT_LE(with_map.beyond_3sigma_position, 0.05);
  EXPECT_LE(with_map.beyond_3sigma_rotation, 0.05);
  ASSERT_FALSE(sigma_mm.empty());
  EXPECT_LT(sigma_mm[sigma_mm.size() / 2], 2.0 * with_map.object_translation_mm.mean);

  // The same map without its covariance (a map written before the key): the frame's noise alone, as before.
  RigMap old_map = r.rig_map;
  r.map = r.dir + "/map/map_without_covariance.yaml";
  WriteMap(r.map, old_map);
  std::vector<double> noise_sigma_mm;
  const sim::EvalResult noise_only = evaluate("poses_noise_only", &noise_sigma_mm);
  EXPECT_GT(noise_only.beyond_3sigma_position, 0.9);
  ASSERT_FALSE(noise_sigma_mm.empty());
  EXPECT_LT(noise_sigma_mm[noise_sigma_mm.size() / 2], 0.5 * sigma_mm[sigma_mm.size() / 2]);
}

// Real processes end to end: mcmt-sim renders images, one mcmt-detector per camera publishes over udpm
// (port 7744) at the recording's frame rate, the live mcmt-tracker publishes poses, a subscriber here
// receives one object_pose_t per frame, in order.
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

TEST(TrackerWithDetectors, DetectorsAndTrackerAsProcessesOverUdpm) {
  if (!HavePrograms() || !test::ProgramsBuilt({"mcmt-detector"}))
    GTEST_SKIP() << "mcmt-sim / mcmt-detector not built in " << kBin;
  const std::string dir = test::MakeTempDir("tracker_detectors");
  const int frames = 30;
  std::string out;
  ASSERT_EQ(RunProgram({kBin + "/mcmt-sim", "--out", dir, "--cameras", "3", "--frames",
                        std::to_string(frames), "--seed", "4", "--quiet"},
                       dir + "/sim.txt", &out),
            0)
      << out;
  // The map from the ground truth, and the true poses in its frames (rig = cam0's, object = marker 0's).
  const sim::GroundTruth truth = sim::ReadGroundTruth(dir + "/ground_truth.yaml");
  std::vector<TrajectoryRow> truth_rows;
  WriteMap(dir + "/map.yaml", sim::MapFromGroundTruth(truth, 0, 0, &truth_rows));
  const std::string url = test::UdpmUrl(7744);
  const std::string tracker_err = dir + "/tracker.txt";
  test::Child tracker(
      // The detector processes publish each frame at a shared wall-clock schedule (--start-wall-utime, 2 s
      // ahead); one ready late (a loaded machine) publishes its frames already due at once: a generous
      // frame deadline and wait let every frame wait for all three. (With the default 100 ms wait, a run
      // on a machine at load 8 dropped every view of one camera as late: max_cams 2.)
      {kBin + "/mcmt-tracker", "--config", dir + "/rig.yaml", "--map", dir + "/map.yaml", "--lcm-url", url,
       "--deadline-ms", "3000", "--max-wait-ms", "3000"},
      tracker_err);
  ASSERT_TRUE(test::WaitForText(tracker_err, "ready", 20)) << test::ReadText(tracker_err);
  lcm::LCM lcm(url + "&recv_buf_size=4194304");  // sees every message on the group
  ASSERT_TRUE(lcm.good());
  PoseCollector collector(lcm);
  std::vector<std::unique_ptr<test::Child>> detectors;
  const std::string start = std::to_string(NowUtime() + 2000000);
  for (const auto& c : truth.cameras)
    detectors.push_back(std::make_unique<test::Child>(
        std::vector<std::string>{kBin + "/mcmt-detector", "--config", dir + "/rig.yaml", "--camera", c.name,
                                 "--lcm-url", url, "--rate", "realtime", "--start-wall-utime", start,
                                 "--quiet"},
        dir + "/detector_" + c.name + ".txt"));
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (collector.poses.size() < static_cast<size_t>(frames) && std::chrono::steady_clock::now() < end)
    lcm.handleTimeout(20);
  for (size_t i = 0; i < detectors.size(); ++i)
    EXPECT_EQ(detectors[i]->Wait(30), 0)
        << test::ReadText(dir + "/detector_" + truth.cameras[i].name + ".txt");
  tracker.Signal(SIGINT);
  EXPECT_EQ(tracker.Wait(20), 0) << test::ReadText(tracker_err);
  ASSERT_EQ(collector.poses.size(), static_cast<size_t>(frames)) << mcmt::test::ReadText(tracker_err);
  double mean_t = 0;
  int max_cams = 0;
  for (int f = 0; f < frames; ++f) {
    const object_pose_t& p = collector.poses[f];
    EXPECT_EQ(p.seq, f);
    EXPECT_EQ(p.utime, truth.frames[f].utime);
    // A frame where one camera sees one square may be flagged ambiguous; never lost here.
    ASSERT_NE(p.status, object_pose_t::STATUS_LOST) << "frame " << f;
    if (p.status == object_pose_t::STATUS_AMBIGUOUS) {
      EXPECT_EQ(p.num_cameras, 1);
      EXPECT_EQ(p.num_markers, 1);
    }
    mean_t += TranslationDistance(FromPose3d(p.rig_from_object), truth_rows[f].rig_from_object);
    max_cams = std::max(max_cams, p.num_cameras);
  }
  mean_t /= frames;
  std::cout << "[ tracker ] detectors on rendered images: mean translation error " << mean_t * 1000 << " mm"
            << std::endl;
  EXPECT_LT(mean_t, 2e-3);
  EXPECT_EQ(max_cams, 3);  // frames assembled across the detector processes
}

}  // namespace
}  // namespace mcmt
