// mcmt-logger's engine: records LCM channels into an LCM event log, durably, with a sidecar.
//
// Threads: the caller's thread runs LCM's handle() and only copies each message into a queue; a writer
// thread encodes events, writes them (whole events only, see EventLogWriter), flushes and fdatasyncs
// every flush_ms, rotates files and refreshes the sidecar. A slow disk therefore never stalls LCM's
// receive queue; if the backlog exceeds max_unwritten_mb, new messages are dropped and counted.
//
// Files (documented in docs/replay.md):
//  - no split: exactly `out` (e.g. session.lcmlog);
//  - --split-mb / --split-minutes: session.00.lcmlog, session.01.lcmlog, ... (every part holds whole events);
//  - sidecar: session.yaml (out with its extension replaced by .yaml), rewritten atomically at start,
//    every few seconds while recording (state: recording) and at the end (state: closed).
// Nothing is ever overwritten: when out, any of its parts or the sidecar exists, construction throws.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "core/config.h"
#include "core/log_writer.h"
#include "core/stop.h"

namespace mcmt {

struct LoggerOptions {
  std::string out;                   // log path (required)
  std::string channels = "MCMT_.*";  // LCM channel regex (anchored by LCM)
  std::string config_path;           // rig YAML copied into the sidecar, with its intrinsics (optional)
  std::string lcm_url;               // for the sidecar; a file:// URL ends the recording at the log's end
  double split_mb = 0.0;             // start a new part when the current one reaches this size (1 MB = 1e6 B)
  double split_minutes = 0.0;        // ... or has been open this long; 0: never
  int flush_ms = 200;                // write + fdatasync interval
  bool fsync = true;                 // fdatasync at every flush (survives power loss, not only a crash)
  double max_seconds = 0.0;          // stop after this long (wall time); 0: until signalled
  long long max_messages = 0;        // stop after this many messages recorded; 0: no limit
  int queue_capacity = 100000;       // LCM subscription queue (messages); LCM's default is 30
  double max_unwritten_mb = 512.0;   // writer backlog above which messages are dropped (counted)
  double status_seconds = 1.0;       // status line interval on stderr; 0: none
  double sidecar_seconds = 2.0;      // sidecar refresh interval while recording

  void Validate() const;  // throws std::invalid_argument naming the option
};

// Reads the optional `logger:` section of a rig YAML (keys declared in LoggerOptionTable). Unknown keys and
// bad values throw OptionError naming file and key.
void LoadLoggerOptions(const YamlSection& section, LoggerOptions* options);
template <class T>
class OptionTable;
const OptionTable<LoggerOptions>& LoggerOptionTable();

// A udpm URL (empty: $LCM_DEFAULT_URL, else LCM's default udpm URL) with recv_buf_size=bytes added when it
// has none: the kernel's default socket buffer (~200 kB) overflows within milliseconds at image rates.
// Other providers (file://, memq://, tcpq://) and bytes <= 0 leave the URL unchanged.
std::string WithReceiveBuffer(const std::string& url, long long bytes);
// net.core.rmem_max (the kernel's cap on recv_buf_size), -1 if unknown.
long long KernelReceiveBufferMax();

// "dir/session.lcmlog" -> "dir/session.yaml"; "x" -> "x.yaml".
std::string SidecarPath(const std::string& log_path);

struct ChannelStats {
  int64_t messages = 0;
  int64_t bytes = 0;  // payload bytes
};

// Per camera (from detections_t on MCMT_DETECTIONS_*): frames seen and frames missing between them.
struct SeqStats {
  int64_t frames = 0;
  int64_t first_seq = -1, last_seq = -1;
  int64_t gaps = 0;         // places where seq jumped forward by more than one
  int64_t missing = 0;      // frames missing in those jumps: lost between detector and log
  int64_t restarts = 0;     // seq went backwards (detector restarted) or repeated
  int64_t undecodable = 0;  // messages on the channel that are not detections_t
};

struct PartInfo {
  std::string path;
  int64_t events = 0;
  uint64_t bytes = 0;
  int64_t first_timestamp = 0, last_timestamp = 0;
};

struct SessionStats {
  int64_t start_utime = 0, end_utime = 0;
  int64_t received = 0;         // handed over by LCM
  int64_t written = 0;          // events in the log
  uint64_t bytes_written = 0;   // file bytes (headers included)
  int64_t dropped_backlog = 0;  // dropped because the writer backlog exceeded max_unwritten_mb
  std::map<std::string, ChannelStats> channels;
  std::map<std::string, SeqStats> cameras;  // by camera name
  std::vector<PartInfo> parts;
  int64_t Missing() const;  // sum of cameras' missing frames
};

class SessionLogger {
 public:
  // Checks the options, loads the config (if any), creates the first file and the sidecar, subscribes.
  // Throws (one line, naming the file or option) when anything is wrong.
  SessionLogger(lcm::LCM& lcm, LoggerOptions options);
  ~SessionLogger();

  // Handles LCM traffic until *stop becomes true, max_seconds pass or max_messages were recorded; then
  // drains the queue, closes the log and writes the final sidecar. Returns the final statistics.
  SessionStats Run(const StopToken& stop);

  const LoggerOptions& options() const { return options_; }
  std::string sidecar_path() const { return SidecarPath(options_.out); }
  std::string current_part() const;

 private:
  struct Pending {
    int64_t timestamp;
    std::string channel;
    std::vector<uint8_t> data;
  };
  void OnMessage(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void WriterLoop();
  void OpenPart();                      // writer thread (and constructor)
  void ClosePart();                     // writer thread
  void Record(const Pending& message);  // writer thread
  void WriteSidecar(bool final_state);
  std::string StatusLine(double rate) const;  // caller holds mutex_

  lcm::LCM& lcm_;
  LoggerOptions options_;
  bool split_ = false;
  std::string config_text_;
  std::vector<std::pair<std::string, std::string>> intrinsics_texts_;  // (path as named, text)
  lcm::Subscription* subscription_ = nullptr;

  std::mutex mutex_;  // guards queue_, queued_bytes_, stats_, writer_
  std::condition_variable wake_;
  std::deque<Pending> queue_;
  size_t queued_bytes_ = 0;
  bool closing_ = false;
  SessionStats stats_;
  std::unique_ptr<EventLogWriter> writer_;
  int next_part_ = 0;
  int64_t part_opened_us_ = 0;
  std::thread writer_thread_;
  std::string writer_error_;
};

}  // namespace mcmt
