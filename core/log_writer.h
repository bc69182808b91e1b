// LCM event logs: the one writer (mcmt-logger, mcmt-import, the CSV import). Reading is core/log_reader.h.
#pragma once

#include <cstdint>
#include <string>

#include "core/log_reader.h"

namespace mcmt {

// An LCM time (microseconds since the epoch) as UTC ISO 8601 with microseconds, e.g.
// "2026-11-22T06:24:33.123456Z"; "" for utime <= 0 (no time).
std::string IsoTime(int64_t utime);

// Writes events to a new file, buffering whole events in memory and handing them to the kernel with
// write(2) only as whole events (at Flush() or when the buffer exceeds its limit). A process killed
// at any moment leaves a file that ends on an event boundary (up to the last write) -- unless the
// kernel itself stops mid-write (power loss), which Sync() (fdatasync) guards against.
class EventLogWriter {
 public:
  // Creates `path` exclusively (O_CREAT | O_EXCL): never overwrites. Throws naming the path.
  explicit EventLogWriter(const std::string& path, size_t buffer_limit = 4 << 20);
  ~EventLogWriter();  // Close()s; errors are swallowed there (call Close() to see them)
  EventLogWriter(const EventLogWriter&) = delete;
  EventLogWriter& operator=(const EventLogWriter&) = delete;

  void Write(int64_t timestamp, const std::string& channel, const void* data, size_t size);
  void Flush();  // buffered events -> kernel
  void Sync();   // Flush + fdatasync
  void Close();  // Sync + close

  const std::string& path() const { return path_; }
  int64_t events() const { return next_eventnum_; }
  uint64_t bytes() const { return bytes_; }  // written or buffered

 private:
  std::string path_;
  int fd_ = -1;
  size_t buffer_limit_;
  std::string buffer_;
  int64_t next_eventnum_ = 0;
  uint64_t bytes_ = 0;
};

}  // namespace mcmt
