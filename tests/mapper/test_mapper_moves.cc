// Cameras that move (issue 17): a camera bumped within one session (mapper/epochs.h) and the offline
// update from an old map (mapper/update.h), on sessions written by the simulator's own generator
// (mcmt-sim --detections-only --move-camera / --add-camera), measured against its ground truth.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/lcm_util.h"
#include "core/log_reader.h"
#include "mapper/mapper.h"
#include "sim/eval.h"
#include "sim/sim.h"
#include "tests/support/temp_dir.h"

namespace mcmt {
namespace {

struct Session {
  sim::GroundTruth truth;
  std::vector<detections_t> detections;
};

// The paper's rig at 1.0 m, 5 cameras, 30 fps, the four-sided object (as mcmt-sim's defaults).
Session Generate(const std::string& dir, int frames, uint64_t seed,
                 std::vector<sim::CameraMoveOptions> moves = {}, int64_t add_camera_frame = -1) {
  sim::DatasetOptions o = sim::DetectionsOnlySession(dir, frames, seed);
  o.moves = std::move(moves);
  o.add_camera_frame = add_camera_frame;
  Session s;
  s.truth = sim::GenerateDataset(o).truth;
  for (const LogEvent& e : ReadEventLog(dir + "/detections.lcmlog")) {
    detections_t d;
    if (Decode(e.data.data(), e.data.size(), &d)) s.detections.push_back(d);
  }
  return s;
}

MapperOptions OptionsFor(const sim::GroundTruth& truth) {
  MapperOptions o;
  for (const auto& c : truth.cameras) o.cameras.push_back(c.name);
  o.sizes.default_size = truth.marker_size;
  o.dictionary = truth.dictionary;
  return o;
}

MapResult Map(const Session& s, const MapperOptions& o, const RigMap* old_map = nullptr) {
  Mapper mapper(o);
  if (old_map) mapper.SetBaseMap(*old_map, false);
  for (const detections_t& d : s.detections) mapper.Add(d);
  return mapper.Solve();
}

// Largest camera position (mm) and rotation (deg) error against the truth at the session's end.
std::pair<double, double> WorstCamera(const Session& s, const MapResult& r) {
  const sim::EvalResult e = sim::Evaluate(s.truth, &r.map, &r.trajectory);
  return {e.camera_position_mm.max, e.camera_rotation_deg.max};
}

TEST(MapperMoves, CameraBumpedWithinASessionIsSplitAtTheMove) {
  test::TempDir dir("moves_bump");
  const Session s = Generate(dir.str(), 600, 1, {{"cam2", 300, 0.5, 3.0}});
  const MapResult r = Map(s, OptionsFor(s.truth));
  ASSERT_EQ(r.report.moved_cameras.size(), 1u);
  const MovedCamera& m = r.report.moved_cameras[0];
  EXPECT_EQ(m.camera, "cam2");
  EXPECT_LE(std::abs(m.seq - 300), 10) << m.seq;
  EXPECT_NEAR(m.rotation_deg, 0.5, 0.05);
  EXPECT_NEAR(m.translation_mm, 3.0, 0.5);
  EXPECT_GT(m.observations_before, 100);
  EXPECT_EQ(r.map.cameras.size(), 5u);  // the earlier epoch is not a camera of the map
  const auto [mm, deg] = WorstCamera(s, r);
  EXPECT_LT(mm, 0.5);
  EXPECT_LT(deg, 0.05);
  bool named = false;
  for (const std::string& w : r.report.warnings)
    named = named || w.find("'cam2' moved at seq") != std::string::npos;
  EXPECT_TRUE(named);
  EXPECT_NE(ReportJson(r).find("\"moved_cameras\": [\n    {\"camera\": \"cam2\""), std::string::npos);

  // Without the split, the bump drags every camera off (what the split fixes).
  MapperOptions no_split = OptionsFor(s.truth);
  no_split.detect_moves = false;
  const MapResult dragged = Map(s, no_split);
  EXPECT_TRUE(dragged.report.moved_cameras.empty());
  EXPECT_GT(WorstCamera(s, dragged).first, 2.0);
}

TEST(MapperMoves, NoMoveNoSplit) {
  test::TempDir dir("moves_still");
  const Session s = Generate(dir.str(), 600, 4);
  const MapResult r = Map(s, OptionsFor(s.truth));
  EXPECT_TRUE(r.report.moved_cameras.empty());
  EXPECT_LT(WorstCamera(s, r).first, 0.5);
}

class MapperUpdate : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test::TempDir("update");
    old_ = new Session(Generate(*dir_ / "old", 600, 1));
    old_map_ = new RigMap(Map(*old_, OptionsFor(old_->truth)).map);
  }
  static void TearDownTestSuite() {
    delete old_map_;
    delete old_;
    delete dir_;
  }
  static test::TempDir* dir_;
  static Session* old_;
  static RigMap* old_map_;
};
test::TempDir* MapperUpdate::dir_ = nullptr;
Session* MapperUpdate::old_ = nullptr;
RigMap* MapperUpdate::old_map_ = nullptr;

TEST_F(MapperUpdate, MovedCameraIsReestimatedAndTheOthersKeepTheirPoses) {
  const Session s = Generate(*dir_ / "moved", 300, 2, {{"cam3", 0, 0.5, 3.0}});
  const MapResult r = Map(s, OptionsFor(s.truth), old_map_);
  ASSERT_EQ(r.report.moved_cameras.size(), 1u);
  EXPECT_EQ(r.report.moved_cameras[0].camera, "cam3");
  EXPECT_NEAR(r.report.moved_cameras[0].rotation_deg, 0.5, 0.05);
  EXPECT_NEAR(r.report.moved_cameras[0].translation_mm, 3.0, 0.5);
  EXPECT_TRUE(r.report.added_cameras.empty());
  const auto [mm, deg] = WorstCamera(s, r);
  EXPECT_LT(mm, 0.5);
  EXPECT_LT(deg, 0.05);
  for (const MapCamera& c : old_map_->cameras) {
    if (c.name == "cam3") continue;
    EXPECT_LT(TranslationDistance(r.map.FindCamera(c.name)->rig_from_cam, c.rig_from_cam), 1e-12) << c.name;
  }
  for (const MapMarker& m : old_map_->markers)  // the layout held fixed
    EXPECT_LT(TranslationDistance(r.map.FindMarker(m.id)->object_from_marker, m.object_from_marker), 1e-12);
}

TEST_F(MapperUpdate, SixthCameraIsAddedFrom300Frames) {
  const Session s = Generate(*dir_ / "added", 300, 3, {}, 0);
  const MapResult r = Map(s, OptionsFor(s.truth), old_map_);
  EXPECT_TRUE(r.report.moved_cameras.empty());
  ASSERT_EQ(r.report.added_cameras, std::vector<std::string>{"cam5"});
  ASSERT_EQ(r.map.cameras.size(), 6u);
  const auto [mm, deg] = WorstCamera(s, r);
  EXPECT_LT(mm, 1.0);
  EXPECT_LT(deg, 0.05);
}

TEST_F(MapperUpdate, ItsOwnSessionMovesNothing) {
  const MapResult r = Map(*old_, OptionsFor(old_->truth), old_map_);
  EXPECT_TRUE(r.report.moved_cameras.empty());
  EXPECT_TRUE(r.report.added_cameras.empty());
  EXPECT_EQ(r.map.cameras.size(), old_map_->cameras.size());
}

TEST_F(MapperUpdate, OldMapWithoutTheRigsReferenceCameraIsAnError) {
  RigMap bad = *old_map_;
  bad.reference_camera = "cam9";
  try {
    Map(*old_, OptionsFor(old_->truth), &bad);
    FAIL() << "expected a MapperError";
  } catch (const MapperError& e) {
    EXPECT_NE(std::string(e.what()).find("reference camera 'cam9'"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace mcmt
