// The one reader of LCM event logs for every mcmt program (mapper, tracker, viewer, eval, export): the
// format of lcm-logger, lcm-logplayer and LCM's file:// provider, read without LCM's own C reader so that
// a damaged file never crashes a program and damage is reported precisely (file, byte offset, event).
//
// An event on disk, all integers big-endian:
//   uint32 sync word 0xEDA1DA01 | int64 event number | int64 timestamp (us) | int32 channel length |
//   int32 payload length | channel bytes (no terminator) | payload bytes
// Logs may be concatenated (cat a.lcmlog b.lcmlog > c.lcmlog): event numbers are not checked.
// Every length is bounded by the bytes left in the file before anything is allocated.
#pragma once

#include <cstdint>
#include <cstdio>
#include <functional>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

namespace mcmt {

constexpr uint32_t kLcmSyncWord = 0xEDA1DA01u;
constexpr int kLcmMaxChannelLength = 255;  // LCM itself allows 63; accept what any writer could produce
constexpr size_t kLcmEventHeaderBytes = 4 + 8 + 8 + 4 + 4;
// Exit status of a program that read a damaged log to its end: its outputs hold everything readable,
// and the damage was reported (0: success, 1: error, 2: usage error).
constexpr int kExitDamagedLog = 3;

struct LogEvent {
  int64_t eventnum = 0;
  int64_t timestamp = 0;  // receive time, microseconds since the epoch
  std::string channel;
  std::vector<uint8_t> data;
  uint64_t offset = 0;  // byte offset of the event in its file (reader only)
};

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
//  - Resync: damage between or inside events is skipped up to the next valid event header;
//    skipped_bytes() and skipped_regions() say where. An event whose lengths run past the end of the
//    file is a cut tail only when no valid event follows it.
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
  uint64_t truncated_tail_offset() const { return truncated_tail_offset_; }
  uint64_t skipped_bytes() const { return skipped_bytes_; }
  // (offset, length) of each skipped region (resync mode).
  const std::vector<std::pair<uint64_t, uint64_t>>& skipped_regions() const { return skipped_regions_; }

 private:
  bool ReadExact(void* buffer, size_t size);  // false at EOF before size bytes
  [[noreturn]] void Fail(uint64_t offset, const std::string& what) const;
  // Seeks to the next plausible event header after `from`; false (and the rest skipped) if none.
  bool Resync(uint64_t from);
  // Is there a plausible event header at `offset`? (sync word and lengths within the file)
  bool PlausibleHeaderAt(uint64_t offset);
  bool CutTail(uint64_t start);  // records the bytes from `start` as a cut tail; returns false

  std::string path_;
  bool resync_;
  FILE* file_ = nullptr;
  uint64_t file_size_ = 0;
  uint64_t position_ = 0;
  int64_t events_read_ = 0;
  uint64_t truncated_tail_bytes_ = 0;
  uint64_t truncated_tail_offset_ = 0;
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

// What reading a whole log (every part, resync mode) found.
struct LogReadReport {
  std::vector<std::string> parts;
  uint64_t bytes = 0;  // size of all parts
  int64_t events = 0;  // whole events read
  uint64_t skipped_bytes = 0;
  uint64_t truncated_bytes = 0;
  // One line per damaged place, e.g. "s.lcmlog: byte 4096: 300 bytes skipped (not an event)" or
  // "s.lcmlog: byte 9000: the last event is cut short (120 bytes ignored)".
  std::vector<std::string> damage;
  bool damaged() const { return !damage.empty(); }
  // One line: "the log s.lcmlog is damaged: 300 bytes skipped in 1 place, last event cut short
  // (first: byte 4096); everything readable was used". Empty when not damaged.
  std::string Summary() const;
};

// Reads every event of every part of the log at `path` (see LogParts) in file order, skipping damage
// (resync mode), and calls fn for each; fn returns false to stop reading. Throws LogFormatError naming the
// file when it cannot be opened, or when it is not an LCM log at all (no event anywhere).
// The order in which a program reading a log takes its detections: capture time, then camera, seq and the
// message bytes, so that its results never depend on the order of the log's events (mapper and tracker).
inline std::tuple<const int64_t&, const std::string&, const int64_t&, const std::vector<uint8_t>&>
CaptureOrderKey(const int64_t& utime, const std::string& camera, const int64_t& seq,
                const std::vector<uint8_t>& bytes) {
  return {utime, camera, seq, bytes};
}

LogReadReport ForEachLogEvent(const std::string& path, const std::function<bool(const LogEvent&)>& fn);

}  // namespace mcmt
