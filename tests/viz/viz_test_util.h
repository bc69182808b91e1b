// Helpers of the viewer tests: temporary folders, running mcmt-viz, pixel checks.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "core/files.h"
#include "core/se3.h"
#include "tests/support/process.h"
#include "tests/support/temp_dir.h"
#include "tests/viz/test_rig.h"

namespace mcmt::viz::testing {

// The tests/support helpers; path() as a std::filesystem::path for the viewer tests.
class TempDir : public mcmt::test::TempDir {
 public:
  explicit TempDir(const std::string& tag) : mcmt::test::TempDir("viz_" + tag) {}
  std::filesystem::path path() const { return mcmt::test::TempDir::path(); }
};

using mcmt::test::ProcessResult;
inline ProcessResult RunCommand(const std::string& command, int timeout_s = 60) {
  return mcmt::test::RunCommand(command, timeout_s);
}

inline std::string VizBin() { return std::string(MCMT_BIN_DIR) + "/mcmt-viz"; }

// Is any pixel within `radius` of (x, y) different from the background colour by more than `tol`?
inline bool NotBackgroundNear(const cv::Mat& bgr, const Eigen::Vector2d& px, const cv::Vec3b& background,
                              int radius = 2, int tol = 20) {
  const int cx = static_cast<int>(std::floor(px.x())), cy = static_cast<int>(std::floor(px.y()));
  for (int y = cy - radius; y <= cy + radius; ++y)
    for (int x = cx - radius; x <= cx + radius; ++x) {
      if (x < 0 || y < 0 || x >= bgr.cols || y >= bgr.rows) continue;
      const cv::Vec3b p = bgr.at<cv::Vec3b>(y, x);
      for (int c = 0; c < 3; ++c)
        if (std::abs(int(p[c]) - int(background[c])) > tol) return true;
    }
  return false;
}

}  // namespace mcmt::viz::testing
