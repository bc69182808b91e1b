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
#include "tests/viz/test_rig.h"

namespace mcmt::viz::testing {

// A fresh folder under the system temp dir, removed at destruction unless MCMT_VIZ_KEEP is set.
class TempDir {
 public:
  explicit TempDir(const std::string& tag) {
    const auto stamp = std::chrono::steady_clock::now().time_since_epoch().count();
    path_ = std::filesystem::temp_directory_path() /
            ("mcmt_viz_" + tag + "_" + std::to_string(::getpid()) + "_" + std::to_string(stamp));
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    if (!std::getenv("MCMT_VIZ_KEEP")) {
      std::error_code ec;
      std::filesystem::remove_all(path_, ec);
    } else {
      std::fprintf(stderr, "kept %s\n", path_.c_str());
    }
  }
  std::string operator/(const std::string& name) const { return (path_ / name).string(); }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

struct ProcessResult {
  int exit_code = -1;
  std::string output;  // stdout + stderr
};

// Runs a shell command line with a time limit (coreutils timeout), capturing its output.
inline ProcessResult RunCommand(const std::string& command, int timeout_s = 60) {
  const std::string full = "timeout -k 5 " + std::to_string(timeout_s) + " " + command + " 2>&1";
  ProcessResult r;
  FILE* pipe = ::popen(full.c_str(), "r");
  if (!pipe) return r;
  char buffer[4096];
  size_t n;
  while ((n = std::fread(buffer, 1, sizeof(buffer), pipe)) > 0) r.output.append(buffer, n);
  const int status = ::pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
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
