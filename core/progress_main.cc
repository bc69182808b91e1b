// mcmt-progress: the progress of another process reading a file (its file offset, from /proc/PID/fdinfo)
// until that process ends, drawn by core/progress.h: a bar with rate and ETA on a terminal, a plain line
// every few seconds otherwise. scripts/mcmt-replay runs it beside lcm-logplayer, which prints nothing.
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

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

// Running, not ended (a zombie has ended: its parent has not collected it yet).
bool Alive(int pid) {
  if (::kill(pid, 0) != 0) return false;
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string id, name, state;
  stat >> id >> name >> state;  // the name has no spaces for the programs watched here
  return state != "Z";
}

}  // namespace

int main(int argc, char** argv) {
  return mcmt::RunMain("mcmt-progress", [&] {
    int pid = 0;
    std::string file, label;
    double period = 5.0;
    mcmt::ArgParser args("mcmt-progress",
                         "Shows how far process --pid has read --file (its file offset) until it ends.");
    args.AddInt("pid", &pid, "process to watch");
    args.AddString("file", &file, "the file it reads", true);
    args.AddString("label", &label, "text before the bar (default: the file's name)");
    args.AddDouble("period", &period, "seconds between lines when stderr is not a terminal");
    int code = 0;
    if (!args.Parse(argc, argv, &code)) return code;
    if (pid <= 0) throw std::invalid_argument("--pid: expected a process id");
    std::error_code ec;
    const fs::path path = fs::canonical(file, ec);
    if (ec) throw std::runtime_error(file + ": " + ec.message());
    const auto size = static_cast<long long>(fs::file_size(path));
    mcmt::Progress progress(label.empty() ? path.filename().string() : label, (size + 1023) / 1024, "kB",
                            mcmt::Progress::Mode::kAuto, period);
    long long last = 0;
    while (Alive(pid)) {
      const long long pos = FileOffset(pid, path);
      if (pos >= 0) last = pos;
      progress.Update(last / 1024);
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    progress.Update(last / 1024);
    progress.Finish();
    return 0;
  });
}
