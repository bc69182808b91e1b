// Rendered images -> the project's detector (DetectRecording) -> mapper, against the simulator's
// ground truth: the whole offline pipeline without LCM.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "core/config.h"
#include "detector/detector.h"
#include "mapper/mapper.h"
#include "sim/eval.h"
#include "sim/sim.h"

namespace mcmt {
namespace {

namespace fs = std::filesystem;

TEST(MapperRendered, RenderedFourSidedAtOneMetre) {
  const std::string dir =
      (fs::temp_directory_path() / ("mcmt_mapper_rendered_" + std::to_string(getpid()))).string();
  fs::remove_all(dir);
  sim::DatasetOptions options;
  options.out_dir = dir;
  options.object.kind = sim::ObjectKind::kFourSided;
  options.rig.num_cameras = 5;
  options.rig.radius = 1.0;
  options.trajectory.frames = 60;
  options.trajectory.seed = 4;
  options.threads = 2;
  const sim::DatasetSummary summary = sim::GenerateDataset(options);
  const RigConfig rig = LoadRigConfig(dir + "/rig.yaml");
  Mapper mapper(MapperOptions::FromConfig(rig));
  for (const CameraConfig& c : rig.cameras)
    for (const detections_t& d : DetectRecording(rig, c.name)) mapper.Add(d);
  const MapResult result = mapper.Solve();
  const sim::EvalResult e = sim::Evaluate(summary.truth, &result.map, &result.trajectory);
  EXPECT_EQ(e.mapped_cameras, 5);
  EXPECT_EQ(e.mapped_markers, e.gt_markers);
  EXPECT_LT(e.object_translation_aligned_mm.mean, 0.5);
  EXPECT_LT(e.object_rotation_deg.mean, 0.3);
  EXPECT_LT(e.camera_position_mm.mean, 2.0);
  EXPECT_LT(e.configuration_mm.mean, 0.3);
  RecordProperty("errors", std::to_string(e.object_translation_aligned_mm.mean) + " mm, " +
                               std::to_string(e.object_rotation_deg.mean) + " deg, cam " +
                               std::to_string(e.camera_position_mm.mean) + " mm, config " +
                               std::to_string(e.configuration_mm.mean) + " mm, rms " +
                               std::to_string(result.map.rms_px) + " px");
  fs::remove_all(dir);
}

}  // namespace
}  // namespace mcmt
