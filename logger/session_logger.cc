#include "logger/session_logger.h"

#include <sys/stat.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <iostream>
#include <regex>
#include <sstream>
#include <stdexcept>

#include "core/files.h"
#include "core/lcm_util.h"
#include "core/options.h"
#include "mcmt/detections_t.hpp"

namespace mcmt {
namespace {

int64_t SteadyUs() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

int64_t WallUs() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

bool Exists(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0;
}

}  // namespace

void LoggerOptions::Validate() const {
  if (out.empty()) throw std::invalid_argument("--out: missing");
  if (channels.empty()) throw std::invalid_argument("--channels: empty regex");
  try {                          // LCM's own regex compiler crashes on some invalid ones: check first
    std::regex check(channels);  // ECMAScript: the closest to the PCRE syntax LCM uses
  } catch (const std::regex_error& e) {
    throw std::invalid_argument("--channels (or logger.channels): invalid regex '" + channels +
                                "': " + e.what());
  }
  if (!(split_mb >= 0) || !std::isfinite(split_mb)) throw std::invalid_argument("--split-mb: must be >= 0");
  if (split_mb > 0 && split_mb < 0.001)
    throw std::invalid_argument("--split-mb: must be at least 0.001 (1000 bytes)");
  if (!(split_minutes >= 0) || !std::isfinite(split_minutes))
    throw std::invalid_argument("--split-minutes: must be >= 0");
  if (flush_ms < 1 || flush_ms > 60000) throw std::invalid_argument("--flush-ms: must be in 1..60000");
  if (!(max_seconds >= 0)) throw std::invalid_argument("--max-seconds: must be >= 0");
  if (max_messages < 0) throw std::invalid_argument("--max-messages: must be >= 0");
  if (queue_capacity < 0) throw std::invalid_argument("queue_capacity: must be >= 0 (0: unlimited)");
  if (!(max_unwritten_mb > 0)) throw std::invalid_argument("max_unwritten_mb: must be > 0");
  if (!(status_seconds >= 0)) throw std::invalid_argument("--status-seconds: must be >= 0");
  if (!(sidecar_seconds > 0)) throw std::invalid_argument("sidecar_seconds: must be > 0");
  if (SidecarPath(out) == out)
    throw std::invalid_argument("--out: '" + out + "' would be its own sidecar; use .lcmlog");
}

const OptionTable<LoggerOptions>& LoggerOptionTable() {
  using O = LoggerOptions;
  static const OptionTable<O>* table =
      &(*new OptionTable<O>("logger"))
           .Add("channels", &O::channels, "LCM channel regex recorded (--channels overrides)", NotEmpty())
           .Add("split_mb", &O::split_mb, "MB", "start a new part at this size (0: never)", AtLeast(0))
           .Add("split_minutes", &O::split_minutes, "min", "start a new part after this long (0: never)",
                AtLeast(0))
           .Add("flush_ms", &O::flush_ms, "ms", "write + fdatasync interval", InRange(1, 60000))
           .Add("fsync", &O::fsync, "fdatasync at every flush (survives power loss, not only a crash)")
           .Add("queue_capacity", &O::queue_capacity, "messages", "LCM subscription queue (0: unlimited)",
                AtLeast(0))
           .Add("max_unwritten_mb", &O::max_unwritten_mb, "MB",
                "writer backlog above which messages are dropped", Above(0))
           .Add("status_seconds", &O::status_seconds, "s", "status line interval on stderr (0: none)",
                AtLeast(0));
  return *table;
}

void LoadLoggerOptions(const YamlSection& section, LoggerOptions* options) {
  LoggerOptionTable().Load(section, options);
}

std::string WithReceiveBuffer(const std::string& url, long long bytes) {
  std::string u = url;
  if (u.empty()) {
    const char* env = std::getenv("LCM_DEFAULT_URL");
    u = env && *env ? env : "udpm://239.255.76.67:7667?ttl=0";
  }
  if (bytes <= 0 || u.rfind("udpm://", 0) != 0 || u.find("recv_buf_size=") != std::string::npos) return url;
  return u + (u.find('?') == std::string::npos ? "?" : "&") + "recv_buf_size=" + std::to_string(bytes);
}

long long KernelReceiveBufferMax() {
  FILE* f = std::fopen("/proc/sys/net/core/rmem_max", "r");
  if (!f) return -1;
  long long v = -1;
  if (std::fscanf(f, "%lld", &v) != 1) v = -1;
  std::fclose(f);
  return v;
}

std::string SidecarPath(const std::string& log_path) {
  const size_t slash = log_path.find_last_of('/');
  const size_t dot = log_path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash) || dot == slash + 1)
    return log_path + ".yaml";
  return log_path.substr(0, dot) + ".yaml";
}

int64_t SessionStats::Missing() const {
  int64_t n = 0;
  for (const auto& [name, s] : cameras) n += s.missing;
  return n;
}

SessionLogger::SessionLogger(lcm::LCM& lcm, LoggerOptions options) : lcm_(lcm), options_(std::move(options)) {
  options_.Validate();
  split_ = options_.split_mb > 0 || options_.split_minutes > 0;
  // Refuse to touch an existing recording: the log, any of its parts, the sidecar.
  const std::string sidecar = SidecarPath(options_.out);
  if (Exists(options_.out))
    throw std::runtime_error(options_.out + ": exists; refusing to overwrite a recording");
  if (Exists(LogPartName(options_.out, 0)))
    throw std::runtime_error(LogPartName(options_.out, 0) + ": exists; refusing to overwrite a recording");
  if (Exists(sidecar))
    throw std::runtime_error(sidecar + ": exists; refusing to overwrite a session sidecar");

  if (!options_.config_path.empty()) {
    RigConfig rig = LoadRigConfig(options_.config_path);  // validates; throws naming file and key
    config_text_ = ReadFile(options_.config_path);
    const YAML::Node cameras = rig.root["cameras"];
    for (size_t i = 0; i < rig.cameras.size(); ++i) {
      std::string named = rig.cameras[i].intrinsics_path;
      if (cameras && cameras.IsSequence() && i < cameras.size() && cameras[i]["intrinsics"])
        named = cameras[i]["intrinsics"].as<std::string>();
      intrinsics_texts_.push_back({named, ReadFile(rig.cameras[i].intrinsics_path)});
    }
  }

  // Subscribe first (a regex LCM refuses leaves no file behind), then create the log, then the sidecar:
  // a sidecar on disk means the logger is listening. No message is handled before Run().
  subscription_ = lcm_.subscribe(options_.channels, &SessionLogger::OnMessage, this);
  if (!subscription_)
    throw std::runtime_error("--channels: LCM refused the regex '" + options_.channels + "'");
  stats_.start_utime = WallUs();
  try {
    subscription_->setQueueCapacity(options_.queue_capacity);
    OpenPart();
    WriteSidecar(false);
  } catch (...) {
    lcm_.unsubscribe(subscription_);
    subscription_ = nullptr;
    if (writer_) {
      writer_.reset();
      ::unlink(stats_.parts.back().path.c_str());
    }
    throw;
  }
}

SessionLogger::~SessionLogger() {
  if (writer_thread_.joinable()) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      closing_ = true;
    }
    wake_.notify_all();
    writer_thread_.join();
  }
  if (subscription_) lcm_.unsubscribe(subscription_);
}

std::string SessionLogger::current_part() const {
  return stats_.parts.empty() ? options_.out : stats_.parts.back().path;
}

void SessionLogger::OnMessage(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (closing_) return;
  if (options_.max_messages > 0 && stats_.received >= options_.max_messages) return;
  ++stats_.received;
  const size_t size = rbuf->data_size;
  if (static_cast<double>(queued_bytes_ + size) > options_.max_unwritten_mb * 1e6) {
    ++stats_.dropped_backlog;
    return;
  }
  Pending p;
  p.timestamp = rbuf->recv_utime;
  p.channel = channel;
  const uint8_t* data = static_cast<const uint8_t*>(rbuf->data);
  p.data.assign(data, data + size);
  queued_bytes_ += size;
  queue_.push_back(std::move(p));
  wake_.notify_one();
}

void SessionLogger::OpenPart() {
  std::string path = options_.out;
  if (split_) {
    // Never overwrite: skip names that appeared meanwhile (EventLogWriter also creates exclusively).
    while (Exists(LogPartName(options_.out, next_part_))) ++next_part_;
    path = LogPartName(options_.out, next_part_++);
  }
  auto writer = std::make_unique<EventLogWriter>(path);
  std::lock_guard<std::mutex> lock(mutex_);
  writer_ = std::move(writer);
  PartInfo part;
  part.path = path;
  stats_.parts.push_back(part);
  part_opened_us_ = SteadyUs();
}

void SessionLogger::ClosePart() {
  if (!writer_) return;
  writer_->Close();
  std::lock_guard<std::mutex> lock(mutex_);
  stats_.parts.back().bytes = writer_->bytes();
}

void SessionLogger::Record(const Pending& message) {
  if (split_ && writer_->events() > 0) {
    const bool by_size =
        options_.split_mb > 0 && static_cast<double>(writer_->bytes()) >= options_.split_mb * 1e6;
    const bool by_time = options_.split_minutes > 0 &&
                         static_cast<double>(SteadyUs() - part_opened_us_) >= options_.split_minutes * 60e6;
    if (by_size || by_time) {
      ClosePart();
      OpenPart();
    }
  }
  const uint64_t before = writer_->bytes();
  writer_->Write(message.timestamp, message.channel, message.data.data(), message.data.size());
  const uint64_t event_bytes = writer_->bytes() - before;

  // Frame seq of detections, to count what was lost on the way (LCM's receive queue, UDP, the network).
  std::string camera;
  int64_t seq = -1;
  bool undecodable = false;
  if (message.channel.rfind(kDetectionsChannelPrefix, 0) == 0) {
    detections_t det;
    if (Decode(message.data.data(), message.data.size(), &det)) {
      camera = det.camera;
      seq = det.seq;
    } else {
      camera = message.channel;
      undecodable = true;
    }
  }

  std::lock_guard<std::mutex> lock(mutex_);
  ++stats_.written;
  stats_.bytes_written += event_bytes;
  ChannelStats& c = stats_.channels[message.channel];
  ++c.messages;
  c.bytes += static_cast<int64_t>(message.data.size());
  PartInfo& part = stats_.parts.back();
  if (part.events == 0) part.first_timestamp = message.timestamp;
  part.last_timestamp = message.timestamp;
  ++part.events;
  part.bytes = writer_->bytes();
  if (!camera.empty()) {
    SeqStats& s = stats_.cameras[camera];
    if (undecodable) {
      ++s.undecodable;
    } else {
      if (s.frames == 0) {
        s.first_seq = seq;
      } else if (seq > s.last_seq + 1) {
        ++s.gaps;
        s.missing += seq - s.last_seq - 1;
      } else if (seq <= s.last_seq) {
        ++s.restarts;
      }
      ++s.frames;
      s.last_seq = seq;
    }
  }
}

void SessionLogger::WriterLoop() {
  try {
    int64_t next_flush = SteadyUs() + options_.flush_ms * 1000LL;
    int64_t next_sidecar = SteadyUs() + static_cast<int64_t>(options_.sidecar_seconds * 1e6);
    for (;;) {
      std::deque<Pending> batch;
      bool closing;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        const auto deadline = std::chrono::steady_clock::time_point(std::chrono::microseconds(next_flush));
        wake_.wait_until(lock, deadline, [&] { return !queue_.empty() || closing_; });
        batch.swap(queue_);
        queued_bytes_ = 0;
        closing = closing_;
      }
      for (const Pending& m : batch) Record(m);
      const int64_t now = SteadyUs();
      if (now >= next_flush || closing) {
        if (options_.fsync)
          writer_->Sync();
        else
          writer_->Flush();
        next_flush = now + options_.flush_ms * 1000LL;
      }
      if (closing) break;
      if (now >= next_sidecar) {
        WriteSidecar(false);
        next_sidecar = now + static_cast<int64_t>(options_.sidecar_seconds * 1e6);
      }
    }
  } catch (const std::exception& e) {
    std::lock_guard<std::mutex> lock(mutex_);
    writer_error_ = e.what();
    closing_ = true;
  }
}

std::string SessionLogger::StatusLine(double rate) const {
  char line[256];
  std::snprintf(line, sizeof(line),
                "%.1f msg/s, %lld msgs, %.2f MB written, %lld missing (seq gaps), %lld dropped", rate,
                static_cast<long long>(stats_.written), static_cast<double>(stats_.bytes_written) / 1e6,
                static_cast<long long>(stats_.Missing()), static_cast<long long>(stats_.dropped_backlog));
  return line;
}

SessionStats SessionLogger::Run(const StopToken& stop) {
  writer_thread_ = std::thread(&SessionLogger::WriterLoop, this);
  const bool from_file = options_.lcm_url.rfind("file://", 0) == 0;
  const int64_t start = SteadyUs();
  int64_t next_status = start + static_cast<int64_t>(options_.status_seconds * 1e6);
  int64_t last_status_received = 0, last_status_us = start;
  const bool tty = ::isatty(2);
  int consecutive_errors = 0;
  std::string error;
  for (;;) {
    if (stop.stop_requested()) break;
    const int64_t now = SteadyUs();
    if (options_.max_seconds > 0 && static_cast<double>(now - start) >= options_.max_seconds * 1e6) break;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!writer_error_.empty()) {
        error = writer_error_;
        break;
      }
      if (options_.max_messages > 0 && stats_.received >= options_.max_messages) break;
    }
    if (options_.status_seconds > 0 && now >= next_status) {
      std::string line;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        const double dt = static_cast<double>(now - last_status_us) / 1e6;
        const double rate = dt > 0 ? static_cast<double>(stats_.received - last_status_received) / dt : 0.0;
        line = "mcmt-logger: " + StatusLine(rate) + ", file " + current_part();
        last_status_received = stats_.received;
      }
      last_status_us = now;
      std::cerr << (tty ? "\r" : "") << line << (tty ? "\033[K" : "\n") << std::flush;
      next_status = now + static_cast<int64_t>(options_.status_seconds * 1e6);
    }
    const int r = lcm_.handleTimeout(50);
    if (r < 0) {
      if (from_file) break;
      if (stop.stop_requested()) break;
      if (++consecutive_errors > 200) {
        error = "LCM stopped delivering messages (handle failed repeatedly)";
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    } else {
      consecutive_errors = 0;
    }
  }
  // Stop receiving, drain, close.
  lcm_.unsubscribe(subscription_);
  subscription_ = nullptr;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    closing_ = true;
  }
  wake_.notify_all();
  writer_thread_.join();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (error.empty() && !writer_error_.empty()) error = writer_error_;
  }
  try {
    ClosePart();
  } catch (const std::exception& e) {
    if (error.empty()) error = e.what();
  }
  stats_.end_utime = WallUs();
  WriteSidecar(true);
  if (options_.status_seconds > 0) {
    const double elapsed = static_cast<double>(SteadyUs() - start) / 1e6;
    std::cerr << (tty ? "\r" : "") << "mcmt-logger: closed " << options_.out << " (" << stats_.parts.size()
              << " part(s)), average "
              << StatusLine(elapsed > 0 ? static_cast<double>(stats_.received) / elapsed : 0.0)
              << (tty ? "\033[K\n" : "\n") << std::flush;
  }
  if (!error.empty()) throw std::runtime_error(error);
  return stats_;
}

void SessionLogger::WriteSidecar(bool final_state) {
  SessionStats s;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    s = stats_;
  }
  const int64_t end = final_state ? s.end_utime : WallUs();
  YAML::Emitter y;
  y << YAML::Comment("mcmt-logger session sidecar: what was recorded, how, and what was lost");
  y << YAML::BeginMap;
  y << YAML::Key << "mcmt_session" << YAML::Value << 1;
  y << YAML::Key << "state" << YAML::Value << (final_state ? "closed" : "recording");
  y << YAML::Key << "log" << YAML::Value << options_.out;
  y << YAML::Key << "split" << YAML::Value << YAML::BeginMap;
  y << YAML::Key << "mb" << YAML::Value << options_.split_mb;
  y << YAML::Key << "minutes" << YAML::Value << options_.split_minutes << YAML::EndMap;
  y << YAML::Key << "parts" << YAML::Value << YAML::BeginSeq;
  for (const PartInfo& p : s.parts) {
    y << YAML::BeginMap << YAML::Key << "file" << YAML::Value << p.path;
    y << YAML::Key << "events" << YAML::Value << p.events;
    y << YAML::Key << "bytes" << YAML::Value << p.bytes;
    y << YAML::Key << "first_utime" << YAML::Value << p.first_timestamp;
    y << YAML::Key << "last_utime" << YAML::Value << p.last_timestamp << YAML::EndMap;
  }
  y << YAML::EndSeq;
  y << YAML::Key << "channels_regex" << YAML::Value << options_.channels;
  y << YAML::Key << "lcm_url" << YAML::Value
    << (options_.lcm_url.empty() ? "(LCM default)" : options_.lcm_url);
  char host[256] = {0};
  ::gethostname(host, sizeof(host) - 1);
  y << YAML::Key << "host" << YAML::Value << host;
  y << YAML::Key << "start_utime" << YAML::Value << s.start_utime;
  y << YAML::Key << "start_time" << YAML::Value << IsoTime(s.start_utime);
  y << YAML::Key << "end_utime" << YAML::Value << end;
  y << YAML::Key << "end_time" << YAML::Value << IsoTime(end);
  y << YAML::Key << "duration_s" << YAML::Value << static_cast<double>(end - s.start_utime) / 1e6;
  {
    const double duration = static_cast<double>(end - s.start_utime) / 1e6;
    char status[160];
    std::snprintf(status, sizeof(status),
                  "%.1f msg/s, %.2f MB written, %lld missing (seq gaps), %lld dropped",
                  duration > 0 ? static_cast<double>(s.received) / duration : 0.0,
                  static_cast<double>(s.bytes_written) / 1e6, static_cast<long long>(s.Missing()),
                  static_cast<long long>(s.dropped_backlog));
    y << YAML::Key << "status" << YAML::Value << status;
  }
  y << YAML::Key << "messages" << YAML::Value << YAML::BeginMap;
  y << YAML::Key << "received" << YAML::Value << s.received;
  y << YAML::Key << "written" << YAML::Value << s.written;
  y << YAML::Key << "bytes_written" << YAML::Value << s.bytes_written << YAML::EndMap;
  y << YAML::Key << "channels" << YAML::Value << YAML::BeginMap;
  for (const auto& [name, c] : s.channels) {
    y << YAML::Key << name << YAML::Value << YAML::Flow << YAML::BeginMap;
    y << YAML::Key << "messages" << YAML::Value << c.messages;
    y << YAML::Key << "bytes" << YAML::Value << c.bytes << YAML::EndMap;
  }
  y << YAML::EndMap;
  y << YAML::Key << "loss" << YAML::Value << YAML::BeginMap;
  y << YAML::Key << "what" << YAML::Value
    << "detections_missing: frames absent from the log between a camera's first and last recorded "
       "detections_t seq (lost by the network, the kernel's socket buffer or LCM's receive queue, "
       "whose capacity is raised to queue_capacity); dropped_backlog: messages this logger dropped "
       "because its write backlog exceeded max_unwritten_mb";
  y << YAML::Key << "queue_capacity" << YAML::Value << options_.queue_capacity;
  y << YAML::Key << "detections_missing" << YAML::Value << s.Missing();
  y << YAML::Key << "dropped_backlog" << YAML::Value << s.dropped_backlog;
  y << YAML::Key << "cameras" << YAML::Value << YAML::BeginMap;
  for (const auto& [name, c] : s.cameras) {
    y << YAML::Key << name << YAML::Value << YAML::Flow << YAML::BeginMap;
    y << YAML::Key << "frames" << YAML::Value << c.frames;
    y << YAML::Key << "first_seq" << YAML::Value << c.first_seq;
    y << YAML::Key << "last_seq" << YAML::Value << c.last_seq;
    y << YAML::Key << "gaps" << YAML::Value << c.gaps;
    y << YAML::Key << "missing" << YAML::Value << c.missing;
    y << YAML::Key << "restarts" << YAML::Value << c.restarts;
    y << YAML::Key << "undecodable" << YAML::Value << c.undecodable << YAML::EndMap;
  }
  y << YAML::EndMap << YAML::EndMap;
  if (!options_.config_path.empty()) {
    y << YAML::Key << "config" << YAML::Value << YAML::BeginMap;
    y << YAML::Key << "path" << YAML::Value << options_.config_path;
    y << YAML::Key << "text" << YAML::Value << YAML::Literal << config_text_;
    y << YAML::Key << "intrinsics" << YAML::Value << YAML::BeginSeq;
    for (const auto& [name, text] : intrinsics_texts_) {
      y << YAML::BeginMap << YAML::Key << "name" << YAML::Value << name;
      y << YAML::Key << "text" << YAML::Value << YAML::Literal << text << YAML::EndMap;
    }
    y << YAML::EndSeq << YAML::EndMap;
  }
  y << YAML::EndMap;
  if (!y.good()) throw std::runtime_error(sidecar_path() + ": cannot emit YAML: " + y.GetLastError());
  WriteFileAtomic(sidecar_path(), std::string(y.c_str()) + "\n");
}

}  // namespace mcmt
