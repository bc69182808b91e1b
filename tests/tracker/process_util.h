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

namespace mcmt {
namespace tracker_test {

// Are all these programs built in MCMT_BIN_DIR?
inline bool ProgramsBuilt(const std::vector<std::string>& names) {
  for (const auto& p : names)
    if (access((std::string(MCMT_BIN_DIR) + "/" + p).c_str(), X_OK) != 0) return false;
  return true;
}

inline std::string Slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

// Starts argv[0] with its stdout and stderr into output_path. Returns the pid.
inline pid_t Spawn(const std::vector<std::string>& argv, const std::string& output_path) {
  const pid_t pid = fork();
  if (pid == 0) {
    const int fd = open(output_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
      dup2(fd, 1);
      dup2(fd, 2);
      close(fd);
    }
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execv(args[0], args.data());
    _exit(127);
  }
  return pid;
}

// Waits for the process; returns its exit code (128 + signal if killed), or -1 after the timeout (then
// the process is killed).
inline int WaitExit(pid_t pid, std::chrono::milliseconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  int status = 0;
  while (std::chrono::steady_clock::now() < end) {
    const pid_t r = waitpid(pid, &status, WNOHANG);
    if (r == pid) return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  kill(pid, SIGKILL);
  waitpid(pid, &status, 0);
  return -1;
}

// Runs to completion; *output gets stdout+stderr.
inline int RunProgram(const std::vector<std::string>& argv, const std::string& output_path,
                      std::string* output,
                      std::chrono::milliseconds timeout = std::chrono::milliseconds(120000)) {
  const int code = WaitExit(Spawn(argv, output_path), timeout);
  if (output) *output = Slurp(output_path);
  return code;
}

// Waits until the file contains `needle` (or the timeout passes).
inline bool WaitForText(const std::string& path, const std::string& needle,
                        std::chrono::milliseconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < end) {
    if (Slurp(path).find(needle) != std::string::npos) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return false;
}

}  // namespace tracker_test
}  // namespace mcmt
