// Integration tests of the whole Mapper (initialisation + refinement) on synthetic detections with
// known ground truth: accuracy, camera subsets, false ids and dropped frames, bad input.
#include <gtest/gtest.h>

#include <algorithm>

#include "mapper/mapper.h"
#include "tests/mapper/synth.h"

namespace mcmt {
namespace {

MapResult MapScene(const testing::SynthScene& scene, MapperOptions options) {
  Mapper mapper(options);
  for (const auto& d : scene.detections) mapper.Add(d);
  return mapper.Solve();
}

MapResult MapScene(const testing::SynthScene& scene) {
  return MapScene(scene, testing::SceneMapperOptions(scene));
}

void ExpectWithinIssueBounds(const testing::SynthScene& scene, const MapResult& result,
                             const std::string& what) {
  const testing::MapErrors e = testing::CompareToTruth(scene, result.map, result.trajectory);
  EXPECT_EQ(e.cameras_compared, static_cast<int>(scene.names.size())) << what;
  EXPECT_EQ(e.markers_compared, static_cast<int>(scene.ids.size())) << what;
  EXPECT_LT(e.object_translation_m, 0.0005) << what;
  EXPECT_LT(e.object_rotation_deg, 0.3) << what;
  EXPECT_LT(e.camera_position_m, 0.002) << what;
  EXPECT_LT(e.configuration_m, 0.0003) << what;
  EXPECT_GT(e.frames_compared, static_cast<int>(0.8 * scene.utimes.size())) << what;
  // The refinement improved on the initialisation.
  EXPECT_LT(result.report.final_rms_px, result.report.initial_rms_px) << what;
  EXPECT_LT(result.report.final_rms_px, 0.3) << what;
}

TEST(MapperSynthetic, AccurateAtThePapersRadiiAndObjects) {
  for (double radius : {0.7, 1.0, 1.3}) {
    for (int object = 0; object < 3; ++object) {
      testing::SynthOptions so;
      so.radius = radius;
      so.frames = 150;
      so.seed = 10 + object;
      if (object == 1) {  // pentagon with two small markers per side
        so.sides = 5;
        so.markers_per_side = 2;
        so.marker_size = 0.025;
        so.side_half_width = 0.06;
      } else if (object == 2) {  // a six-sided prism with distortion in every camera
        so.sides = 6;
        so.radtan_k1 = -0.2;
      }
      const testing::SynthScene scene = testing::MakeScene(so);
      const MapResult result = MapScene(scene, testing::SceneMapperOptions(scene, so.marker_size));
      const testing::MapErrors e =
          testing::CompareToTruth(scene, result.map, result.trajectory, so.marker_size);
      const std::string what = "radius " + std::to_string(radius) + " object " + std::to_string(object);
      EXPECT_EQ(e.cameras_compared, 5) << what;
      EXPECT_EQ(e.markers_compared, static_cast<int>(scene.ids.size())) << what;
      EXPECT_LT(e.object_translation_m, 0.0005) << what;
      EXPECT_LT(e.object_rotation_deg, 0.3) << what;
      EXPECT_LT(e.camera_position_m, 0.002) << what;
      EXPECT_LT(e.configuration_m, 0.0003) << what;
      EXPECT_TRUE(result.report.rejected_markers.empty()) << what;
      EXPECT_LT(result.report.final_rms_px, result.report.initial_rms_px) << what;
    }
  }
}

TEST(MapperSynthetic, EverySubsetOfThreeOfFiveCamerasMaps) {
  testing::SynthOptions so;
  so.frames = 150;
  so.seed = 21;
  const testing::SynthScene full = testing::MakeScene(so);
  int subsets = 0;
  for (int a = 0; a < 5; ++a)
    for (int b = a + 1; b < 5; ++b)
      for (int c = b + 1; c < 5; ++c) {
        testing::SynthScene scene = full;
        const std::vector<std::string> keep = {full.names[a], full.names[b], full.names[c]};
        scene.names = keep;
        scene.rig_from_cam = {full.rig_from_cam[a], full.rig_from_cam[b], full.rig_from_cam[c]};
        scene.detections.clear();
        for (const auto& d : full.detections)
          if (std::find(keep.begin(), keep.end(), d.camera) != keep.end()) scene.detections.push_back(d);
        const std::string what = keep[0] + "," + keep[1] + "," + keep[2];
        MapResult result;
        ASSERT_NO_THROW(result = MapScene(scene)) << what;
        ExpectWithinIssueBounds(scene, result, what);
        ++subsets;
      }
  EXPECT_EQ(subsets, 10);
}

TEST(MapperSynthetic, FalseDetectionsAndDroppedFramesAreHandled) {
  testing::SynthOptions so;
  so.frames = 200;
  so.seed = 31;
  so.false_rate = 0.1;        // 10 % of camera frames carry a false detection
  so.drop_rate = 0.05;        // 5 % of camera frames are dropped
  so.static_false_id = 77;    // and a marker fixed in the room, not on the object
  so.camera_jitter_us = 700;  // cameras not exactly simultaneous
  const testing::SynthScene scene = testing::MakeScene(so);
  ASSERT_GT(scene.false_detections, 50);
  const MapResult result = MapScene(scene);
  ExpectWithinIssueBounds(scene, result, "false + dropped");
  // No false id in the map; the static one is reported as not rigidly attached.
  for (const MapMarker& m : result.map.markers)
    EXPECT_NE(std::find(scene.ids.begin(), scene.ids.end(), m.id), scene.ids.end())
        << "false id " << m.id << " mapped";
  bool static_reported = false;
  for (const RejectedMarker& r : result.report.rejected_markers) {
    EXPECT_NE(std::find(scene.false_ids.begin(), scene.false_ids.end(), r.id), scene.false_ids.end())
        << "true marker " << r.id << " rejected: " << r.reason;
    if (r.id == 77) {
      static_reported = true;
      EXPECT_NE(r.reason.find("not rigidly attached"), std::string::npos) << r.reason;
    }
  }
  EXPECT_TRUE(static_reported);
  const std::string json = ReportJson(result);
  EXPECT_NE(json.find("\"id\": 77"), std::string::npos);
}

TEST(MapperSynthetic, CamerasStartingLateAndStoppingEarly) {
  testing::SynthOptions so;
  so.frames = 200;
  so.seed = 33;
  so.camera_jitter_us = 900;
  testing::SynthScene scene = testing::MakeScene(so);
  std::vector<detections_t> kept;
  for (const auto& d : scene.detections) {
    if (d.camera == "cam3" && d.seq < 80) continue;   // starts late
    if (d.camera == "cam4" && d.seq >= 90) continue;  // stops early
    kept.push_back(d);
  }
  scene.detections = kept;
  const MapResult result = MapScene(scene);
  ExpectWithinIssueBounds(scene, result, "late start / early stop");
  EXPECT_EQ(result.report.frames_assembled, 200);  // jittered utimes still join their frames
}

TEST(MapperSynthetic, WhitelistIgnoresOtherIds) {
  testing::SynthOptions so;
  so.frames = 80;
  so.static_false_id = 77;
  const testing::SynthScene scene = testing::MakeScene(so);
  MapperOptions options = testing::SceneMapperOptions(scene);
  options.marker_ids = scene.ids;
  const MapResult result = MapScene(scene, options);
  EXPECT_GT(result.report.ignored_ids, 0);
  EXPECT_TRUE(result.report.rejected_markers.empty());
  EXPECT_EQ(result.map.markers.size(), scene.ids.size());
}

TEST(MapperSynthetic, DuplicateIdsInOneFrameAreDroppedAndReported) {
  testing::SynthOptions so;
  so.frames = 80;
  testing::SynthScene scene = testing::MakeScene(so);
  int added = 0;
  for (auto& d : scene.detections)
    if (!d.markers.empty() && added < 5) {
      marker_t copy = d.markers[0];
      for (auto& c : copy.corners) c[0] += 100;
      d.markers.push_back(copy);
      d.num_markers = static_cast<int32_t>(d.markers.size());
      ++added;
    }
  const MapResult result = MapScene(scene);
  EXPECT_EQ(result.report.duplicates, 2 * added);
  EXPECT_EQ(result.report.duplicate_examples.size(), static_cast<size_t>(added));
  ExpectWithinIssueBounds(scene, result, "duplicates");
}

// ---------------------------------------------------------------------------------------------
// Bad input

TEST(MapperSynthetic, NoDetectionsIsAClearError) {
  testing::SynthOptions so;
  so.frames = 5;
  const testing::SynthScene scene = testing::MakeScene(so);
  Mapper mapper(testing::SceneMapperOptions(scene));
  try {
    mapper.Solve();
    FAIL() << "expected an error";
  } catch (const MapperError& e) {
    EXPECT_NE(std::string(e.what()).find("no detections"), std::string::npos) << e.what();
  }
}

TEST(MapperSynthetic, OneCameraOnlyNamesTheSilentCameras) {
  testing::SynthOptions so;
  so.frames = 60;
  const testing::SynthScene scene = testing::MakeScene(so);
  Mapper mapper(testing::SceneMapperOptions(scene));
  for (const auto& d : scene.detections)
    if (d.camera == "cam0") mapper.Add(d);
  try {
    mapper.Solve();
    FAIL() << "expected an error";
  } catch (const MapperError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("sent no detections"), std::string::npos) << what;
    EXPECT_NE(what.find("cam1"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << "one line: " << what;
  }
  // --allow-partial maps the one camera (markers and object poses still come out).
  MapperOptions options = testing::SceneMapperOptions(scene);
  options.allow_partial = true;
  Mapper partial(options);
  for (const auto& d : scene.detections)
    if (d.camera == "cam0") partial.Add(d);
  const MapResult result = partial.Solve();
  EXPECT_EQ(result.map.cameras.size(), 1u);
  EXPECT_EQ(result.report.dropped_cameras.size(), 4u);
}

TEST(MapperSynthetic, DisconnectedCameraIsNamedWithWhatWouldConnectIt) {
  testing::SynthOptions so;
  so.frames = 120;
  const testing::SynthScene scene = testing::MakeScene(so);
  // cam2 only reports frames where no other camera reports: it never shares a frame with them.
  Mapper mapper(testing::SceneMapperOptions(scene));
  MapperOptions options = testing::SceneMapperOptions(scene);
  options.allow_partial = true;
  Mapper partial(options);
  for (const auto& d : scene.detections) {
    const bool even = d.seq % 2 == 0;
    if ((d.camera == "cam2") == even) continue;  // cam2: odd frames; others: even frames
    mapper.Add(d);
    partial.Add(d);
  }
  try {
    mapper.Solve();
    FAIL() << "expected an error";
  } catch (const MapperError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("camera 'cam2' cannot be placed"), std::string::npos) << what;
    EXPECT_NE(what.find("record frames where 'cam2' and one of those cameras see the object"),
              std::string::npos)
        << what;
    EXPECT_NE(what.find("--allow-partial"), std::string::npos) << what;
  }
  const MapResult result = partial.Solve();
  EXPECT_EQ(result.map.cameras.size(), 4u);
  EXPECT_EQ(result.map.FindCamera("cam2"), nullptr);
  ASSERT_EQ(result.report.dropped_cameras.size(), 1u);
  EXPECT_EQ(result.report.dropped_cameras[0], "cam2");
  const testing::MapErrors e = testing::CompareToTruth(scene, result.map, result.trajectory);
  EXPECT_LT(e.camera_position_m, 0.002);
}

TEST(MapperSynthetic, UnknownCameraIsIgnoredWithAWarning) {
  testing::SynthOptions so;
  so.frames = 60;
  testing::SynthScene scene = testing::MakeScene(so);
  MapperOptions options = testing::SceneMapperOptions(scene);
  options.cameras.pop_back();  // cam4 not in the rig
  scene.names.pop_back();
  scene.rig_from_cam.pop_back();
  const MapResult result = MapScene(scene, options);
  EXPECT_EQ(result.map.cameras.size(), 4u);
  ASSERT_FALSE(result.report.warnings.empty());
  EXPECT_NE(result.report.warnings[0].find("cam4"), std::string::npos);
}

}  // namespace
}  // namespace mcmt
