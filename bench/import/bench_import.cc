// The real TagSLAM sessions (../shared/data/tagslam_test) as a user runs them: mcmt-import, mcmt-mapper,
// mcmt-report, each its own process: wall time each, and the mapper process's peak RSS.
// TagSLAM's own figure for test_6 (its README: "runs 500 s for optimization") printed beside.
//   bench_import [--sessions test_2,test_8,test_6]
// Prints a markdown table.
#include <sys/resource.h>
#include <sys/wait.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "core/files.h"
#include "tests/support/process.h"

namespace {

const std::string kBin = MCMT_BIN_DIR "/";
const std::string kData = MCMT_SOURCE_DIR "/../shared/data/tagslam_test/";

struct Run {
  double seconds = 0.0;
  double peak_mib = 0.0;
};

// Runs a program to completion (its output into `log`); wall time and the process's own peak RSS.
Run Timed(const std::vector<std::string>& argv, const std::string& log) {
  const auto start = std::chrono::steady_clock::now();
  const pid_t pid = mcmt::test::Child(argv, log).Release();
  int status = 0;
  rusage usage{};
  if (wait4(pid, &status, 0, &usage) != pid || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::fprintf(stderr, "bench_import: %s failed:\n%s\n", argv[0].c_str(),
                 mcmt::test::ReadText(log).c_str());
    std::exit(1);
  }
  return {std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
          usage.ru_maxrss / 1024.0};
}

std::string Field(const std::string& json, const std::string& key) {
  const size_t at = json.find("\"" + key + "\": ");
  if (at == std::string::npos) return "?";
  const size_t from = at + key.size() + 4;
  return json.substr(from, json.find_first_of(",}\n", from) - from);
}

}  // namespace

int main(int argc, char** argv) {
  std::string list = "test_2,test_8,test_6";
  for (int i = 1; i + 1 < argc; ++i)
    if (std::string(argv[i]) == "--sessions") list = argv[i + 1];
  std::printf("## mcmt-import on the TagSLAM sessions (real detections; processes, 2 cores)\n\n");
  std::printf(
      "| session | frames | observations | import (s) | mapping (s) | mapper peak RSS (MiB) | final rms (px) "
      "| report (s) | TagSLAM (its README) |\n|---|---|---|---|---|---|---|---|---|\n");
  std::stringstream names(list);
  std::string name;
  while (std::getline(names, name, ',')) {
    const std::string src = kData + name + "/";
    if (!std::filesystem::exists(src + "tag_detections.bag.bz2")) {
      std::printf("| %s | (data absent) |\n", name.c_str());
      continue;
    }
    const std::string dir = std::filesystem::temp_directory_path() / ("mcmt_bench_import_" + name);
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    const Run t_import = Timed({kBin + "mcmt-import", "--rosbag", src + "tag_detections.bag.bz2", "--cameras",
                                src + "cameras.yaml", "--out", dir + "/session"},
                               dir + "/import.txt");
    const Run t_map = Timed({kBin + "mcmt-mapper", "--config", dir + "/session/rig.yaml", "--log",
                             dir + "/session/session.lcmlog", "--out", dir + "/map"},
                            dir + "/mapper.txt");
    const Run t_report = Timed({kBin + "mcmt-report", dir + "/map"}, dir + "/report.txt");
    const std::string report = mcmt::ReadFile(dir + "/map/report.json");
    std::printf("| %s | %s | %s | %.2f | %.1f | %.0f | %.3f | %.1f | %s |\n", name.c_str(),
                Field(report, "frames_used").c_str(), Field(report, "observations_used").c_str(),
                t_import.seconds, t_map.seconds, t_map.peak_mib, std::stod(Field(report, "final_rms_px")),
                t_report.seconds, name == "test_6" ? "500 s optimisation, ~64000 factors" : "");
    std::fflush(stdout);
    std::filesystem::remove_all(dir);
  }
  return 0;
}
