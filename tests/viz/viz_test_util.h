// A known rig for the viewer tests: cameras on a circle looking at a cube with markers on five faces
// that moves along a circle, expressed in the reference camera's frame as the mapper would.
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

namespace mcmt::viz::testing {

// Camera at `eye` looking at `target` (world z up), OpenCV axes: x right, y down, z forward.
inline Rigid3 WorldFromCamLookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target) {
  const Eigen::Vector3d z = (target - eye).normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Rigid3 t = Rigid3::Identity();
  t.linear().col(0) = x;
  t.linear().col(1) = y;
  t.linear().col(2) = z;
  t.translation() = eye;
  return t;
}

inline CameraModel TestCameraModel() {
  CameraModel m;
  m.width = 640;
  m.height = 480;
  m.fx = m.fy = 500;
  m.cx = 319.5;
  m.cy = 239.5;
  return m;
}

struct TestRig {
  RigMap map;
  std::vector<TrajectoryRow> trajectory;
  Rigid3 world_from_rig = Rigid3::Identity();
};

// num_cameras cameras on a circle of radius 2 m, 1.2 m high, looking at the origin; a 0.12 m cube
// (markers 0.09 m, ids 0..4, DICT_4X4_50) moving on a circle of radius 0.3 m for `frames` frames.
inline TestRig MakeTestRig(int num_cameras = 4, int frames = 12, double camera_rms_step = 0.4) {
  TestRig rig;
  std::vector<Rigid3> world_from_cam;
  for (int i = 0; i < num_cameras; ++i) {
    const double a = 2.0 * M_PI * i / num_cameras + 0.3;
    world_from_cam.push_back(WorldFromCamLookAt(Eigen::Vector3d(2.0 * std::cos(a), 2.0 * std::sin(a), 1.2),
                                                Eigen::Vector3d(0, 0, 0.1)));
  }
  const Rigid3 rig_from_world = Inverse(world_from_cam[0]);
  rig.world_from_rig = world_from_cam[0];
  rig.map.dictionary = "DICT_4X4_50";
  rig.map.reference_camera = "cam0";
  rig.map.reference_marker = 0;
  for (int i = 0; i < num_cameras; ++i) {
    MapCamera c;
    c.name = "cam" + std::to_string(i);
    c.model = TestCameraModel();
    c.rig_from_cam = Normalized(rig_from_world * world_from_cam[i]);
    c.observations = 100;
    c.rms_px = 0.2 + camera_rms_step * i;
    c.max_px = 2 * c.rms_px;
    rig.map.cameras.push_back(c);
  }
  // Cube faces: outward normals; a marker's x axis on the face, y = z x x.
  const double half = 0.06;
  const std::array<Eigen::Vector3d, 5> normals = {Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(1, 0, 0),
                                                  Eigen::Vector3d(0, 1, 0), Eigen::Vector3d(-1, 0, 0),
                                                  Eigen::Vector3d(0, -1, 0)};
  std::vector<Rigid3> cube_from_marker;
  for (const auto& n : normals) {
    Eigen::Vector3d x = std::abs(n.z()) > 0.5 ? Eigen::Vector3d(1, 0, 0) : Eigen::Vector3d(0, 0, 1).cross(n);
    x.normalize();
    const Eigen::Vector3d y = n.cross(x);
    Rigid3 t = Rigid3::Identity();
    t.linear().col(0) = x;
    t.linear().col(1) = y;
    t.linear().col(2) = n;
    t.translation() = half * n;
    cube_from_marker.push_back(t);
  }
  const Rigid3 object_from_cube = Inverse(cube_from_marker[0]);
  for (int id = 0; id < 5; ++id) {
    MapMarker m;
    m.id = id;
    m.size = 0.09;
    m.object_from_marker = Normalized(object_from_cube * cube_from_marker[id]);
    m.observations = 50;
    m.rms_px = 0.1 + 0.3 * id;
    m.max_px = 2 * m.rms_px;
    rig.map.markers.push_back(m);
  }
  rig.map.rms_px = 0.5;
  rig.map.num_frames = frames;
  rig.map.num_observations = frames * 8;
  for (int k = 0; k < frames; ++k) {
    const double a = 2.0 * M_PI * k / std::max(frames, 1);
    Rigid3 world_from_cube = Rigid3::Identity();
    world_from_cube.linear() = Eigen::AngleAxisd(0.6 * a, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    world_from_cube.translation() = Eigen::Vector3d(0.3 * std::cos(a), 0.3 * std::sin(a), 0.15);
    TrajectoryRow row;
    row.utime = 1000000 + 33333 * k;
    row.seq = k;
    row.rig_from_object = Normalized(rig_from_world * world_from_cube * Inverse(object_from_cube));
    row.rms_px = 0.4;
    row.cameras = num_cameras;
    row.markers = 3;
    rig.trajectory.push_back(row);
  }
  return rig;
}

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
