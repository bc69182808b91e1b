// LCM event logs (the format of lcm-logger, lcm-logplayer and LCM's file:// provider), read and written
// without LCM's own C reader so that damage is reported precisely (file, byte offset, event number).
//
// An event on disk, all integers big-endian:
//   uint32 sync word 0xEDA1DA01 | int64 event number | int64 timestamp (us) | int32 channel length |
//   int32 payload length | channel bytes (no terminator) | payload bytes
// Logs may be concatenated (cat a.lcmlog b.lcmlog > c.lcmlog): event numbers are not checked.
#pragma once

#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

namespace mcmt {

constexpr uint32_t kLcmSyncWord = 0xEDA1DA01u;
constexpr int kLcmMaxChannelLength = 255;  // LCM itself allows 63; accept what any writer could produce
constexpr size_t kLcmEventHeaderBytes = 4 + 8 + 8 + 4 + 4;

struct LogEvent {
  int64_t eventnum = 0;
  int64_t timestamp = 0;  // receive time, microseconds since the epoch
  std::string channel;
  std::vector<uint8_t> data;
  uint64_t offset = 0;  // byte offset of the event in its file (reader only)
};

// An LCM time (microseconds since the epoch) as UTC ISO 8601 with microseconds, e.g.
// "2026-11-22T06:24:33.123456Z"; "" for utime <= 0 (no time).
std::string IsoTime(int64_t utime);

class LogFormatError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Encodes one event (header + channel + payload) in the on-disk format.
void AppendEncodedEvent(int64_t eventnum, int64_t timestamp, const std::string& channel, const void* data,
                        size_t size, std::string* out);

// Sequential reader.
//  - Strict (default): anything that is not a whole event throws LogFormatError naming the file, the
//    byte offset and the event number, e.g.
//      "bad.lcmlog: byte 0: not an LCM event log (no sync word 0xEDA1DA01)".
//    One exception: a last event cut short by the end of the file (a crash while writing) ends the
//    log; truncated_tail_bytes() says how many bytes were ignored.
//  - Resync: garbage between events is skipped (like LCM's own reader, which scans for the next sync
//    word); skipped_bytes() and skipped_regions() say where.
class EventLogReader {
 public:
  explicit EventLogReader(const std::string& path, bool resync = false);
  ~EventLogReader();
  EventLogReader(const EventLogReader&) = delete;
  EventLogReader& operator=(const EventLogReader&) = delete;

  // Next event; false at the end of the log.
  bool Next(LogEvent* event);

  const std::string& path() const { return path_; }
  uint64_t file_size() const { return file_size_; }
  int64_t events_read() const { return events_read_; }
  uint64_t truncated_tail_bytes() const { return truncated_tail_bytes_; }
  uint64_t skipped_bytes() const { return skipped_bytes_; }
  // (offset, length) of each skipped region (resync mode).
  const std::vector<std::pair<uint64_t, uint64_t>>& skipped_regions() const { return skipped_regions_; }

 private:
  bool ReadExact(void* buffer, size_t size);  // false at EOF before size bytes
  [[noreturn]] void Fail(uint64_t offset, const std::string& what) const;
  bool Resync(uint64_t from);  // seeks to the next sync word after `from`; false if none

  std::string path_;
  bool resync_;
  FILE* file_ = nullptr;
  uint64_t file_size_ = 0;
  uint64_t position_ = 0;
  int64_t events_read_ = 0;
  uint64_t truncated_tail_bytes_ = 0;
  uint64_t skipped_bytes_ = 0;
  std::vector<std::pair<uint64_t, uint64_t>> skipped_regions_;
};

// Reads a whole log (strict).
std::vector<LogEvent> ReadEventLog(const std::string& path);

// The files of a log: `path` itself when it exists, else the parts a split recording wrote
// (stem.00.ext, stem.01.ext, ... for path stem.ext), in order. Throws naming the path when neither exists.
std::vector<std::string> LogParts(const std::string& path);
// Name of part `index` of a split recording: "dir/session.lcmlog", 3 -> "dir/session.03.lcmlog".
std::string LogPartName(const std::string& path, int index);

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
