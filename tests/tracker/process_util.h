// Running the mcmt programs as separate processes in tests.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "tests/support/process.h"

namespace mcmt {
namespace tracker_test {

// Are all these programs built in MCMT_BIN_DIR?
inline bool ProgramsBuilt(const std::vector<std::string>& names) {
  for (const auto& p : names)
    if (access((std::string(MCMT_BIN_DIR) + "/" + p).c_str(), X_OK) != 0) return false;
  return true;
}

// Starts argv[0] with its stdout and stderr into output_path. Returns the pid.
inline pid_t Spawn(const std::vector<std::string>& argv, const std::string& output_path) {
  return mcmt::test::Child(argv, output_path).Release();
}

// Waits for the process; returns its exit code (128 + signal if killed), or -1 after the timeout (then
// the process is killed).
inline int WaitExit(pid_t pid, std::chrono::milliseconds timeout) {
  return mcmt::test::WaitForExit(pid, timeout.count() * 1e-3);
}

// Runs to completion; *output gets stdout+stderr.
inline int RunProgram(const std::vector<std::string>& argv, const std::string& output_path,
                      std::string* output,
                      std::chrono::milliseconds timeout = std::chrono::milliseconds(120000)) {
  const int code = WaitExit(Spawn(argv, output_path), timeout);
  if (output) *output = mcmt::test::ReadText(output_path);
  return code;
}

// Waits until the file contains `needle` (or the timeout passes).
inline bool WaitForText(const std::string& path, const std::string& needle,
                        std::chrono::milliseconds timeout) {
  return mcmt::test::WaitForText(path, needle, timeout.count() * 1e-3);
}

}  // namespace tracker_test
}  // namespace mcmt
