// MapperOptions: the rig's mapper: and sync: sections through the declared table; the same checks for
// options built in code; errors name file and key.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/options.h"
#include "mapper/mapper.h"
#include "tests/support/temp_dir.h"

namespace mcmt {
namespace {

namespace fs = std::filesystem;

// The pinned test's rig (five cameras) with `extra` appended, in a fresh folder.
std::string PinnedRigWith(const std::string& name, const std::string& extra) {
  const fs::path src = fs::path(MCMT_SOURCE_DIR) / "tests/data/mapper_pin";
  const fs::path dir = test::MakeTempDir("mapper_options_" + name);
  for (int c = 0; c < 5; ++c)
    fs::copy_file(src / ("cam" + std::to_string(c) + ".yml"), dir / ("cam" + std::to_string(c) + ".yml"));
  std::ofstream(dir / "rig.yaml") << ReadFile((src / "rig.yaml").string()) << extra;
  return (dir / "rig.yaml").string();
}

std::string FromConfigError(const std::string& name, const std::string& extra) {
  const std::string path = PinnedRigWith(name, extra);
  try {
    MapperOptions::FromConfig(LoadRigConfig(path));
  } catch (const OptionError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(path + ": ", 0), 0u) << what;  // names the file
    return what.substr(path.size() + 2);
  }
  return "(no error)";
}

TEST(MapperOptions, ReadsMapperAndSyncSections) {
  const MapperOptions o =
      MapperOptions::FromConfig(LoadRigConfig(PinnedRigWith("read",
                                                            "  tau_e: 3\n  linear_solver: dense_schur\n"
                                                            "  reference_camera: cam2\n"
                                                            "  corner_weights: sides\n"
                                                            "sync: {tolerance_ms: 4.5}\n")));
  EXPECT_EQ(o.tau_e, 3.0);
  EXPECT_EQ(o.outlier_px, 0.55);
  EXPECT_EQ(o.linear_solver, "dense_schur");
  EXPECT_EQ(o.reference_camera, "cam2");
  EXPECT_TRUE(o.corner_weighting.BySides());
  EXPECT_EQ(o.corner_weighting.floor, CornerWeighting().floor);
  EXPECT_EQ(o.sync_tolerance_ms, 4.5);
  EXPECT_EQ(o.sync_tolerance_us(), 4500);
  EXPECT_EQ(o.cameras.size(), 5u);
}

TEST(MapperOptions, FileErrorsNameTheKey) {
  EXPECT_EQ(FromConfigError("typo", "  hubr_px: 2\n").substr(0, 24), "mapper.hubr_px: unknown ");
  EXPECT_EQ(FromConfigError("pairs", "  max_pair_events: 5\n"),
            "mapper.max_pair_events: must be >= 10, got 5");
  EXPECT_EQ(FromConfigError("solver", "  linear_solver: cholesky\n"),
            "mapper.linear_solver: expected one of auto, sparse_schur, dense_schur, iterative_schur, got "
            "'cholesky'");
  EXPECT_EQ(FromConfigError("ref", "  reference_camera: cam7\n"),
            "mapper.reference_camera: no camera named 'cam7' (cameras: cam0, cam1, cam2, cam3, cam4)");
  EXPECT_EQ(FromConfigError("weights", "  corner_weights: diagonal\n"),
            "mapper.corner_weights: expected one of equal, sides, got 'diagonal'");
  EXPECT_EQ(FromConfigError("floor", "  corner_weight_floor: -0.1\n"),
            "mapper.corner_weight_floor: must be >= 0, got -0.1");
  EXPECT_EQ(FromConfigError("sync", "sync: {tolerance_ms: -1}\n"), "sync.tolerance_ms: must be >= 0, got -1");
  // Self-calibration keys: declared in the table or read beside it, the same error form.
  EXPECT_EQ(FromConfigError("ratio", "  observability_ratio: 1.5\n"),
            "mapper.observability_ratio: must be in (0, 1], got 1.5");
  EXPECT_EQ(FromConfigError("offset", "  max_time_offset_ms: 0\n"),
            "mapper.max_time_offset_ms: must be > 0, got 0");
  EXPECT_EQ(FromConfigError("sigma", "  intrinsics_sigma: {focal_rel: 0}\n").substr(0, 34),
            "mapper.intrinsics_sigma.focal_rel:");
  EXPECT_EQ(FromConfigError("sigma_key", "  intrinsics_sigma: {focal: 0.1}\n").substr(0, 39),
            "mapper.intrinsics_sigma.focal: unknown ");
  EXPECT_EQ(FromConfigError("refine", "  refine_intrinsics: magic\n").substr(0, 26),
            "mapper.refine_intrinsics: ");
  EXPECT_EQ(FromConfigError("refine_cams", "  refine_intrinsics_cameras: [cam9]\n"),
            "mapper.refine_intrinsics_cameras: no camera named 'cam9'");
  EXPECT_EQ(FromConfigError("sync_key", "sync: {tolerance_us: 1}\n").substr(0, 29),
            "sync.tolerance_us: unknown ke");
  // The printed marker size's sigma: a percentage, 0 (exact) up to below 10 %.
  EXPECT_EQ(FromConfigError("size_sigma", "  marker_size_sigma_percent: -0.1\n"),
            "mapper.marker_size_sigma_percent: must be in [0, 10), got -0.1");
  EXPECT_EQ(FromConfigError("size_sigma_big", "  marker_size_sigma_percent: 10\n"),
            "mapper.marker_size_sigma_percent: must be in [0, 10), got 10");
  EXPECT_EQ(FromConfigError("size_sigma_text", "  marker_size_sigma_percent: much\n").substr(0, 34),
            "mapper.marker_size_sigma_percent: ");
  EXPECT_EQ(MapperOptions::FromConfig(
                LoadRigConfig(PinnedRigWith("size_sigma_ok", "  marker_size_sigma_percent: 0.25\n")))
                .marker_size_sigma_percent,
            0.25);
  EXPECT_EQ(MapperOptions().marker_size_sigma_percent, 0.0);
}

// Checks that FromConfig made and Validate skipped before (options built in code) now fail the same way.
TEST(MapperOptions, OptionsBuiltInCodeGetTheFileChecks) {
  const auto error = [](MapperOptions o) -> std::string {
    o.sizes.default_size = 0.05;
    try {
      Mapper mapper(o);
    } catch (const OptionError& e) {
      return e.what();
    }
    return "(no error)";
  };
  MapperOptions o;
  EXPECT_EQ(error(o), "(no error)");
  o.max_pair_events = 5;
  EXPECT_EQ(error(o), "mapper.max_pair_events: must be >= 10, got 5");
  o = MapperOptions();
  o.threads = -2;
  EXPECT_EQ(error(o), "mapper.threads: must be >= 0, got -2");
  o = MapperOptions();
  o.linear_solver = "qr";
  EXPECT_EQ(error(o).substr(0, 33), "mapper.linear_solver: expected on");
  o = MapperOptions();
  o.marker_inlier_fraction = 1.5;
  EXPECT_EQ(error(o), "mapper.marker_inlier_fraction: must be in [0, 1], got 1.5");
  o = MapperOptions();
  o.estimate_clock_drift = true;
  EXPECT_EQ(error(o), "mapper.clock_drift: needs time_offsets: true (a drift is estimated with the offsets)");
  o.estimate_time_offsets = true;
  EXPECT_EQ(error(o), "(no error)");
  o = MapperOptions();
  o.cameras = {"a", "b"};
  o.reference_camera = "c";
  EXPECT_EQ(error(o), "mapper.reference_camera: no camera named 'c' (cameras: a, b)");
  o = MapperOptions();
  o.marker_ids = {1, 2};
  o.reference_marker = 3;
  EXPECT_EQ(error(o), "mapper.reference_marker: 3 is not in markers.ids");
  o = MapperOptions();
  o.intrinsics.sigma.center_px = 0;
  EXPECT_EQ(error(o), "mapper.intrinsics_sigma.center_px: must be > 0, got 0");
  o = MapperOptions();
  o.intrinsics.observability_ratio = 0;
  EXPECT_EQ(error(o), "mapper.observability_ratio: must be in (0, 1], got 0");
  o = MapperOptions();
  o.marker_size_sigma_percent = 12;
  EXPECT_EQ(error(o), "mapper.marker_size_sigma_percent: must be in [0, 10), got 12");
}

TEST(MapperOptions, DocsTableListsEveryKey) {
  const std::string md = MapperOptionTable().Markdown();
  for (const std::string& key : MapperOptionTable().Keys())
    EXPECT_NE(md.find("| `" + key + "` |"), std::string::npos) << key;
  EXPECT_NE(md.find("| `huber_px` | px | `1` |"), std::string::npos) << md;
  EXPECT_NE(md.find("| `max_pair_events` |  | `3000` | must be >= 10 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| `paper_stop_px` | px | `0.0001` | must be > 0 |"), std::string::npos) << md;
}

}  // namespace
}  // namespace mcmt
