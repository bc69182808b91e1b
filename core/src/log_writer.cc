#include "core/log_writer.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <ctime>
#include <sstream>

namespace mcmt {

// ---------------------------------------------------------------------------------------------------------
// Writer

EventLogWriter::EventLogWriter(const std::string& path, size_t buffer_limit)
    : path_(path), buffer_limit_(buffer_limit) {
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd_ < 0) {
    if (errno == EEXIST) throw std::runtime_error(path + ": exists; refusing to overwrite a recording");
    throw std::runtime_error(path + ": cannot create: " + std::strerror(errno));
  }
  buffer_.reserve(buffer_limit_ + (64 << 10));
  // Make the new name itself durable (a power cut right after creation must not lose the file).
  const size_t slash = path.find_last_of('/');
  const std::string dir = slash == std::string::npos ? "." : (slash == 0 ? "/" : path.substr(0, slash));
  const int dir_fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir_fd >= 0) {
    ::fsync(dir_fd);
    ::close(dir_fd);
  }
}

EventLogWriter::~EventLogWriter() {
  try {
    Close();
  } catch (...) {
  }
}

void EventLogWriter::Write(int64_t timestamp, const std::string& channel, const void* data, size_t size) {
  if (fd_ < 0) throw std::runtime_error(path_ + ": write after close");
  const size_t before = buffer_.size();
  AppendEncodedEvent(next_eventnum_++, timestamp, channel, data, size, &buffer_);
  bytes_ += buffer_.size() - before;
  if (buffer_.size() >= buffer_limit_) Flush();
}

void EventLogWriter::Flush() {
  size_t done = 0;
  while (done < buffer_.size()) {
    ssize_t n = ::write(fd_, buffer_.data() + done, buffer_.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw std::runtime_error(path_ + ": write failed: " + std::strerror(errno));
    }
    done += static_cast<size_t>(n);
  }
  buffer_.clear();
}

void EventLogWriter::Sync() {
  if (fd_ < 0) return;
  Flush();
  if (::fdatasync(fd_) != 0 && errno != EINVAL && errno != EROFS)
    throw std::runtime_error(path_ + ": fdatasync failed: " + std::strerror(errno));
}

void EventLogWriter::Close() {
  if (fd_ < 0) return;
  Sync();
  int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0) throw std::runtime_error(path_ + ": close failed: " + std::strerror(errno));
}

std::string IsoTime(int64_t utime) {
  if (utime <= 0) return "";
  const std::time_t seconds = static_cast<std::time_t>(utime / 1000000);
  std::tm tm{};
  gmtime_r(&seconds, &tm);
  char text[64];
  std::strftime(text, sizeof(text), "%Y-%m-%dT%H:%M:%S", &tm);
  char full[96];
  std::snprintf(full, sizeof(full), "%s.%06lldZ", text, static_cast<long long>(utime % 1000000));
  return full;
}

}  // namespace mcmt
