// Integration tests of the whole Mapper (initialisation + refinement) on the simulator's detections
// (tests/support/mapper_sim.h) with known ground truth: accuracy with distortion and differing intrinsics,
// a marker fixed in the room, false ids and dropped frames, cameras starting late, bad input. (The paper's
// objects at its radii and the camera subsets: test_mapper_sim.)
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>

#include "core/ippe.h"
#include "mapper/mapper.h"
#include "sim/eval.h"
#include "tests/support/mapper_sim.h"

namespace mcmt {
namespace {

using test::Filter;
using test::MapMessages;
using test::MapperOptionsFor;
using test::MapperSession;

constexpr int kRoomId = 77;

struct Scene {
  sim::Session session;
  sim::GroundTruth truth;
  std::vector<detections_t> messages;
  explicit Scene(const sim::SessionOptions& o)
      : session(sim::SimulateSession(o)), truth(session.Truth()), messages(session.Messages()) {}
  MapperOptions Options() const {
    MapperOptions options = MapperOptionsFor(truth);
    options.sync_tolerance_ms = 5.0;  // staggered cameras
    return options;
  }
  bool OnObject(int id) const { return truth.FindMarker(id) != nullptr; }
};

// Means over frames, the worst camera and the worst marker (mean of its corners), after rigid alignment.
void ExpectWithinIssueBounds(const sim::GroundTruth& truth, const MapResult& result,
                             const std::string& what) {
  const sim::EvalResult e = sim::Evaluate(truth, &result.map, &result.trajectory);
  EXPECT_EQ(e.mapped_cameras, static_cast<int>(result.map.cameras.size())) << what;
  EXPECT_EQ(e.mapped_markers, e.gt_markers) << what;
  EXPECT_LT(e.object_translation_aligned_mm.mean, 0.5) << what;
  EXPECT_LT(e.object_rotation_deg.mean, 0.3) << what;
  EXPECT_LT(e.camera_position_mm.max, 2.0) << what;
  EXPECT_LT(e.configuration_mm.max, 0.3) << what;
  EXPECT_GT(e.frames_with_pose, 0.8 * e.gt_frames) << what;
  // The refinement improved on the initialisation.
  EXPECT_LT(result.report.final_rms_px, result.report.initial_rms_px) << what;
  EXPECT_LT(result.report.final_rms_px, 0.3) << what;
}

TEST(MapperSynthetic, AccurateWithDistortionAndDifferingIntrinsics) {
  const std::vector<std::pair<sim::ObjectKind, DistortionModel>> cases = {
      {sim::ObjectKind::kFourSided, DistortionModel::kRadTan},
      {sim::ObjectKind::kPentagon, DistortionModel::kNone},
      {sim::ObjectKind::kBox, DistortionModel::kFisheye}};
  for (double radius : {0.7, 1.0, 1.3}) {
    for (size_t k = 0; k < cases.size(); ++k) {
      sim::SessionOptions o = MapperSession(150, 10 + k);
      o.rig.radius = radius;
      o.object.kind = cases[k].first;
      o.object.marker_size = cases[k].first == sim::ObjectKind::kPentagon ? 0.025 : 0.04;
      o.rig.distortion = cases[k].second;
      const Scene scene(o);
      const MapResult result = MapMessages(scene.messages, scene.Options());
      const std::string what =
          "radius " + std::to_string(radius) + " " + sim::ObjectKindNames()[static_cast<int>(cases[k].first)];
      EXPECT_EQ(result.map.cameras.size(), 5u) << what;
      EXPECT_TRUE(result.report.rejected_markers.empty()) << what;
      ExpectWithinIssueBounds(scene.truth, result, what);
    }
  }
}

TEST(MapperSynthetic, FalseDetectionsAndDroppedFramesAreHandled) {
  sim::SessionOptions o = MapperSession(200, 31);
  o.detections.false_rate = 0.1;  // 0.1 false detections per camera frame
  o.detections.drop_rate = 0.05;  // 5 % of camera frames are dropped
  o.extra_bodies = {test::RoomMarker(kRoomId, 0.04, sim::MakeTrajectory(o.trajectory))};  // not on the object
  o.camera_stagger_us = 700;  // cameras not exactly simultaneous
  const Scene scene(o);
  int false_detections = 0, room_detections = 0;
  for (const detections_t& d : scene.messages)
    for (const marker_t& m : d.markers) {
      false_detections += !scene.OnObject(m.id) && m.id != kRoomId;
      room_detections += m.id == kRoomId;
    }
  ASSERT_GT(false_detections, 50);
  ASSERT_GT(room_detections, 100);
  const MapResult result = MapMessages(scene.messages, scene.Options());
  ExpectWithinIssueBounds(scene.truth, result, "false + dropped");
  // No false id in the map; the room's marker is reported as not rigidly attached.
  for (const MapMarker& m : result.map.markers) EXPECT_TRUE(scene.OnObject(m.id)) << "false id " << m.id;
  bool room_reported = false;
  for (const RejectedMarker& r : result.report.rejected_markers) {
    EXPECT_FALSE(scene.OnObject(r.id)) << "true marker " << r.id << " rejected: " << r.reason;
    if (r.id == kRoomId) {
      room_reported = true;
      EXPECT_NE(r.reason.find("not rigidly attached"), std::string::npos) << r.reason;
    }
  }
  EXPECT_TRUE(room_reported);
  const std::string json = ReportJson(result);
  EXPECT_NE(json.find("\"id\": 77"), std::string::npos);
}

TEST(MapperSynthetic, CamerasStartingLateAndStoppingEarly) {
  sim::SessionOptions o = MapperSession(200, 33);
  o.camera_stagger_us = 900;
  const Scene scene(o);
  const std::vector<detections_t> kept = Filter(scene.messages, [](const detections_t& d) {
    return !(d.camera == "cam3" && d.seq < 80) &&  // starts late
           !(d.camera == "cam4" && d.seq >= 90);   // stops early
  });
  const MapResult result = MapMessages(kept, scene.Options());
  ExpectWithinIssueBounds(scene.truth, result, "late start / early stop");
  EXPECT_EQ(result.report.frames_assembled, 200);  // staggered utimes still join their frames
}

TEST(MapperSynthetic, WhitelistIgnoresOtherIds) {
  sim::SessionOptions o = MapperSession(80, 1);
  o.extra_bodies = {test::RoomMarker(kRoomId, 0.04, sim::MakeTrajectory(o.trajectory))};
  const Scene scene(o);
  MapperOptions options = scene.Options();
  for (const sim::SimMarker& m : scene.truth.markers) options.marker_ids.push_back(m.id);
  const MapResult result = MapMessages(scene.messages, options);
  EXPECT_GT(result.report.ignored_ids, 0);
  EXPECT_TRUE(result.report.rejected_markers.empty());
  EXPECT_EQ(result.map.markers.size(), scene.truth.markers.size());
}

// Issue 15 (reference renderer, 1.3 m, half-cell margin, black tool): markers 0 and 3 of the four-sided
// object were rejected (their poses seen with 1 and 2 disagreed), 1 and 2 were placed from a wrong pair of
// square poses, and the mapper published a map 936 mm off without a word. Here markers 0 and 3 disagree
// with 1 and 2 (their corners turned by seq % 4 quarter turns) and hold most of the observations: the
// mapper says which markers and maps nothing, or maps without them with a warning under --allow-partial.
TEST(MapperSynthetic, DeclaredMarkersThatMostlyDisagreeAreAnError) {
  sim::SessionOptions o = MapperSession(150, 41);
  o.object.kind = sim::ObjectKind::kFourSided;
  const Scene scene(o);
  std::vector<detections_t> messages = scene.messages;
  for (detections_t& d : messages) {
    std::vector<marker_t> kept;
    for (marker_t m : d.markers) {
      if (m.id == 0 || m.id == 3) {
        const marker_t turned = m;
        for (int k = 0; k < 4; ++k)
          for (int x = 0; x < 2; ++x) m.corners[k][x] = turned.corners[(k + d.seq) % 4][x];
      } else if (d.seq % 3 != 0)
        continue;  // 1 and 2 in a third of the frames
      kept.push_back(m);
    }
    d.markers = kept;
    d.num_markers = static_cast<int32_t>(kept.size());
  }
  MapperOptions options = scene.Options();
  options.marker_ids = {0, 1, 2, 3};
  try {
    MapMessages(messages, options);
    ADD_FAILURE() << "a map on markers 1 and 2 alone, without an error";
  } catch (const MapperError& e) {
    EXPECT_NE(std::string(e.what()).find("markers 0, 3 of markers.ids cannot be placed"), std::string::npos)
        << e.what();
  }
  options.allow_partial = true;
  const MapResult result = MapMessages(messages, options);
  ASSERT_FALSE(result.report.warnings.empty());
  EXPECT_NE(result.report.warnings.back().find("markers 0, 3"), std::string::npos)
      << result.report.warnings.back();
  // Without the whitelist the ids are not declared: rejected and reported as before.
  options.allow_partial = false;
  options.marker_ids.clear();
  EXPECT_NO_THROW(MapMessages(messages, options));
}

// Issue 15 (reference renderer, 1.3 m, black tool): neighbouring faces are seen together by one camera
// rarely and only at grazing angles, where one square's pose (IPPE) flipped the same way in 5 of their 6
// shared frames: the mapper placed them 37 deg apart instead of 90 and published a map 936 mm off. Here a
// camera frame sees two markers in one frame of five (the higher id is dropped in the others), and there
// the higher id's corners are those of a wrong pose, the only one kept: `wrong` gives it from the true
// cam_from_marker and the pose of the square IPPE finds in the true corners. The cameras' views of single
// markers are right and outvote it.
using WrongPose = std::function<Rigid3(const Rigid3& cam_from_marker, const SquarePose& square)>;

// Marker m of detection d shown in the pose `wrong` gives from its true cam_from_marker and the pose of the
// square IPPE finds in its true corners: its corners replaced by that pose's projection.
void ShowInWrongPose(const Scene& scene, const detections_t& d, const WrongPose& wrong, marker_t* m) {
  const sim::SimCamera& camera = *scene.truth.FindCamera(d.camera);
  const sim::SimMarker& marker = *scene.truth.FindMarker(m->id);
  const Rigid3 cam_from_marker =
      camera.rig_from_cam.inverse() * scene.truth.frames[d.seq].rig_from_object * marker.object_from_marker;
  MarkerCorners2d corners;
  for (int k = 0; k < 4; ++k) corners[k] = Eigen::Vector2d(m->corners[k][0], m->corners[k][1]);
  const Rigid3 shown = wrong(cam_from_marker, EstimateSquarePose(camera.model, corners, marker.size));
  const MarkerCorners3d square = MarkerCornersInMarker(marker.size);
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector2d p = camera.model.Project(shown * square[k]);
    m->corners[k][0] = p.x();
    m->corners[k][1] = p.y();
  }
}

// The other IPPE pose of the square (its normal mirrored about the line of sight).
Rigid3 OtherSquarePose(const Rigid3& cam_from_marker, const SquarePose& square) {
  const Rigid3& a = square.hypotheses[0].cam_from_marker;
  return RotationAngle(a, cam_from_marker) <
                 RotationAngle(square.hypotheses[1].cam_from_marker, cam_from_marker)
             ? square.hypotheses[1].cam_from_marker
             : a;
}

MapResult ExpectNeighboursSeenTogetherOutvoted(const WrongPose& wrong, const std::string& what,
                                               bool refined_too) {
  sim::SessionOptions o = MapperSession(150, 43);
  o.object.kind = sim::ObjectKind::kFourSided;
  const Scene scene(o);
  std::vector<detections_t> messages = scene.messages;
  int wrong_poses = 0;
  for (detections_t& d : messages) {
    if (d.markers.size() < 2) continue;
    const auto higher = std::max_element(d.markers.begin(), d.markers.end(),
                                         [](const marker_t& x, const marker_t& y) { return x.id < y.id; });
    if (d.seq % 5 != 0) {
      d.markers.erase(higher);
      d.num_markers = static_cast<int32_t>(d.markers.size());
      continue;
    }
    ShowInWrongPose(scene, d, wrong, &*higher);
    ++wrong_poses;
  }
  EXPECT_GT(wrong_poses, 50) << what;
  const MapResult result = MapMessages(messages, scene.Options());
  // The graphs' layout: every marker, none turned (a wrong relative pose moves corners by 20-40 mm; the
  // cameras' views place a marker to a few mm).
  const sim::EvalResult initial = sim::Evaluate(scene.truth, &result.initial_map, &result.initial_trajectory);
  EXPECT_EQ(initial.mapped_markers, initial.gt_markers) << what;
  EXPECT_LT(initial.configuration_mm.max, 10.0) << what;
  if (!refined_too) return result;
  const sim::EvalResult e = sim::Evaluate(scene.truth, &result.map, &result.trajectory);
  EXPECT_LT(e.camera_position_mm.max, 3.0) << what;
  EXPECT_LT(e.configuration_mm.max, 0.5) << what;
  return result;
}

TEST(MapperSynthetic, NeighboursSeenTogetherInWrongSquarePosesAreOutvoted) {
  ExpectNeighboursSeenTogetherOutvoted(OtherSquarePose, "flipped square poses", true);
}

TEST(MapperSynthetic, NeighboursSeenTogetherInOneWrongRelativePoseAreOutvoted) {
  // The same wrong pose in every shared frame: turned 50 deg about its horizontal axis, so that the pair's
  // relative pose seen by one camera agrees with itself (a verified but wrong edge of the marker graph).
  // Its corners are far from the true ones, unlike a flipped square's: the graphs' layout is what is
  // tested (the refinement's handling of 12 % gross observations is another matter).
  const MapResult result = ExpectNeighboursSeenTogetherOutvoted(
      [](const Rigid3& cam_from_marker, const SquarePose&) {
        return cam_from_marker * Rigid3(Eigen::AngleAxisd(50.0 * M_PI / 180.0, Eigen::Vector3d::UnitX()));
      },
      "turned 50 deg in every shared frame", false);
  // Said, with the pair.
  ASSERT_FALSE(result.report.warnings.empty());
  EXPECT_NE(result.report.warnings[0].find("contradicted by the views of several cameras"), std::string::npos)
      << result.report.warnings[0];
}

// AMapNoCameraSupportsIsAnError with `options`: the flipped views are an error (a warning under
// --allow-partial), the true ones map.
void ExpectUnsupportedMapRefused(const Scene& scene, const std::vector<detections_t>& pair,
                                 const std::vector<detections_t>& flipped, MapperOptions options) {
  try {
    const MapResult result = MapMessages(flipped, options);
    const sim::EvalResult e = sim::Evaluate(scene.truth, &result.map, &result.trajectory);
    ADD_FAILURE() << "a map " << e.camera_position_mm.max << " mm off without an error";
  } catch (const MapperError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("no camera supports the map"), std::string::npos) << what;
    for (const char* camera : {"cam0 ", "cam1 ", "cam2 ", "cam3 ", "cam4 "})
      EXPECT_NE(what.find(camera), std::string::npos) << what;
    EXPECT_NE(what.find("--allow-partial"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << "one line: " << what;
  }
  options.allow_partial = true;
  const MapResult result = MapMessages(flipped, options);
  const sim::EvalResult e = sim::Evaluate(scene.truth, &result.map, &result.trajectory);
  EXPECT_GT(e.camera_position_mm.max, 50.0);  // wrong indeed
  ASSERT_FALSE(result.report.warnings.empty());
  EXPECT_NE(result.report.warnings.back().find("no camera supports the map"), std::string::npos)
      << result.report.warnings.back();
  // The same markers in their true views: mapped, without that warning (with time offsets the clocks'
  // own, synchronised here: "the first pass's frames are kept").
  options.allow_partial = false;
  const MapResult good = MapMessages(pair, options);
  for (const std::string& w : good.report.warnings)
    EXPECT_EQ(w.find("no camera supports the map"), std::string::npos) << w;
  EXPECT_EQ(good.report.warnings.size(), options.estimate_time_offsets ? 1u : 0u);
  EXPECT_LT(sim::Evaluate(scene.truth, &good.map, &good.trajectory).camera_position_mm.max, 2.0);
}

// Issue 15 (reference renderer, 1.3 m, black tool, on 3141d2b): neighbouring markers were placed from a
// wrong pair of square poses and the bundle settled in a wrong minimum (scale -64 %) with every camera's RMS
// 3.6-4.6x its predicted; the map came out without a word. Here the object is two neighbouring markers (1
// and 2 of the four-sided object) shown in every view in the square's other IPPE pose: the map comes out
// far off with every camera at 5.9-7.5x its predicted RMS and 12-17 % of its markers' side (good maps,
// real ones too, keep a camera under 2.7x or 2.4 %: bench/results/2026-12-05-plausible.md). The mapper says
// so and maps nothing, or maps with the warning under --allow-partial; the true views map.
TEST(MapperSynthetic, AMapNoCameraSupportsIsAnError) {
  sim::SessionOptions o = MapperSession(150, 41);
  o.object.kind = sim::ObjectKind::kFourSided;
  const Scene scene(o);
  std::vector<detections_t> pair = scene.messages;  // markers 1 and 2 only
  for (detections_t& d : pair) {
    std::vector<marker_t> kept;
    for (const marker_t& m : d.markers)
      if (m.id == 1 || m.id == 2) kept.push_back(m);
    d.markers = kept;
    d.num_markers = static_cast<int32_t>(kept.size());
  }
  std::vector<detections_t> flipped = pair;
  for (detections_t& d : flipped)
    for (marker_t& m : d.markers) ShowInWrongPose(scene, d, OtherSquarePose, &m);
  // With mapper.time_offsets too (the diagnostics then move the poses along the bundle's velocities;
  // before, the check skipped time offsets and the wrong map came out without a word).
  for (const bool time_offsets : {false, true}) {
    SCOPED_TRACE(time_offsets ? "time offsets" : "synchronised clocks");
    MapperOptions options = scene.Options();
    options.estimate_time_offsets = time_offsets;
    ExpectUnsupportedMapRefused(scene, pair, flipped, options);
  }
}

TEST(MapperSynthetic, DuplicateIdsInOneFrameAreDroppedAndReported) {
  Scene scene(MapperSession(80, 1));
  int added = 0;
  for (auto& d : scene.messages)
    if (!d.markers.empty() && added < 5) {
      marker_t copy = d.markers[0];
      for (auto& c : copy.corners) c[0] += 100;
      d.markers.push_back(copy);
      d.num_markers = static_cast<int32_t>(d.markers.size());
      ++added;
    }
  const MapResult result = MapMessages(scene.messages, scene.Options());
  EXPECT_EQ(result.report.duplicates, 2 * added);
  EXPECT_EQ(result.report.duplicate_examples.size(), static_cast<size_t>(added));
  ExpectWithinIssueBounds(scene.truth, result, "duplicates");
}

// ---------------------------------------------------------------------------------------------
// Bad input

TEST(MapperSynthetic, NoDetectionsIsAClearError) {
  const Scene scene(MapperSession(5, 1));
  Mapper mapper(scene.Options());
  try {
    mapper.Solve();
    FAIL() << "expected an error";
  } catch (const MapperError& e) {
    EXPECT_NE(std::string(e.what()).find("no detections"), std::string::npos) << e.what();
  }
}

TEST(MapperSynthetic, OneCameraOnlyNamesTheSilentCameras) {
  const Scene scene(MapperSession(60, 1));
  const std::vector<detections_t> cam0 =
      Filter(scene.messages, [](const detections_t& d) { return d.camera == "cam0"; });
  try {
    MapMessages(cam0, scene.Options());
    FAIL() << "expected an error";
  } catch (const MapperError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("sent no detections"), std::string::npos) << what;
    EXPECT_NE(what.find("cam1"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << "one line: " << what;
  }
  // --allow-partial maps the one camera (markers and object poses still come out).
  MapperOptions options = scene.Options();
  options.allow_partial = true;
  const MapResult result = MapMessages(cam0, options);
  EXPECT_EQ(result.map.cameras.size(), 1u);
  EXPECT_EQ(result.report.dropped_cameras.size(), 4u);
}

TEST(MapperSynthetic, DisconnectedCameraIsNamedWithWhatWouldConnectIt) {
  const Scene scene(MapperSession(120, 1));
  // cam2 only reports frames where no other camera reports: it never shares a frame with them.
  const std::vector<detections_t> split =
      Filter(scene.messages, [](const detections_t& d) { return (d.camera == "cam2") != (d.seq % 2 == 0); });
  try {
    MapMessages(split, scene.Options());
    FAIL() << "expected an error";
  } catch (const MapperError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("camera 'cam2' cannot be placed"), std::string::npos) << what;
    EXPECT_NE(what.find("record frames where 'cam2' and one of those cameras see the object"),
              std::string::npos)
        << what;
    EXPECT_NE(what.find("--allow-partial"), std::string::npos) << what;
  }
  MapperOptions options = scene.Options();
  options.allow_partial = true;
  const MapResult result = MapMessages(split, options);
  EXPECT_EQ(result.map.cameras.size(), 4u);
  EXPECT_EQ(result.map.FindCamera("cam2"), nullptr);
  ASSERT_EQ(result.report.dropped_cameras.size(), 1u);
  EXPECT_EQ(result.report.dropped_cameras[0], "cam2");
  const sim::EvalResult e = sim::Evaluate(scene.truth, &result.map, &result.trajectory);
  EXPECT_LT(e.camera_position_mm.max, 2.0);
}

TEST(MapperSynthetic, UnknownCameraIsIgnoredWithAWarning) {
  const Scene scene(MapperSession(60, 1));
  MapperOptions options = scene.Options();
  options.cameras.pop_back();  // cam4 not in the rig
  const MapResult result = MapMessages(scene.messages, options);
  EXPECT_EQ(result.map.cameras.size(), 4u);
  ASSERT_FALSE(result.report.warnings.empty());
  EXPECT_NE(result.report.warnings[0].find("cam4"), std::string::npos);
}

}  // namespace
}  // namespace mcmt
