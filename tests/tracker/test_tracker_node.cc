// TrackerNode fed with encoded messages (no network): frame assembly, a camera that stops, false
// markers, garbage, unknown cameras, maps from MCMT_MAP, one pose per frame in order.
#include <gtest/gtest.h>

#include <lcm/lcm-cpp.hpp>
#include <limits>
#include <regex>

#include "core/lcm_util.h"
#include "tests/support/temp_dir.h"
#include "tests/support/tracker_sim.h"
#include "tracker/tracker.h"

namespace mcmt {
namespace {

// Collects the poses a node publishes (memq: same process).
class PoseSink {
 public:
  explicit PoseSink(lcm::LCM& lcm, const std::string& channel = kPoseChannel) : lcm_(lcm) {
    lcm_.subscribe(channel, &PoseSink::Handle, this)->setQueueCapacity(100000);
  }
  void Drain() {
    while (lcm_.handleTimeout(0) > 0) {
    }
  }
  std::vector<object_pose_t> poses;

 private:
  void Handle(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    poses.push_back(DecodeOrThrow<object_pose_t>(rbuf->data, rbuf->data_size));
  }
  lcm::LCM& lcm_;
};

// The simulator's session (tests/support/tracker_sim.h: 5 cameras, the cube, 150 frames) and its rig file.
struct Fixture {
  test::TrackerSim sim = test::SimulateTracking(test::TrackerSession());
  const sim::Session& session = sim.session;
  const RigMap& map = sim.map;
  test::TempDir dir{"tracker_node"};
  RigConfig rig = LoadRigConfig(sim::WriteSessionRig(dir.str(), session));
  Rigid3 Truth(size_t f) const { return sim.truth.at(f).rig_from_object; }
};

TrackerNodeOptions LogModeOptions() {
  TrackerNodeOptions o;
  o.log_mode = true;
  o.keep_trajectory = true;
  o.quiet = true;
  return o;
}

void Feed(TrackerNode& node, const detections_t& d) {
  const auto bytes = Encode(d);
  node.OnDetections(DetectionsChannel(d.camera), bytes.data(), bytes.size());
}

TEST(TrackerNode, OnePosePerFrameInOrderAndAccurate) {
  Fixture fx;
  lcm::LCM in("memq://"), out("memq://");
  ASSERT_TRUE(in.good() && out.good());
  PoseSink sink(out);
  TrackerNode node(in, fx.rig, LogModeOptions(), fx.map, &out);
  for (const auto& frame : fx.session.views)
    for (const auto& d : frame) Feed(node, d);
  node.Flush();
  sink.Drain();
  ASSERT_EQ(sink.poses.size(), fx.session.views.size());
  for (size_t f = 0; f < sink.poses.size(); ++f) {
    const object_pose_t& p = sink.poses[f];
    EXPECT_EQ(p.seq, static_cast<int64_t>(f));
    EXPECT_EQ(p.utime, fx.sim.truth[f].utime);
    EXPECT_EQ(p.status, object_pose_t::STATUS_TRACKING);
    EXPECT_EQ(p.object, "object");
    EXPECT_EQ(p.num_rejected, 0);
    EXPECT_GE(p.latency_ms, 0.0);
    EXPECT_LT(TranslationDistance(FromPose3d(p.rig_from_object), fx.Truth(f)), 2e-3);
    for (int a = 0; a < 6; ++a) EXPECT_GT(p.covariance[a][a], 0.0);
  }
  // Every frame was complete: all five cameras used somewhere.
  size_t max_cams = 0;
  for (const auto& p : sink.poses) max_cams = std::max(max_cams, p.cameras.size());
  EXPECT_EQ(max_cams, 5u);
  // The first frame waited for every camera of the map (not closed by the first camera's message).
  std::set<std::string> first_frame_cams;
  for (const auto& d : fx.session.views[0])
    if (!d.markers.empty()) first_frame_cams.insert(d.camera);
  EXPECT_EQ(sink.poses[0].cameras.size(), first_frame_cams.size());
  EXPECT_EQ(node.trajectory().size(), fx.session.views.size());
}

TEST(TrackerNode, CameraKilledMidRunTheOthersCarryOn) {
  Fixture fx;
  lcm::LCM in("memq://");
  TrackerNode node(in, fx.rig, LogModeOptions(), fx.map);
  const int killed = 2, kill_from = 40;
  for (size_t f = 0; f < fx.session.views.size(); ++f)
    for (const auto& d : fx.session.views[f])
      if (!(d.camera == "cam2" && static_cast<int>(f) >= kill_from)) Feed(node, d);
  node.Flush();
  (void)killed;
  const auto& traj = node.trajectory();
  ASSERT_EQ(traj.size(), fx.session.views.size());  // no frame lost
  double mean_t = 0;
  for (size_t f = 0; f < traj.size(); ++f) {
    EXPECT_EQ(traj[f].seq, static_cast<int64_t>(f));
    mean_t += TranslationDistance(traj[f].rig_from_object, fx.Truth(f));
    if (static_cast<int>(f) >= kill_from) {
      EXPECT_LE(traj[f].cameras, 4);
    }
  }
  EXPECT_LT(mean_t / traj.size(), 0.5e-3);
  // 150 frames at 30 fps = 5 s; the camera is silent for 3.7 s > 1 s timeout: reported stale.
  EXPECT_NE(node.StatusLine().find("stale cameras: cam2"), std::string::npos) << node.StatusLine();
}

TEST(TrackerNode, GarbageUnknownCameraDuplicatesAreIgnored) {
  Fixture fx;
  lcm::LCM in("memq://");
  TrackerNode node(in, fx.rig, LogModeOptions(), fx.map);
  testing::internal::CaptureStderr();
  const std::vector<uint8_t> garbage = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13};
  for (size_t f = 0; f < fx.session.views.size(); ++f) {
    node.OnDetections("MCMT_DETECTIONS_CAM0", garbage.data(), garbage.size());
    node.OnDetections("MCMT_DETECTIONS_CAM0", garbage.data(), 0);
    for (auto d : fx.session.views[f]) {
      if (d.camera == "cam4") d.camera_model.fx += 5.0;  // a detector with other intrinsics
      Feed(node, d);
      Feed(node, d);  // duplicate
    }
    detections_t stranger = fx.session.views[f][0];
    stranger.camera = "cam9";
    Feed(node, stranger);
  }
  node.Flush();
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(node.trajectory().size(), fx.session.views.size());
  EXPECT_EQ(node.stats().bad_messages, 2 * static_cast<int64_t>(fx.session.views.size()));
  EXPECT_EQ(node.stats().unknown_camera, static_cast<int64_t>(fx.session.views.size()));
  // Warned once per channel / camera, not once per message.
  auto count = [&](const std::string& needle) {
    size_t n = 0;
    for (size_t p = err.find(needle); p != std::string::npos; p = err.find(needle, p + 1)) ++n;
    return n;
  };
  EXPECT_EQ(count("undecodable message on MCMT_DETECTIONS_CAM0"), 1u) << err;
  EXPECT_EQ(count("camera 'cam9'"), 1u) << err;
  EXPECT_EQ(count("camera 'cam4': the detections' intrinsics differ"), 1u) << err;
}

// A camera whose messages always come after the next frame's: its views miss the deadline, are
// dropped, counted and warned about once; every frame is still posed from the others.
TEST(TrackerNode, LaggingCameraViewsAreDroppedAndReported) {
  Fixture fx;
  lcm::LCM in("memq://");
  TrackerNode node(in, fx.rig, LogModeOptions(), fx.map);
  testing::internal::CaptureStderr();
  const auto& views = fx.session.views;
  for (size_t f = 0; f < views.size(); ++f) {
    for (const auto& d : views[f])
      if (d.camera != "cam4") Feed(node, d);
    if (f > 0) Feed(node, views[f - 1][4]);  // cam4's view of the previous frame, 33 ms late
  }
  node.Flush();
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(node.trajectory().size(), views.size());
  EXPECT_GE(node.stats().late_views, static_cast<int64_t>(views.size()) - 3);
  EXPECT_NE(err.find("views of camera 'cam4' arrive after their frame was solved (deadline 15 ms,"),
            std::string::npos)
      << err;
  EXPECT_NE(node.StatusLine().find("late views dropped: cam4"), std::string::npos) << node.StatusLine();
}

TEST(TrackerNode, FalseMarkerDoesNotMoveThePose) {
  Fixture fx;
  lcm::LCM in1("memq://"), in2("memq://");
  TrackerNode clean(in1, fx.rig, LogModeOptions(), fx.map);
  TrackerNode dirty(in2, fx.rig, LogModeOptions(), fx.map);
  for (size_t f = 0; f < fx.session.views.size(); ++f) {
    for (const auto& d : fx.session.views[f]) {
      Feed(clean, d);
      detections_t bad = d;
      if (d.camera == "cam1" && !d.markers.empty()) {
        marker_t fake = d.markers[0];
        fake.id = fake.id ^ 1;  // the opposite face's id (sim's cube: +x -x +y -y +z -z), placed elsewhere
        for (auto& c : fake.corners) c[1] += 4.0;
        bad.markers.push_back(fake);
        bad.num_markers++;
      }
      Feed(dirty, bad);
    }
  }
  clean.Flush();
  dirty.Flush();
  ASSERT_EQ(clean.trajectory().size(), dirty.trajectory().size());
  for (size_t f = 0; f < clean.trajectory().size(); ++f) {
    EXPECT_LT(
        TranslationDistance(clean.trajectory()[f].rig_from_object, dirty.trajectory()[f].rig_from_object),
        1e-7);
    EXPECT_LT(RotationAngle(clean.trajectory()[f].rig_from_object, dirty.trajectory()[f].rig_from_object),
              1e-7);
  }
  EXPECT_GT(dirty.stats().rejected, 50);
  EXPECT_EQ(clean.stats().rejected, 0);
}

TEST(TrackerNode, MapOfAnotherRigIsRefused) {
  Fixture fx;
  RigMap other = fx.map;
  other.cameras[3].name = "left_camera";
  lcm::LCM in("memq://");
  try {
    TrackerNode node(in, fx.rig, LogModeOptions(), other);
    FAIL() << "must throw";
  } catch (const std::exception& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("left_camera"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

TEST(TrackerNode, WaitsForMapMessageAndSwitchesToNewerMaps) {
  Fixture fx;
  lcm::LCM in("memq://");
  TrackerNodeOptions o = LogModeOptions();
  testing::internal::CaptureStderr();
  TrackerNode node(in, fx.rig, o, std::nullopt);
  EXPECT_FALSE(node.has_map());
  const auto& views = fx.session.views;
  for (int f = 0; f < 10; ++f)
    for (const auto& d : views[f]) Feed(node, d);
  EXPECT_EQ(node.trajectory().size(), 0u);
  EXPECT_GT(node.stats().no_map, 0);
  // A map of another rig on MCMT_MAP: ignored with a warning, still waiting.
  RigMap foreign = fx.map;
  foreign.cameras[0].name = "zzz";
  auto foreign_bytes = Encode(ToRigMapMsg(foreign, 5));
  node.OnMap(foreign_bytes.data(), foreign_bytes.size());
  EXPECT_FALSE(node.has_map());
  const std::vector<uint8_t> garbage(40, 0xab);
  node.OnMap(garbage.data(), garbage.size());
  EXPECT_FALSE(node.has_map());
  // The right map.
  auto bytes = Encode(ToRigMapMsg(fx.map, 10));
  node.OnMap(bytes.data(), bytes.size());
  ASSERT_TRUE(node.has_map());
  for (int f = 10; f < 60; ++f)
    for (const auto& d : views[f]) Feed(node, d);
  // Same map again: no switch. Newer map: switch.
  node.OnMap(bytes.data(), bytes.size());
  EXPECT_EQ(node.stats().map_switches, 0);
  auto newer = Encode(ToRigMapMsg(fx.map, 11));
  node.OnMap(newer.data(), newer.size());
  EXPECT_EQ(node.stats().map_switches, 1);
  for (size_t f = 60; f < views.size(); ++f)
    for (const auto& d : views[f]) Feed(node, d);
  node.Flush();
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("zzz"), std::string::npos) << err;
  EXPECT_NE(err.find("switched to a newer map"), std::string::npos) << err;
  // Every frame after the first map got a pose (frame 10 may have been assembled before it).
  EXPECT_GE(node.trajectory().size(), views.size() - 11);
  for (const auto& row : node.trajectory()) {
    EXPECT_GE(row.seq, 10);
    EXPECT_LT(TranslationDistance(row.rig_from_object, fx.Truth(row.seq)), 2e-3);
  }
}

TEST(TrackerNode, LostWhenNoMappedMarkerIsSeenThenRecovers) {
  Fixture fx;
  lcm::LCM in("memq://"), out("memq://");
  PoseSink sink(out);
  TrackerNode node(in, fx.rig, LogModeOptions(), fx.map, &out);
  for (size_t f = 0; f < 40; ++f) {
    for (auto d : fx.session.views[f]) {
      if (f >= 10 && f < 20) {  // the object leaves every view
        d.markers.clear();
        d.num_markers = 0;
      }
      Feed(node, d);
    }
  }
  node.Flush();
  sink.Drain();
  ASSERT_EQ(sink.poses.size(), 40u);
  for (size_t f = 0; f < 40; ++f) {
    const bool gone = f >= 10 && f < 20;
    EXPECT_EQ(sink.poses[f].status, gone ? object_pose_t::STATUS_LOST : object_pose_t::STATUS_TRACKING) << f;
    if (!gone) {
      EXPECT_LT(TranslationDistance(FromPose3d(sink.poses[f].rig_from_object), fx.Truth(f)), 2e-3);
    }
  }
  EXPECT_EQ(node.stats().lost, 10);
}

// Issue 14: invalid content gets one line naming camera and channel, and is counted; the valid views of
// the same frames are still used.
TEST(TrackerNode, InvalidContentIsDroppedWithAReasonNamingTheCamera) {
  Fixture fx;
  lcm::LCM in("memq://");
  TrackerNode node(in, fx.rig, LogModeOptions(), fx.map);
  testing::internal::CaptureStderr();
  const auto& views = fx.session.views;
  int nan_markers = 0;
  for (size_t f = 0; f < views.size(); ++f)
    for (detections_t d : views[f]) {
      if (d.camera == "cam1") {  // its camera field says cam3: refused on CAM1's channel
        d.camera = "cam3";
        const std::vector<uint8_t> bytes = Encode(d);
        node.OnDetections("MCMT_DETECTIONS_CAM1", bytes.data(), bytes.size());
        continue;
      }
      if (d.camera == "cam2") d.camera_model.width = -640;
      if (d.camera == "cam0" && !d.markers.empty()) {
        d.markers[0].corners[0][0] = std::numeric_limits<double>::infinity();
        ++nan_markers;
      }
      Feed(node, d);
    }
  node.Flush();
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(node.trajectory().size(), views.size());
  EXPECT_EQ(node.stats().invalid, 2 * static_cast<int64_t>(views.size()));
  EXPECT_EQ(node.stats().invalid_markers, nan_markers);
  for (const char* line :
       {"camera 'cam3' on MCMT_DETECTIONS_CAM1: the message's camera field belongs on MCMT_DETECTIONS_CAM3",
        "camera 'cam2' on MCMT_DETECTIONS_CAM2: invalid camera model in the message: image size must be "
        "positive, got -640x",
        "camera 'cam0' on MCMT_DETECTIONS_CAM0: marker "})
    EXPECT_NE(err.find(line), std::string::npos) << line << "\n" << err;
  EXPECT_NE(node.StatusLine().find("invalid messages dropped"), std::string::npos) << node.StatusLine();
}

}  // namespace
}  // namespace mcmt

namespace mcmt {
namespace {

// "tracked 100.0 %" was the last status interval's figure, shown beside the totals as if it were theirs:
// the line now says which is which and gives the total's percentage too.
TEST(TrackerNode, StatusLineLabelsTheIntervalAndTheTotalTrackedShares) {
  Fixture fx;
  lcm::LCM in("memq://");
  TrackerNode node(in, fx.rig, LogModeOptions(), fx.map);
  const size_t lost_from = fx.session.views.size() * 2 / 3;
  for (size_t f = 0; f < fx.session.views.size(); ++f)
    for (detections_t d : fx.session.views[f]) {
      if (f >= lost_from) {  // the object out of view: frames without markers
        d.markers.clear();
        d.num_markers = 0;
      }
      Feed(node, d);
    }
  node.Flush();
  const std::string line = node.StatusLine();
  std::smatch m;
  ASSERT_TRUE(
      std::regex_search(line, m,
                        std::regex(R"(tracked ([0-9.]+) % of the last ([0-9]+) frames.*\(total: ([0-9]+) )"
                                   R"(frames, ([0-9]+) tracked = ([0-9.]+) %)")))
      << line;
  const double total_frames = std::stod(m[3]), tracked = std::stod(m[4]);
  EXPECT_NEAR(std::stod(m[5]), 100.0 * tracked / total_frames, 0.05) << line;
  EXPECT_LT(std::stod(m[5]), 70.0) << line;  // a third of the frames had no markers
}

}  // namespace
}  // namespace mcmt
