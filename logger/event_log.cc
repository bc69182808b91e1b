#include "logger/event_log.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <ctime>
#include <sstream>

namespace mcmt {
namespace {

void PutBigEndian(uint64_t value, int bytes, std::string* out) {
  for (int i = bytes - 1; i >= 0; --i) out->push_back(static_cast<char>((value >> (8 * i)) & 0xff));
}

uint64_t GetBigEndian(const uint8_t* p, int bytes) {
  uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v = (v << 8) | p[i];
  return v;
}

bool FileExists(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0;
}

}  // namespace

void AppendEncodedEvent(int64_t eventnum, int64_t timestamp, const std::string& channel, const void* data,
                        size_t size, std::string* out) {
  if (channel.empty() || channel.size() > static_cast<size_t>(kLcmMaxChannelLength))
    throw std::invalid_argument("bad channel name '" + channel + "'");
  if (size > static_cast<size_t>(INT32_MAX)) throw std::invalid_argument("message too large on " + channel);
  PutBigEndian(kLcmSyncWord, 4, out);
  PutBigEndian(static_cast<uint64_t>(eventnum), 8, out);
  PutBigEndian(static_cast<uint64_t>(timestamp), 8, out);
  PutBigEndian(channel.size(), 4, out);
  PutBigEndian(size, 4, out);
  out->append(channel);
  out->append(static_cast<const char*>(data), size);
}

// ---------------------------------------------------------------------------------------------------------
// Reader

EventLogReader::EventLogReader(const std::string& path, bool resync) : path_(path), resync_(resync) {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) throw LogFormatError(path + ": cannot open: " + std::strerror(errno));
  if (S_ISDIR(st.st_mode)) throw LogFormatError(path + ": is a directory, not an LCM event log");
  file_ = std::fopen(path.c_str(), "rb");
  if (!file_) throw LogFormatError(path + ": cannot open: " + std::strerror(errno));
  file_size_ = static_cast<uint64_t>(st.st_size);
}

EventLogReader::~EventLogReader() {
  if (file_) std::fclose(file_);
}

bool EventLogReader::ReadExact(void* buffer, size_t size) {
  size_t n = std::fread(buffer, 1, size, file_);
  position_ += n;
  if (n != size && std::ferror(file_)) Fail(position_, std::string("read error: ") + std::strerror(errno));
  return n == size;
}

void EventLogReader::Fail(uint64_t offset, const std::string& what) const {
  std::ostringstream s;
  s << path_ << ": byte " << offset << " (event " << events_read_ << "): " << what;
  throw LogFormatError(s.str());
}

bool EventLogReader::Resync(uint64_t from) {
  // Scan byte by byte from from+1 for the sync word.
  if (std::fseek(file_, static_cast<long>(from + 1), SEEK_SET) != 0) return false;
  position_ = from + 1;
  uint32_t window = 0;
  int have = 0;
  int c;
  while ((c = std::fgetc(file_)) != EOF) {
    ++position_;
    window = (window << 8) | static_cast<uint32_t>(c);
    if (++have >= 4 && window == kLcmSyncWord) {
      uint64_t start = position_ - 4;
      skipped_regions_.push_back({from, start - from});
      skipped_bytes_ += start - from;
      std::fseek(file_, static_cast<long>(start), SEEK_SET);
      position_ = start;
      return true;
    }
  }
  skipped_regions_.push_back({from, file_size_ - from});
  skipped_bytes_ += file_size_ - from;
  position_ = file_size_;
  return false;
}

bool EventLogReader::Next(LogEvent* event) {
  for (;;) {
    const uint64_t start = position_;
    uint8_t header[kLcmEventHeaderBytes];
    size_t n = std::fread(header, 1, sizeof(header), file_);
    position_ += n;
    if (n == 0) return false;
    const uint32_t sync = static_cast<uint32_t>(GetBigEndian(header, 4));
    if (n >= 4 && sync != kLcmSyncWord) {
      if (resync_ && start > 0) {
        if (!Resync(start)) return false;
        continue;
      }
      std::ostringstream what;
      if (start == 0)
        what << "not an LCM event log (no sync word 0xEDA1DA01 at the start)";
      else
        what << "garbage between events: expected the sync word 0xEDA1DA01, found 0x" << std::hex << sync;
      Fail(start, what.str());
    }
    if (n < sizeof(header)) {  // cut short by the end of the file
      if (start == 0 && n < 4) Fail(0, "not an LCM event log (too short)");
      truncated_tail_bytes_ = file_size_ - start;
      return false;
    }
    const int64_t eventnum = static_cast<int64_t>(GetBigEndian(header + 4, 8));
    const int64_t timestamp = static_cast<int64_t>(GetBigEndian(header + 12, 8));
    const int32_t channel_len = static_cast<int32_t>(GetBigEndian(header + 20, 4));
    const int32_t data_len = static_cast<int32_t>(GetBigEndian(header + 24, 4));
    const uint64_t remaining = file_size_ - position_;
    bool bad = channel_len <= 0 || channel_len > kLcmMaxChannelLength || data_len < 0;
    if (!bad && static_cast<uint64_t>(channel_len) + static_cast<uint64_t>(data_len) > remaining) {
      // Cut short by the end of the file: the crash case. A length that could not be a partial write of
      // a real event (more than 1 GB beyond the end) is garbage rather than truncation.
      if (static_cast<uint64_t>(channel_len) + static_cast<uint64_t>(data_len) - remaining < (1ull << 30)) {
        truncated_tail_bytes_ = file_size_ - start;
        position_ = file_size_;
        return false;
      }
      bad = true;
    }
    if (bad) {
      if (resync_) {
        if (!Resync(start)) return false;
        continue;
      }
      std::ostringstream what;
      what << "corrupt event header (channel length " << channel_len << ", payload length " << data_len
           << ")";
      Fail(start, what.str());
    }
    event->eventnum = eventnum;
    event->timestamp = timestamp;
    event->offset = start;
    event->channel.resize(static_cast<size_t>(channel_len));
    event->data.resize(static_cast<size_t>(data_len));
    if (!ReadExact(&event->channel[0], event->channel.size()) ||
        (data_len > 0 && !ReadExact(event->data.data(), event->data.size()))) {
      truncated_tail_bytes_ = file_size_ - start;
      return false;
    }
    bool printable = true;
    for (char c : event->channel)
      if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) > 0x7e) printable = false;
    if (!printable) {
      if (resync_) {
        if (!Resync(start)) return false;
        continue;
      }
      Fail(start, "corrupt event: channel name is not printable text");
    }
    ++events_read_;
    return true;
  }
}

std::vector<LogEvent> ReadEventLog(const std::string& path) {
  EventLogReader reader(path);
  std::vector<LogEvent> events;
  LogEvent event;
  while (reader.Next(&event)) events.push_back(event);
  return events;
}

std::string LogPartName(const std::string& path, int index) {
  const size_t slash = path.find_last_of('/');
  const size_t dot = path.find_last_of('.');
  char number[16];
  std::snprintf(number, sizeof(number), "%02d", index);
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash) || dot == slash + 1)
    return path + "." + number;
  return path.substr(0, dot) + "." + number + path.substr(dot);
}

std::vector<std::string> LogParts(const std::string& path) {
  if (FileExists(path)) return {path};
  std::vector<std::string> parts;
  for (int i = 0; FileExists(LogPartName(path, i)); ++i) parts.push_back(LogPartName(path, i));
  if (parts.empty())
    throw LogFormatError(path + ": cannot open: no such file (nor split parts " + LogPartName(path, 0) +
                         ", ...)");
  return parts;
}

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
