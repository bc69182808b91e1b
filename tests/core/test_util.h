// Helpers shared by the core tests: a test camera, a temporary folder removed at the end, file writing.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "core/camera.h"

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

class TempDir {
 public:
  TempDir() {
    std::string pattern = (std::filesystem::temp_directory_path() / "mcmt_core_test_XXXXXX").string();
    char* made = ::mkdtemp(pattern.data());
    if (!made) throw std::runtime_error("mkdtemp failed");
    path_ = made;
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::string& path() const { return path_; }
  std::string File(const std::string& name) const { return path_ + "/" + name; }
  std::string Write(const std::string& name, const std::string& content) const {
    const std::string p = File(name);
    std::filesystem::create_directories(std::filesystem::path(p).parent_path());
    std::ofstream out(p, std::ios::binary);
    out << content;
    return p;
  }

 private:
  std::string path_;
};

}  // namespace testing_util
}  // namespace mcmt
