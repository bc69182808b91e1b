// Helpers shared by the core tests: a test camera, a temporary folder removed at the end, file writing.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "core/camera.h"
#include "tests/support/temp_dir.h"

namespace mcmt {
namespace testing_util {

// A 1280x960 camera with strong radtan distortion (k1 k2 p1 p2 k3).
inline CameraModel TestCamera() {
  CameraModel c;
  c.width = 1280;
  c.height = 960;
  c.fx = c.fy = 1000;
  c.cx = 639.5;
  c.cy = 479.5;
  c.model = DistortionModel::kRadTan;
  c.distortion = {-0.25, 0.09, 0.001, -0.0007, -0.015};
  return c;
}

using TempDir = mcmt::test::TempDir;  // tests/support

}  // namespace testing_util
}  // namespace mcmt
