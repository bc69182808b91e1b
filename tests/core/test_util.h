// Helpers shared by the core tests: a test camera, a temporary folder removed at the end, file writing,
// text edits and a contains-check for error messages.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "core/camera.h"
#include "tests/support/temp_dir.h"

// A string that must contain a part, and says which when it does not.
#define EXPECT_CONTAINS(haystack, needle)                          \
  EXPECT_NE(std::string(haystack).find(needle), std::string::npos) \
      << "'" << (haystack) << "' lacks '" << (needle) << "'"

namespace mcmt {
namespace testing_util {

// A 1280x960 camera with strong radtan distortion (k1 k2 p1 p2 k3).
inline CameraModel TestCamera() {
  CameraModel c = CameraModel::Pinhole(1280, 960, 1000, 639.5, 479.5);
  c.model = DistortionModel::kRadTan;
  c.distortion = {-0.25, 0.09, 0.001, -0.0007, -0.015};
  return c;
}

using TempDir = mcmt::test::TempDir;  // tests/support

// `text` with the first `from` replaced by `to` (a test failure when `from` is not there).
inline std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

}  // namespace testing_util
}  // namespace mcmt
