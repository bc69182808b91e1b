#include "mapper/out_folder.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "core/files.h"

namespace mcmt {
namespace {

namespace fs = std::filesystem;

constexpr char kSessionFile[] = ".mcmt-session";

std::string Recorded(const fs::path& dir) {
  std::ifstream in(dir / kSessionFile);
  std::string line;
  std::getline(in, line);
  return line;
}

}  // namespace

std::string MapperSession(const std::string& log) {
  if (log.empty()) return "live";
  std::error_code ec;
  const fs::path abs = fs::weakly_canonical(fs::absolute(log), ec);
  return "log " + (ec ? log : abs.string());
}

void CheckOutputFolder(const std::string& outdir) {
  std::error_code ec;
  fs::create_directories(outdir, ec);
  if (ec || !fs::is_directory(outdir))
    throw std::runtime_error("--out " + outdir + ": cannot create the output folder" +
                             (ec ? ": " + ec.message() : std::string(": not a folder")));
  const std::string probe = (fs::path(outdir) / (".mcmt-probe.tmp." + std::to_string(::getpid()))).string();
  const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw std::runtime_error("--out " + outdir + ": cannot write there: " + std::strerror(errno));
  ::close(fd);
  ::unlink(probe.c_str());
}

void CheckOutFolder(const std::string& outdir, const std::string& session, bool force) {
  const fs::path dir(outdir);
  std::string found;
  for (const char* name : {"map.yaml", "report.json", "trajectory.csv"}) {
    std::error_code ec;
    if (fs::exists(dir / name, ec)) {
      found = name;
      break;
    }
  }
  if (found.empty() || force) return;
  const std::string recorded = Recorded(dir);
  if (session != "live" && recorded == session) return;  // the same log mapped again
  throw std::runtime_error("--out " + outdir + " holds the results of another session (" + found + ", from " +
                           (recorded.empty() ? std::string("an unrecorded input") : recorded) +
                           "): choose another folder, or give --force to overwrite them");
}

void RecordSession(const std::string& outdir, const std::string& session) {
  WriteFileAtomic((fs::path(outdir) / kSessionFile).string(), session + "\n");
}

}  // namespace mcmt
