#include "core/log_reader.h"

#include <sys/stat.h>

#include <cerrno>
#include <cstring>
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

struct Header {
  uint32_t sync = 0;
  int64_t eventnum = 0, timestamp = 0;
  int32_t channel_len = 0, data_len = 0;
};

Header ParseHeader(const uint8_t* h) {
  Header out;
  out.sync = static_cast<uint32_t>(GetBigEndian(h, 4));
  out.eventnum = static_cast<int64_t>(GetBigEndian(h + 4, 8));
  out.timestamp = static_cast<int64_t>(GetBigEndian(h + 12, 8));
  out.channel_len = static_cast<int32_t>(GetBigEndian(h + 20, 4));
  out.data_len = static_cast<int32_t>(GetBigEndian(h + 24, 4));
  return out;
}

bool LengthsValid(const Header& h) {
  return h.channel_len > 0 && h.channel_len <= kLcmMaxChannelLength && h.data_len >= 0;
}

bool Printable(const std::string& text) {
  for (char c : text)
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) > 0x7e) return false;
  return true;
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

bool EventLogReader::PlausibleHeaderAt(uint64_t offset) {
  if (offset + kLcmEventHeaderBytes > file_size_) return false;
  uint8_t h[kLcmEventHeaderBytes];
  if (std::fseek(file_, static_cast<long>(offset), SEEK_SET) != 0) return false;
  if (std::fread(h, 1, sizeof(h), file_) != sizeof(h)) return false;
  const Header header = ParseHeader(h);
  if (header.sync != kLcmSyncWord || !LengthsValid(header)) return false;
  const uint64_t end = offset + kLcmEventHeaderBytes + static_cast<uint64_t>(header.channel_len) +
                       static_cast<uint64_t>(header.data_len);
  return end <= file_size_;
}

bool EventLogReader::Resync(uint64_t from) {
  // The next sync word after `from` that starts a header whose lengths fit in the file.
  std::vector<uint8_t> chunk(1 << 16);
  uint64_t scan = from + 1;
  uint32_t window = 0;
  int have = 0;
  while (scan < file_size_) {
    if (std::fseek(file_, static_cast<long>(scan), SEEK_SET) != 0) break;
    const size_t n = std::fread(chunk.data(), 1, chunk.size(), file_);
    if (n == 0) break;
    for (size_t i = 0; i < n; ++i) {
      window = (window << 8) | chunk[i];
      if (++have < 4 || window != kLcmSyncWord) continue;
      const uint64_t candidate = scan + i - 3;
      if (!PlausibleHeaderAt(candidate)) continue;
      skipped_regions_.push_back({from, candidate - from});
      skipped_bytes_ += candidate - from;
      std::fseek(file_, static_cast<long>(candidate), SEEK_SET);
      position_ = candidate;
      return true;
    }
    // Chunks overlap by nothing: the window carries the last 3 bytes over; PlausibleHeaderAt moved the
    // file position, so the next chunk is read by offset.
    scan += n;
  }
  position_ = file_size_;
  std::fseek(file_, 0, SEEK_END);
  return false;
}

bool EventLogReader::CutTail(uint64_t start) {
  truncated_tail_offset_ = start;
  truncated_tail_bytes_ = file_size_ > start ? file_size_ - start : 0;
  position_ = file_size_;
  std::fseek(file_, 0, SEEK_END);
  return false;
}

bool EventLogReader::Next(LogEvent* event) {
  for (;;) {
    const uint64_t start = position_;
    uint8_t raw[kLcmEventHeaderBytes];
    const size_t n = std::fread(raw, 1, sizeof(raw), file_);
    position_ += n;
    if (n == 0) return false;
    const Header h = ParseHeader(raw);
    const bool sync_ok = n >= 4 && h.sync == kLcmSyncWord;
    if (n >= 4 && !sync_ok) {
      if (resync_ && start > 0) {
        const bool found = Resync(start);
        if (!found) {
          skipped_regions_.push_back({start, file_size_ - start});
          skipped_bytes_ += file_size_ - start;
          return false;
        }
        continue;
      }
      std::ostringstream what;
      if (start == 0)
        what << "not an LCM event log (no sync word 0xEDA1DA01 at the start)";
      else
        what << "garbage between events: expected the sync word 0xEDA1DA01, found 0x" << std::hex << h.sync;
      Fail(start, what.str());
    }
    if (n < sizeof(raw)) {  // cut short by the end of the file
      if (start == 0 && n < 4) Fail(0, "not an LCM event log (too short)");
      return CutTail(start);
    }
    const uint64_t remaining = file_size_ > position_ ? file_size_ - position_ : 0;
    const uint64_t body =
        static_cast<uint64_t>(std::max(h.channel_len, 0)) + static_cast<uint64_t>(std::max(h.data_len, 0));
    bool bad = !LengthsValid(h);
    if (!bad && body > remaining) {
      // Runs past the end of the file: a last event cut short (a crash while writing) -- unless a valid
      // event follows, in which case this header is damage.
      if (!resync_) {
        if (body - remaining < (1ull << 30)) return CutTail(start);
        bad = true;
      } else {
        if (Resync(start)) continue;
        return CutTail(start);
      }
    }
    if (bad) {
      if (resync_) {
        if (Resync(start)) continue;
        skipped_regions_.push_back({start, file_size_ - start});
        skipped_bytes_ += file_size_ - start;
        return false;
      }
      std::ostringstream what;
      what << "corrupt event header (channel length " << h.channel_len << ", payload length " << h.data_len
           << ")";
      Fail(start, what.str());
    }
    event->eventnum = h.eventnum;
    event->timestamp = h.timestamp;
    event->offset = start;
    event->channel.resize(static_cast<size_t>(h.channel_len));
    event->data.resize(static_cast<size_t>(h.data_len));
    if (!ReadExact(&event->channel[0], event->channel.size()) ||
        (h.data_len > 0 && !ReadExact(event->data.data(), event->data.size())))
      return CutTail(start);  // the file shrank while reading
    if (!Printable(event->channel)) {
      if (resync_) {
        if (Resync(start)) continue;
        skipped_regions_.push_back({start, file_size_ - start});
        skipped_bytes_ += file_size_ - start;
        return false;
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

std::string LogReadReport::Summary() const {
  if (!damaged()) return "";
  std::ostringstream s;
  s << "the log " << (parts.empty() ? std::string("?") : parts.front())
    << (parts.size() > 1 ? " (" + std::to_string(parts.size()) + " parts)" : std::string())
    << " is damaged: ";
  const size_t places = damage.size() - (truncated_bytes > 0 ? 1 : 0);
  if (skipped_bytes > 0)
    s << skipped_bytes << " bytes skipped in " << places << (places == 1 ? " place" : " places");
  if (truncated_bytes > 0)
    s << (skipped_bytes > 0 ? ", " : "") << "last event cut short (" << truncated_bytes << " bytes)";
  s << " (first: " << damage.front() << "); " << events << " events read, everything readable was used";
  return s.str();
}

LogReadReport ForEachLogEvent(const std::string& path, const std::function<bool(const LogEvent&)>& fn) {
  LogReadReport report;
  report.parts = LogParts(path);
  for (const std::string& part : report.parts) {
    EventLogReader reader(part, /*resync=*/true);
    report.bytes += reader.file_size();
    LogEvent event;
    bool go_on = true;
    while (go_on && reader.Next(&event)) go_on = fn(event);
    report.events += reader.events_read();
    report.skipped_bytes += reader.skipped_bytes();
    for (const auto& [offset, length] : reader.skipped_regions())
      report.damage.push_back(part + ": byte " + std::to_string(offset) + ": " + std::to_string(length) +
                              " bytes skipped (not an LCM event)");
    if (reader.truncated_tail_bytes() > 0) {
      report.truncated_bytes += reader.truncated_tail_bytes();
      report.damage.push_back(part + ": byte " + std::to_string(reader.truncated_tail_offset()) +
                              ": the last event is cut short (" +
                              std::to_string(reader.truncated_tail_bytes()) + " bytes ignored)");
    }
    if (reader.events_read() == 0 && reader.file_size() > 0 && reader.skipped_bytes() > 0)
      throw LogFormatError(part + ": not an LCM event log (no valid event in " +
                           std::to_string(reader.file_size()) + " bytes)");
    if (!go_on) break;
  }
  return report;
}

}  // namespace mcmt
