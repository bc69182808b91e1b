// The tracker on real footage (caliscope ChArUco session, ../shared/data/caliscope): the project's
// detector, the mapper's map, then every frame tracked by TrackerNode (log mode). With the map fixed,
// the tracker solves the bundle adjustment's per-frame sub-problem: its poses must agree with the
// mapper's refined trajectory, with sub-pixel residuals, and every frame with a mapped marker is posed.
// Camera health on the same session detected with each camera's own frame times: not judged (and said
// so) while the cameras' frames fall apart, judged ok with the map's clock offsets.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <map>

#include "core/config.h"
#include "core/files.h"
#include "core/lcm_util.h"
#include "core/log_reader.h"
#include "core/math.h"
#include "core/stop.h"
#include "detector/detector.h"
#include "mapper/mapper.h"
#include "mcmt/tracker_status_t.hpp"
#include "tests/support/caliscope.h"
#include "tests/support/temp_dir.h"
#include "tracker/tracker.h"

namespace mcmt {
namespace {

const std::string kData = std::string(MCMT_SOURCE_DIR) + "/../shared/data/caliscope";

TEST(TrackerRealData, CharucoSessionAgreesWithTheMappersTrajectory) {
  if (!std::filesystem::exists(kData + "/charuco_calibration/cam_0.mp4"))
    GTEST_SKIP() << "real data not found at " << kData << " (the caliscope sessions of ../shared/data)";
  const RigConfig rig = LoadRigConfig(std::string(MCMT_SOURCE_DIR) + "/configs/caliscope_charuco.yaml");
  std::vector<detections_t> detections;
  for (const CameraConfig& c : rig.cameras) {
    std::vector<detections_t> d = DetectRecording(rig, c.name);
    detections.insert(detections.end(), d.begin(), d.end());
  }
  // As a log would hold them: by capture time, cameras in turn.
  std::stable_sort(detections.begin(), detections.end(),
                   [](const detections_t& a, const detections_t& b) { return a.utime < b.utime; });
  Mapper mapper(MapperOptions::FromConfig(rig));
  for (const auto& d : detections) mapper.Add(d);
  const MapResult mapped = mapper.Solve();

  lcm::LCM lcm("memq://");
  TrackerNodeOptions options;
  options.tracker = TrackerOptions::FromConfig(rig);
  options.log_mode = true;
  options.keep_trajectory = true;
  options.quiet = true;
  TrackerNode node(lcm, rig, options, mapped.map);
  std::set<int64_t> with_marker;  // frame utimes where a mapped camera saw a mapped marker
  for (const auto& d : detections) {
    const auto bytes = Encode(d);
    node.OnDetections(DetectionsChannel(d.camera), bytes.data(), bytes.size());
    if (!mapped.map.FindCamera(d.camera)) continue;
    for (const auto& m : d.markers)
      if (mapped.map.FindMarker(m.id)) with_marker.insert(d.utime);
  }
  node.Flush();

  // A pose for every frame with a mapped marker (frames are keyed by the utime that opened them; the
  // session's cameras share one time per synchronised frame).
  std::set<int64_t> posed;
  for (const auto& row : node.trajectory()) posed.insert(row.utime);
  EXPECT_EQ(posed, with_marker);

  std::map<int64_t, Rigid3> mapper_pose;
  for (const auto& row : mapped.trajectory) mapper_pose[row.utime] = row.rig_from_object;
  std::vector<double> dt, dr, rms;
  for (const auto& row : node.trajectory()) {
    rms.push_back(row.rms_px);
    auto it = mapper_pose.find(row.utime);
    if (it == mapper_pose.end()) continue;
    dt.push_back(TranslationDistance(row.rig_from_object, it->second));
    dr.push_back(RotationAngle(row.rig_from_object, it->second) * 180 / M_PI);
  }
  ASSERT_GT(dt.size(), 50u);
  std::cout << "[ tracker ] caliscope charuco: " << node.trajectory().size() << " poses, " << dt.size()
            << " compared with the mapper: median difference " << Median(dt) * 1000 << " mm, " << Median(dr)
            << " deg; median rms " << Median(rms) << " px" << std::endl;
  EXPECT_LT(Median(dt), 0.5e-3);
  EXPECT_LT(Median(dr), 0.05);
  EXPECT_LT(Median(rms), 1.0);
  RecordProperty("median_difference_to_mapper_mm", std::to_string(Median(dt) * 1000));
}

// ---------------------------------------------------------------------------------------------------
// Camera health on real clocks. Detected with each camera's own frame times (caliscope_time: camera), the
// session's clocks jitter 5-6 ms RMS and its images show capture latencies of +122, -24, -27 ms against
// cam0 (tests/mapper/test_mapper_selfcal_realdata.cc): at 6 fps no two cameras' views fall within the 2 ms
// sync tolerance of two others once the offsets are applied.

const std::string kRig = std::string(MCMT_SOURCE_DIR) + "/configs/caliscope_charuco.yaml";

// The session mapped once per program with the clock offsets estimated (mapper.time_offsets).
const MapResult& MapWithOffsets(const RigConfig& rig) {
  static const MapResult mapped = [&] {
    MapperOptions options = MapperOptions::FromConfig(rig);
    options.estimate_time_offsets = true;
    Mapper mapper(options);
    for (const auto& d : test::CaliscopeCameraTimeDetections(rig)) mapper.Add(d);
    return mapper.Solve();
  }();
  return mapped;
}

struct HealthRun {
  std::vector<CameraHealth> health;
  std::vector<TrajectoryRow> poses;
  std::vector<tracker_status_t> statuses;
  std::string log;  // the tracker's stderr
  int64_t frames = 0;
};

struct StatusSink {
  std::vector<tracker_status_t>* out;
  void On(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    tracker_status_t msg;
    if (Decode(rbuf->data, rbuf->data_size, &msg)) out->push_back(msg);
  }
};

// The detections written as a log (in camera order: mcmt-tracker --log sorts them by capture time) and
// tracked with `map` and the sync tolerance set to sync_tolerance_ms (< 0: the rig's options as they are,
// the window chosen by the tracker).
HealthRun TrackCameraTimes(const RigConfig& rig, const RigMap& map, double sync_tolerance_ms) {
  test::TempDir dir("tracker_realdata_health");
  std::string bytes;
  int64_t n = 0;
  for (const detections_t& d : test::CaliscopeCameraTimeDetections(rig)) {
    const std::vector<uint8_t> data = Encode(d);
    AppendEncodedEvent(n++, d.utime, DetectionsChannel(d.camera), data.data(), data.size(), &bytes);
  }
  WriteFileAtomic(dir / "detections.lcmlog", bytes);
  TrackerNodeOptions options;
  options.tracker = TrackerOptions::FromConfig(rig);
  if (sync_tolerance_ms >= 0) {
    options.tracker.sync_tolerance_ms = sync_tolerance_ms;
    options.tracker.sync_tolerance_set = true;
  }
  options.log_mode = true;
  options.keep_trajectory = true;
  options.quiet = true;
  lcm::LCM input("memq://"), output("memq://");
  HealthRun run;
  StatusSink sink{&run.statuses};
  output.subscribe(kTrackerStatusChannel, &StatusSink::On, &sink)->setQueueCapacity(1 << 16);
  TrackerNode node(input, rig, options, map, &output);
  testing::internal::CaptureStderr();
  node.RunLog(dir / "detections.lcmlog", StopToken());
  run.log = testing::internal::GetCapturedStderr();
  while (output.handleTimeout(0) > 0) {
  }
  run.health = node.health()->Snapshot();
  run.poses = node.trajectory();
  run.frames = node.stats().frames;
  std::cout << "[ health ] tolerance "
            << (sync_tolerance_ms >= 0 ? std::to_string(sync_tolerance_ms) + " ms" : std::string("chosen"))
            << ", offsets";
  for (const MapCamera& c : map.cameras) std::cout << " " << c.name << " " << 1e-3 * c.time_offset_us;
  std::cout << " ms: " << run.frames << " frames\n";
  for (const CameraHealth& h : run.health)
    std::cout << "[ health ]   " << h.camera << ": " << CameraStateName(h.state) << ", " << h.frames
              << " frames judged, rms " << h.rms_px << " px, baseline " << h.baseline_px << " px\n";
  return run;
}

std::map<int, int> CamerasPerFrame(const HealthRun& run) {
  std::map<int, int> out;
  for (const TrajectoryRow& r : run.poses) out[r.cameras]++;
  return out;
}

#define SKIP_WITHOUT_DATA()                                               \
  if (!std::filesystem::exists(kData + "/charuco_calibration/cam_0.mp4")) \
  GTEST_SKIP() << "real data not found at " << kData << " (the caliscope sessions of ../shared/data)"

// With the map's offsets at the 2 ms tolerance: no view shares a frame with two others, no camera is
// judged, and the tracker says so, naming the cameras, and publishes them "not judged". (Without offsets
// the clocks' jitter puts some views together: 30 of 138 poses from 3-4 cameras, every camera judged in
// 25-30 frames, cam1 at 2.8-14 px, 122 ms off: health cannot be trusted there either.)
TEST(TrackerRealData, CameraTimesApartFromEachOtherLeaveHealthNotJudgedAndSaySo) {
  SKIP_WITHOUT_DATA();
  const RigConfig rig = LoadRigConfig(kRig);
  const HealthRun run = TrackCameraTimes(rig, MapWithOffsets(rig).map, 2.0);
  ASSERT_EQ(run.health.size(), 4u);
  for (const auto& [cameras, frames] : CamerasPerFrame(run))
    std::cout << "[ health ]   " << frames << " poses from " << cameras << " camera(s)\n";
  std::cout << run.log;
  for (const CameraHealth& h : run.health) {
    EXPECT_EQ(h.state, CameraState::kNotJudged) << h.camera;
    EXPECT_EQ(h.frames, 0) << h.camera;
    EXPECT_NE(run.log.find("'" + h.camera + "'"), std::string::npos) << h.camera;
  }
  EXPECT_NE(run.log.find("its health cannot be judged"), std::string::npos);
  EXPECT_NE(run.log.find("mapper.time_offsets"), std::string::npos);
  EXPECT_NE(run.log.find("tracker.sync_tolerance_ms"), std::string::npos);
  bool published = false;
  for (const tracker_status_t& s : run.statuses)
    for (const camera_health_t& c : s.cameras)
      published = published || c.state == camera_health_t::STATE_NOT_JUDGED;
  EXPECT_TRUE(published);
}

// Multi-camera frames, every camera judged, none suspect.
void ExpectEveryCameraJudgedOk(const HealthRun& run) {
  ASSERT_EQ(run.health.size(), 4u);
  int multi = 0;
  for (const auto& [cameras, frames] : CamerasPerFrame(run)) {
    std::cout << "[ health ]   " << frames << " poses from " << cameras << " camera(s)\n";
    if (cameras >= 3) multi += frames;
  }
  std::vector<double> rms;
  for (const TrajectoryRow& r : run.poses) rms.push_back(r.rms_px);
  std::cout << "[ health ]   median pose rms " << Median(rms) << " px\n" << run.log;
  // The board is in cam1's view alone for the session's first 62 frames (10 s); from then on 43 of 53
  // poses come from 3-4 cameras.
  EXPECT_GE(multi, 40);
  EXPECT_EQ(run.log.find("cannot be judged"), std::string::npos);
  for (const CameraHealth& h : run.health) {
    EXPECT_EQ(h.state, CameraState::kOk) << h.camera;
    EXPECT_EQ(h.first_suspect_utime, -1) << h.camera;
    EXPECT_GT(h.frames, 30) << h.camera;
  }
}

// With the map's offsets and frames spanning the capture latencies (60 ms set by hand: cam1's views land
// 45 ms after cam0's, between two of its frames), each view sees the board moved to its capture time
// along its velocity: multi-camera frames, every camera judged, none suspect.
TEST(TrackerRealData, CameraTimesWithTheMapsOffsetsJudgeEveryCameraOk) {
  SKIP_WITHOUT_DATA();
  const RigConfig rig = LoadRigConfig(kRig);
  const HealthRun run = TrackCameraTimes(rig, MapWithOffsets(rig).map, 60.0);
  ExpectEveryCameraJudgedOk(run);
  EXPECT_EQ(run.log.find("sync window"), std::string::npos) << "a window set by hand is not chosen";
}

// The same with the default options: the map has clock offsets, so the tracker measures the cameras'
// phases over their first frames, finds them tens of ms apart at 6 fps (not triggered together) and
// chooses the window itself (half the frame interval, 83 ms), saying so once.
TEST(TrackerRealData, CameraTimesWithTheMapsOffsetsAtTheDefaultOptionsChooseTheWindow) {
  SKIP_WITHOUT_DATA();
  const RigConfig rig = LoadRigConfig(kRig);
  ASSERT_FALSE(TrackerOptions::FromConfig(rig).sync_tolerance_set) << kRig << " sets the tolerance";
  const HealthRun run = TrackCameraTimes(rig, MapWithOffsets(rig).map, -1.0);
  ExpectEveryCameraJudgedOk(run);
  const size_t said = run.log.find("mcmt-tracker: sync window ");
  ASSERT_NE(said, std::string::npos) << run.log;
  EXPECT_EQ(run.log.find("mcmt-tracker: sync window ", said + 1), std::string::npos) << "said more than once";
  EXPECT_NE(run.log.find("not triggered together"), std::string::npos) << run.log;
  const double window_ms = std::stod(run.log.substr(said + std::string("mcmt-tracker: sync window ").size()));
  EXPECT_GT(window_ms, 45.0);
  EXPECT_LE(window_ms, kMaxAutoSyncWindowMs);
}

}  // namespace
}  // namespace mcmt
