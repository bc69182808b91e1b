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
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "core/files.h"
#include "core/se3.h"
#include "tests/support/process.h"
#include "tests/support/temp_dir.h"
#include "tests/viz/test_rig.h"
#include "viz/scene.h"

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

// ---- several bodies: pixels of a body's colour (viz/scene.h's BodyColor) --------------------------------

// Is this pixel body k's colour (each channel within 45 of it)?
inline bool IsBodyColour(const cv::Vec3b& p, size_t k) {
  const Eigen::Vector3d c = 255.0 * BodyColor(k);
  return std::abs(p[2] - c.x()) < 45 && std::abs(p[1] - c.y()) < 45 && std::abs(p[0] - c.z()) < 45;
}

// Pixels of body k's colour within `radius` of px.
inline int BodyPixelsNear(const cv::Mat& bgr, const Eigen::Vector2d& px, size_t k, int radius) {
  int n = 0;
  for (int y = static_cast<int>(px.y()) - radius; y <= static_cast<int>(px.y()) + radius; ++y)
    for (int x = static_cast<int>(px.x()) - radius; x <= static_cast<int>(px.x()) + radius; ++x)
      if (x >= 0 && y >= 0 && x < bgr.cols && y < bgr.rows && IsBodyColour(bgr.at<cv::Vec3b>(y, x), k)) ++n;
  return n;
}

// Pixels of body k's colour in the box [x0, x1) x [y0, y1).
inline int BodyPixelsIn(const cv::Mat& bgr, int x0, int y0, int x1, int y1, size_t k) {
  int n = 0;
  for (int y = std::max(0, y0); y < std::min(bgr.rows, y1); ++y)
    for (int x = std::max(0, x0); x < std::min(bgr.cols, x1); ++x)
      if (IsBodyColour(bgr.at<cv::Vec3b>(y, x), k)) ++n;
  return n;
}

// For every marker of body k at its pose: the midpoints of its outline's 4 edges (1.25 x the marker's
// half side, where the body's outline is drawn), projected; how many have body k's colour within 3 px, and
// how many another body's colour.
struct OutlineHits {
  int points = 0, own = 0, other = 0;
};
inline OutlineHits Outline(const VizScene& scene, const cv::Mat& img, const RigMap& map, size_t k) {
  OutlineHits hits;
  const std::optional<Rigid3> rig_from_object = scene.BodyPose(0, map.objects[k].name);
  EXPECT_TRUE(rig_from_object.has_value()) << map.objects[k].name;
  if (!rig_from_object) return hits;
  for (const MapMarker& m : map.objects[k].markers) {
    const double e = 1.25 * 0.5 * m.size;
    for (const Eigen::Vector3d& mid : {Eigen::Vector3d(0, e, 0), Eigen::Vector3d(e, 0, 0),
                                       Eigen::Vector3d(0, -e, 0), Eigen::Vector3d(-e, 0, 0)}) {
      Eigen::Vector2d px;
      if (!scene.ProjectRigPoint(0, *rig_from_object * (m.object_from_marker * mid), &px)) continue;
      ++hits.points;
      if (BodyPixelsNear(img, px, k, 3) > 0) ++hits.own;
      for (size_t j = 0; j < map.objects.size(); ++j)
        if (j != k && BodyPixelsNear(img, px, j, 3) > 0) {
          ++hits.other;
          break;
        }
    }
  }
  return hits;
}

}  // namespace mcmt::viz::testing
