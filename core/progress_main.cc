// mcmt-progress: runs a command that reads a file and shows how far it has read it (its file offset, from
// /proc/PID/fdinfo), drawn by core/progress.h: a bar with rate and ETA on a terminal, a plain line every
// few seconds otherwise. Exits with the command's status. scripts/mcmt-replay runs lcm-logplayer (which
// prints nothing) under it:  mcmt-progress --file session.lcmlog -- lcm-logplayer session.lcmlog
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "core/cli.h"
#include "core/progress.h"

namespace {

namespace fs = std::filesystem;

// The offset of PID's descriptor open on `file`, -1 when none is (yet, or any more).
long long FileOffset(int pid, const fs::path& file) {
  std::error_code ec;
  const fs::path fd_dir = "/proc/" + std::to_string(pid) + "/fd";
  for (const auto& entry : fs::directory_iterator(fd_dir, ec)) {
    std::error_code link_ec;
    if (fs::read_symlink(entry.path(), link_ec) != file) continue;
    std::ifstream info("/proc/" + std::to_string(pid) + "/fdinfo/" + entry.path().filename().string());
    std::string key;
    long long pos = -1;
    while (info >> key)
      if (key == "pos:" && info >> pos) return pos;
  }
  return -1;
}

// Starts argv (execvp); returns its pid.
pid_t Start(const std::vector<std::string>& argv) {
  const pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
  if (pid == 0) {
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    ::execvp(args[0], args.data());
    std::fprintf(stderr, "mcmt-progress: error: cannot run %s: %s\n", args[0], std::strerror(errno));
    ::_exit(127);
  }
  return pid;
}

// Polls the child's offset in `path` until it ends; returns its exit status (128 + signal if killed).
int Watch(pid_t pid, const fs::path& path, mcmt::Progress* progress, long long size) {
  long long last = 0;
  for (;;) {
    int status = 0;
    if (::waitpid(pid, &status, WNOHANG) == pid) {
      const int code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      if (code == 0) last = size;  // it read the whole file
      progress->Update((last + 1023) / 1024);
      return code;
    }
    const long long pos = FileOffset(pid, path);
    if (pos >= 0) last = pos;
    progress->Update((last + 1023) / 1024);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
}

}  // namespace

int main(int argc, char** argv) {
  return mcmt::RunMain("mcmt-progress", [&] {
    int own = argc;  // our options end at "--"; the command follows
    for (int i = 1; i < argc; ++i)
      if (std::string(argv[i]) == "--") {
        own = i;
        break;
      }
    std::string file, label;
    double period = 5.0;
    mcmt::ArgParser args(
        "mcmt-progress",
        "Runs COMMAND (after --) and shows how far it has read --file; exits with its status.");
    args.AddString("file", &file, "the file the command reads", true);
    args.AddString("label", &label, "text before the bar (default: the file's name)");
    args.AddDouble("period", &period, "seconds between lines when stderr is not a terminal");
    args.AddEpilog("example: mcmt-progress --file session.lcmlog -- lcm-logplayer session.lcmlog\n");
    int code = 0;
    if (!args.Parse(own, argv, &code)) return code;
    if (own + 1 >= argc) throw std::invalid_argument("no command after --");
    std::error_code ec;
    const fs::path path = fs::canonical(file, ec);
    if (ec) throw std::runtime_error(file + ": " + ec.message());
    const auto size = static_cast<long long>(fs::file_size(path));
    mcmt::Progress progress(label.empty() ? path.filename().string() : label, (size + 1023) / 1024, "kB",
                            mcmt::Progress::Mode::kAuto, period);
    const int status =
        Watch(Start(std::vector<std::string>(argv + own + 1, argv + argc)), path, &progress, size);
    progress.Finish();
    return status;
  });
}
