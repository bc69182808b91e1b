// The one temporary-folder helper of the tests: a fresh folder under the system temp dir
// (mcmt_<tag>_<random>), removed with everything in it at destruction unless MCMT_KEEP_TEST_DIRS is set
// (then its path is printed, to look at what a failing test wrote).
//
//   mcmt::test::TempDir dir("mapper_cli");
//   const std::string rig = dir.Write("rig.yaml", text);   // dir / "rig.yaml", parents made
#pragma once

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

namespace mcmt::test {

// A fresh, unique folder (mkdtemp) whose path is returned; the caller removes it (or not).
inline std::string MakeTempDir(const std::string& tag) {
  const std::string pattern = (std::filesystem::temp_directory_path() / ("mcmt_" + tag + "_XXXXXX")).string();
  std::vector<char> buf(pattern.begin(), pattern.end());
  buf.push_back('\0');
  if (!::mkdtemp(buf.data())) throw std::runtime_error("mkdtemp failed for " + pattern);
  return buf.data();
}

class TempDir {
 public:
  explicit TempDir(const std::string& tag = "test") : path_(MakeTempDir(tag)) {}
  ~TempDir() {
    if (std::getenv("MCMT_KEEP_TEST_DIRS")) {
      std::fprintf(stderr, "kept %s\n", path_.c_str());
      return;
    }
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::string& path() const { return path_; }
  const std::string& str() const { return path_; }
  std::string File(const std::string& name) const { return path_ + "/" + name; }
  std::string operator/(const std::string& name) const { return File(name); }
  // Writes `content` to `name` (parent folders made); returns the path.
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

}  // namespace mcmt::test
