#include "tests/support/udpm.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>

namespace mcmt::test {

std::string UdpmLockPath(int port) {
  return (std::filesystem::temp_directory_path() / ("mcmt_udpm_" + std::to_string(port) + ".lock")).string();
}

int UdpmPort(int base) {
  static std::mutex mutex;
  static std::map<int, int> claimed;  // base -> port; the lock files stay open (and locked) until exit
  const std::lock_guard<std::mutex> lock(mutex);
  if (const auto it = claimed.find(base); it != claimed.end()) return it->second;
  for (int slot = 0; slot < kUdpmSlots; ++slot) {
    const int port = base + slot * kUdpmSlotStride;
    const std::string path = UdpmLockPath(port);
    const int fd = ::open(path.c_str(), O_RDWR | O_CREAT, 0666);
    if (fd < 0)
      throw std::runtime_error(path + ": cannot open the udpm port's lock file: " + std::strerror(errno));
    if (::flock(fd, LOCK_EX | LOCK_NB) == 0) return claimed[base] = port;
    ::close(fd);
  }
  throw std::runtime_error("udpm port " + std::to_string(base) + ": every slot up to " +
                           std::to_string(base + (kUdpmSlots - 1) * kUdpmSlotStride) +
                           " is held by another test run (" + UdpmLockPath(base) + ", ...)");
}

std::string UdpmUrl(int base) { return "udpm://239.255.76.67:" + std::to_string(UdpmPort(base)) + "?ttl=0"; }

}  // namespace mcmt::test
