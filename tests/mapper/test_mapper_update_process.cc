// The offline update as users run it (issue 17): mcmt-sim writes the sessions, mcmt-mapper maps the
// first one, then `mcmt-mapper --config rig.yaml --map OLD/map.yaml --log new.lcmlog --out NEW/` runs
// as a process of its own on a session where a camera was bumped, or where a sixth camera was added.
// The new map.yaml is measured against the simulator's ground truth (sim::Evaluate, mcmt-eval's
// figures) and report.json's moved_cameras / added_cameras are read back.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <iostream>
#include <string>

#include "core/files.h"
#include "sim/eval.h"
#include "sim/sim.h"
#include "tests/support/process.h"
#include "tests/support/temp_dir.h"

namespace mcmt {
namespace {

using test::Bin;
using test::RunCommand;

// mcmt-sim --detections-only into dir (the paper's rig at 1.0 m, 5 cameras, 30 fps).
void Simulate(const std::string& dir, int frames, int seed, const std::string& extra = "") {
  const test::ProcessResult r =
      RunCommand(Bin("mcmt-sim") + " --out " + dir + " --detections-only --quiet" + " --frames " +
                     std::to_string(frames) + " --seed " + std::to_string(seed) + " " + extra,
                 120);
  ASSERT_EQ(r.exit_code, 0) << r.output;
}

test::ProcessResult Mapper(const std::string& args) {
  return RunCommand(Bin("mcmt-mapper") + " --threads 1 " + args, 240);
}

class MapperUpdateProcess : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test::TempDir("update_process");
    Simulate(*dir_ / "old", 600, 1);
    const test::ProcessResult r = Mapper("--config " + (*dir_ / "old/rig.yaml") + " --log " +
                                         (*dir_ / "old/detections.lcmlog") + " --out " + (*dir_ / "old_map"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  static void TearDownTestSuite() { delete dir_; }
  static std::string OldMap() { return *dir_ / "old_map/map.yaml"; }
  // The update of session `name` from the old map: the new map's camera errors against the session's end.
  static sim::EvalResult Update(const std::string& name, YAML::Node* report) {
    const std::string session = *dir_ / name, out = *dir_ / (name + "_map");
    const test::ProcessResult r = Mapper("--config " + session + "/rig.yaml --map " + OldMap() + " --log " +
                                         session + "/detections.lcmlog --out " + out);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    *report = YAML::LoadFile(out + "/report.json");
    const RigMap map = ReadMap(out + "/map.yaml");
    const sim::EvalResult e =
        sim::Evaluate(sim::ReadGroundTruth(session + "/ground_truth.yaml"), &map, nullptr);
    std::cout << name << ": cameras within " << e.camera_position_mm.max << " mm, "
              << e.camera_rotation_deg.max << " deg of the truth\n";
    return e;
  }
  static test::TempDir* dir_;
};
test::TempDir* MapperUpdateProcess::dir_ = nullptr;

TEST_F(MapperUpdateProcess, MovedCameraReestimatedWithinHalfAMillimetre) {
  Simulate(*dir_ / "moved", 300, 2, "--move-camera cam3,0,0.5,3");
  YAML::Node report;
  const sim::EvalResult e = Update("moved", &report);
  ASSERT_EQ(e.mapped_cameras, 5);
  EXPECT_LT(e.camera_position_mm.max, 0.5);
  EXPECT_LT(e.camera_rotation_deg.max, 0.05);
  ASSERT_TRUE(report["moved_cameras"].IsSequence());
  ASSERT_EQ(report["moved_cameras"].size(), 1u);
  const YAML::Node m = report["moved_cameras"][0];
  EXPECT_EQ(m["camera"].as<std::string>(), "cam3");
  EXPECT_NEAR(m["rotation_deg"].as<double>(), 0.5, 0.05);
  EXPECT_NEAR(m["translation_mm"].as<double>(), 3.0, 0.5);
  EXPECT_EQ(report["added_cameras"].size(), 0u);
  // The old map's other cameras are exactly where they were (the layout and the rest held fixed).
  const RigMap old_map = ReadMap(OldMap()), new_map = ReadMap(*dir_ / "moved_map/map.yaml");
  for (const MapCamera& c : old_map.cameras) {
    if (c.name == "cam3") continue;
    EXPECT_LT(TranslationDistance(new_map.FindCamera(c.name)->rig_from_cam, c.rig_from_cam), 1e-9) << c.name;
  }
}

TEST_F(MapperUpdateProcess, SixthCameraAddedFrom300FramesWithinAMillimetre) {
  Simulate(*dir_ / "added", 300, 3, "--add-camera 0");
  YAML::Node report;
  const sim::EvalResult e = Update("added", &report);
  ASSERT_EQ(e.mapped_cameras, 6);
  EXPECT_LT(e.camera_position_mm.max, 1.0);
  EXPECT_LT(e.camera_rotation_deg.max, 0.05);
  EXPECT_EQ(report["moved_cameras"].size(), 0u);
  ASSERT_EQ(report["added_cameras"].size(), 1u);
  EXPECT_EQ(report["added_cameras"][0].as<std::string>(), "cam5");
}

TEST_F(MapperUpdateProcess, TheOldMapIsNotOverwritten) {
  const test::ProcessResult r =
      Mapper("--config " + (*dir_ / "old/rig.yaml") + " --map " + OldMap() + " --log " +
             (*dir_ / "old/detections.lcmlog") + " --out " + (*dir_ / "old_map"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("holds the old map given with --map"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace mcmt
