// Agreement with a peer calibration (caliscope camera_array.toml).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "sim/peer_calibration.h"
#include "tests/support/temp_dir.h"

namespace fs = std::filesystem;

namespace {
const std::string kArray =
    std::string(MCMT_SOURCE_DIR) + "/../shared/data/caliscope/charuco_calibration/camera_array.toml";

// The peer's cameras as a map whose rig frame is cam1's.
mcmt::RigMap MapFromPeer(const std::vector<mcmt::sim::PeerCamera>& peer) {
  mcmt::RigMap map;
  for (const auto& p : peer) {
    mcmt::MapCamera c;
    c.name = p.name;
    c.rig_from_cam = peer[1].cam_from_world * mcmt::Inverse(p.cam_from_world);
    map.cameras.push_back(c);
  }
  return map;
}
}  // namespace

TEST(PeerCalibration, ReadsCaliscopeAndAgreesWithItselfInAnotherFrame) {
  if (!fs::exists(kArray)) GTEST_SKIP() << kArray << " absent (../shared/data not available)";
  const auto peer = mcmt::sim::ReadCaliscopeCameras(kArray);
  ASSERT_EQ(peer.size(), 4u);
  EXPECT_EQ(peer[0].name, "cam0");
  // cam0's translation as written in the file.
  EXPECT_NEAR(peer[0].cam_from_world.translation().x(), 0.12300856355436324, 1e-15);
  const auto a = mcmt::sim::CompareWithPeer(MapFromPeer(peer), peer);
  ASSERT_EQ(a.cameras.size(), 4u);
  EXPECT_LT(a.max_position_mm, 1e-6);
  EXPECT_LT(a.max_rotation_deg, 1e-6);
  EXPECT_NEAR(a.scale_ratio, 1.0, 1e-9);
}

TEST(PeerCalibration, ShowsAKnownDisplacement) {
  if (!fs::exists(kArray)) GTEST_SKIP() << kArray << " absent (../shared/data not available)";
  const auto peer = mcmt::sim::ReadCaliscopeCameras(kArray);
  mcmt::RigMap map = MapFromPeer(peer);
  map.cameras[2].rig_from_cam.translation() += Eigen::Vector3d(0.04, 0, 0);  // 40 mm
  const auto a = mcmt::sim::CompareWithPeer(map, peer);
  // Horn alignment spreads the displacement: the moved camera keeps most of it, total stays 40 mm-ish.
  EXPECT_GT(a.cameras[2].position_mm, 20.0);
  EXPECT_LT(a.cameras[2].position_mm, 40.0 + 1e-6);
  EXPECT_GT(a.max_position_mm, 20.0);
  map.cameras.pop_back();
  EXPECT_EQ(mcmt::sim::CompareWithPeer(map, peer).missing, std::vector<std::string>{"cam3"});
}

TEST(PeerCalibration, MalformedFileNamesTheKey) {
  const mcmt::test::TempDir dir("peer");
  const fs::path f = dir / "peer.toml";
  std::ofstream(f) << "[cameras.0]\nrotation = [[1,0,0],[0,1,0]]\ntranslation = [0,0,0]\n";
  try {
    mcmt::sim::ReadCaliscopeCameras(f.string());
    FAIL() << "expected an error";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("cameras.0.rotation: expected 9 numbers, got 6"), std::string::npos)
        << e.what();
  }
  std::ofstream(f) << "[cameras.0]\nrotation = [[1,0,0],[0,1,0],[0,0,1]]\n";
  EXPECT_THROW(mcmt::sim::ReadCaliscopeCameras(f.string()), std::runtime_error);
  EXPECT_THROW(mcmt::sim::ReadCaliscopeCameras("/nonexistent.toml"), std::runtime_error);
}
