// The one process runner of the tests: a program as a child process (argv, no shell) with stdout and
// stderr into files, waited for with a time limit; or a shell command line run to completion with its
// output captured.
//
//   mcmt::test::Child mapper({Bin("mcmt-mapper"), "--config", rig, "--out", out}, dir / "out.txt");
//   mapper.Signal(SIGINT);
//   EXPECT_EQ(mapper.Wait(30), 0);
//   EXPECT_EQ(RunProgram({Bin("mcmt-tracker"), "--help"}, dir / "help.txt", &output), 0);
//   const ProcessResult r = RunCommand(Bin("mcmt-eval") + " --json ...");   // r.exit_code, r.output
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace mcmt::test {

inline std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// A built program (MCMT_BIN_DIR, set by mcmt_add_test).
inline std::string Bin(const std::string& name) { return std::string(MCMT_BIN_DIR) + "/" + name; }

// Whether every one of these programs is built (an executable Bin(name)).
inline bool ProgramsBuilt(const std::vector<std::string>& names) {
  for (const std::string& name : names)
    if (::access(Bin(name).c_str(), X_OK) != 0) return false;
  return true;
}

// Waits for a child by pid: its exit code, 128 + signal when killed by one, or -1 on timeout (the child is
// then killed).
inline int WaitForExit(pid_t pid, double timeout_s) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  int status = 0;
  while (::waitpid(pid, &status, WNOHANG) != pid) {
    if (std::chrono::steady_clock::now() > end) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, nullptr, 0);
      return -1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return -2;
}

// A child process running argv[0] with stdout into out_path and stderr into err_path (both into out_path
// when err_path is empty). Killed (SIGKILL) at destruction if still running.
class Child {
 public:
  Child() = default;
  Child(const std::vector<std::string>& argv, const std::string& out_path, const std::string& err_path = "") {
    pid_ = ::fork();
    if (pid_ == 0) {
      const int out = ::open(out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      const int err = err_path.empty() ? out : ::open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      if (out >= 0) ::dup2(out, 1);
      if (err >= 0) ::dup2(err, 2);
      std::vector<char*> args;
      for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
      args.push_back(nullptr);
      ::execv(args[0], args.data());
      ::_exit(127);
    }
  }
  ~Child() {
    if (pid_ > 0 && !done_) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;

  bool Running() {
    if (done_ || pid_ <= 0) return false;
    int status = 0;
    if (::waitpid(pid_, &status, WNOHANG) == pid_) {
      done_ = true;
      status_ = status;
      return false;
    }
    return true;
  }
  // Exit code, 128 + signal when killed by one, or -1 on timeout (the child is then killed).
  int Wait(double timeout_s) {
    if (!done_ && pid_ > 0) {
      done_ = true;
      return WaitForExit(pid_, timeout_s);
    }
    if (WIFEXITED(status_)) return WEXITSTATUS(status_);
    if (WIFSIGNALED(status_)) return 128 + WTERMSIG(status_);
    return -2;
  }
  void Signal(int sig) {
    if (pid_ > 0 && !done_) ::kill(pid_, sig);
  }
  pid_t pid() const { return pid_; }
  // Forget the child (its owner waits for it by pid).
  pid_t Release() {
    done_ = true;
    return pid_;
  }

 private:
  pid_t pid_ = -1;
  bool done_ = false;
  int status_ = 0;
};

// Runs argv[0] to completion with stdout and stderr into output_path: its exit code as Child::Wait gives it
// (-1 after timeout_s, the child then killed); *output (optional) gets what it wrote.
inline int RunProgram(const std::vector<std::string>& argv, const std::string& output_path,
                      std::string* output = nullptr, double timeout_s = 120) {
  Child child(argv, output_path);
  const int code = child.Wait(timeout_s);
  if (output) *output = ReadText(output_path);
  return code;
}

struct ProcessResult {
  int exit_code = -1;  // -1: not run or not exited normally
  std::string output;  // stdout + stderr
};

// Runs a shell command line (stderr joined to stdout) to completion; timeout_s > 0 wraps it in coreutils'
// timeout.
inline ProcessResult RunCommand(const std::string& command, int timeout_s = 0) {
  const std::string full =
      (timeout_s > 0 ? "timeout -k 5 " + std::to_string(timeout_s) + " " : std::string()) + command + " 2>&1";
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

// Waits until the file contains `needle` (false after the timeout).
inline bool WaitForText(const std::string& path, const std::string& needle, double timeout_s) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (std::chrono::steady_clock::now() < end) {
    if (ReadText(path).find(needle) != std::string::npos) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return false;
}

}  // namespace mcmt::test
