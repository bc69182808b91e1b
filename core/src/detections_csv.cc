#include "core/detections_csv.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include "core/lcm_util.h"
#include "core/log_writer.h"
#include "mcmt/detections_t.hpp"
#include "mcmt/marker_t.hpp"

namespace mcmt {

const char kDetectionsCsvHeader[] = "utime,seq,camera,id,x0,y0,x1,y1,x2,y2,x3,y3";

std::vector<std::string> SplitCsv(const std::string& line) {
  std::vector<std::string> fields;
  size_t start = 0;
  for (;;) {
    const size_t comma = line.find(',', start);
    std::string f = line.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    f.erase(0, f.find_first_not_of(" \t\r"));
    f.erase(f.find_last_not_of(" \t\r") + 1);
    fields.push_back(std::move(f));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return fields;
}

CsvToLogResult DetectionsCsvToLog(const std::string& csv_path, const RigConfig& rig,
                                  const std::string& out_log) {
  struct stat st;
  if (::stat(out_log.c_str(), &st) == 0)
    throw std::runtime_error(out_log + ": exists; refusing to overwrite a log");
  std::ifstream in(csv_path);
  if (!in) throw std::runtime_error(csv_path + ": cannot open: " + std::strerror(errno));
  std::string line;
  int line_number = 0;
  if (!std::getline(in, line)) throw std::runtime_error(csv_path + ": empty file (expected the header line)");
  ++line_number;
  if (!line.empty() && line.back() == '\r') line.pop_back();
  if (line != kDetectionsCsvHeader)
    throw std::runtime_error(csv_path + ":1: expected the header '" + std::string(kDetectionsCsvHeader) +
                             "', got '" + line + "'");
  static const char* kColumns[] = {"utime", "seq", "camera", "id", "x0", "y0",
                                   "x1",    "y1",  "x2",     "y2", "x3", "y3"};

  const std::string tmp = out_log + ".tmp." + std::to_string(::getpid());
  CsvToLogResult result;
  try {
    EventLogWriter writer(tmp);
    detections_t current;
    bool have_current = false;
    auto flush_current = [&]() {
      if (!have_current) return;
      current.num_markers = static_cast<int32_t>(current.markers.size());
      std::vector<uint8_t> data = Encode(current);
      writer.Write(current.utime, DetectionsChannel(current.camera), data.data(), data.size());
      ++result.messages;
      have_current = false;
    };
    while (std::getline(in, line)) {
      ++line_number;
      if (!line.empty() && line.back() == '\r') line.pop_back();
      if (line.empty()) continue;
      const std::string where = csv_path + ":" + std::to_string(line_number);
      std::vector<std::string> f = SplitCsv(line);
      if (f.size() != 12)
        throw std::runtime_error(where + ": expected 12 columns, got " + std::to_string(f.size()));
      auto parse_int = [&](int col) -> long long {
        char* end = nullptr;
        errno = 0;
        long long v = std::strtoll(f[col].c_str(), &end, 10);
        if (f[col].empty() || *end != '\0' || errno)
          throw std::runtime_error(where + ": " + kColumns[col] + ": expected an integer, got '" + f[col] +
                                   "'");
        return v;
      };
      auto parse_double = [&](int col) -> double {
        char* end = nullptr;
        errno = 0;
        double v = std::strtod(f[col].c_str(), &end);
        if (f[col].empty() || *end != '\0' || errno == ERANGE)
          throw std::runtime_error(where + ": " + kColumns[col] + ": expected a number, got '" + f[col] +
                                   "'");
        return v;
      };
      const int64_t utime = parse_int(0);
      const int64_t seq = parse_int(1);
      const std::string& camera = f[2];
      const long long id = parse_int(3);
      if (id < 0 || id > INT32_MAX) throw std::runtime_error(where + ": id: out of range: " + f[3]);
      if (!have_current || current.camera != camera || current.utime != utime || current.seq != seq) {
        flush_current();
        const CameraConfig* cam = rig.FindCamera(camera);
        if (!cam) {
          std::string names;
          for (const auto& c : rig.cameras) names += (names.empty() ? "" : ", ") + c.name;
          throw std::runtime_error(where + ": camera '" + camera + "' is not in " + rig.path +
                                   " (cameras: " + names + ")");
        }
        current = detections_t();
        current.utime = utime;
        current.seq = seq;
        current.camera = camera;
        current.dictionary = rig.markers.dictionary;
        current.camera_model = ToCameraModelMsg(cam->model);
        current.detection_ms = 0.0;
        have_current = true;
      }
      marker_t m;
      m.id = static_cast<int32_t>(id);
      for (int k = 0; k < 4; ++k) {
        m.corners[k][0] = parse_double(4 + 2 * k);
        m.corners[k][1] = parse_double(5 + 2 * k);
      }
      current.markers.push_back(m);
      ++result.rows;
    }
    flush_current();
    writer.Close();
  } catch (...) {
    ::unlink(tmp.c_str());
    throw;
  }
  // Never overwrite: link() fails if out_log appeared meanwhile.
  if (::link(tmp.c_str(), out_log.c_str()) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    throw std::runtime_error(out_log + ": cannot create: " + std::strerror(err));
  }
  ::unlink(tmp.c_str());
  return result;
}

}  // namespace mcmt
