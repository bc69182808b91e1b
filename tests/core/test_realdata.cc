// The rig configs shipped in configs/ (real caliscope recordings) load, and their sources resolve to
// the recordings in shared/data when those are present.
#include <gtest/gtest.h>

#include <filesystem>

#include "core/config.h"

namespace mcmt {
namespace {

namespace fs = std::filesystem;

TEST(RealData, CaliscopeConfigsLoad) {
  const fs::path data = fs::path(MCMT_SOURCE_DIR) / ".." / "shared" / "data" / "caliscope";
  if (!fs::exists(data)) GTEST_SKIP() << "real data absent: " << data.string();
  for (const char* name : {"caliscope_4cam.yaml", "caliscope_charuco.yaml"}) {
    const fs::path path = fs::path(MCMT_SOURCE_DIR) / "configs" / name;
    if (!fs::exists(path)) GTEST_SKIP() << "config absent: " << path.string();
    const RigConfig rig = LoadRigConfig(path.string());
    EXPECT_EQ(rig.markers.dictionary, "DICT_4X4_1000");
    EXPECT_TRUE(rig.markers.inverted);
    ASSERT_EQ(rig.cameras.size(), 4u);
    for (const auto& cam : rig.cameras) {
      EXPECT_NO_THROW(cam.model.Validate());
      EXPECT_EQ(cam.model.width, 1280);
      EXPECT_EQ(cam.model.height, 720);
      EXPECT_EQ(cam.model.model, DistortionModel::kRadTan);
      // Resolved to the recording (absolute) because it exists.
      EXPECT_TRUE(fs::path(cam.source).is_absolute()) << cam.source;
      EXPECT_TRUE(fs::exists(cam.source)) << cam.source;
      EXPECT_TRUE(fs::exists(cam.timestamps_path)) << cam.timestamps_path;
    }
  }
}

}  // namespace
}  // namespace mcmt
