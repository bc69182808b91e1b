#include "logger/export.h"

#include <sys/stat.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <cerrno>
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <opencv2/core.hpp>
#include <sstream>
#include <stdexcept>

#include "core/lcm_util.h"
#include "core/marker.h"
#include "core/se3.h"
#include "mcmt/camera_model_t.hpp"
#include "mcmt/detections_t.hpp"
#include "mcmt/mapper_command_t.hpp"
#include "mcmt/mapper_status_t.hpp"
#include "mcmt/marker_t.hpp"
#include "mcmt/object_pose_t.hpp"
#include "mcmt/pose3d_t.hpp"
#include "mcmt/rig_map_t.hpp"

namespace mcmt {

namespace {

std::string G17(double v) {
  char text[40];
  std::snprintf(text, sizeof(text), "%.17g", v);
  return text;
}

std::string EventWhere(const std::string& path, const LogEvent& e, int64_t index) {
  std::ostringstream s;
  s << path << ": event " << index << " (byte " << e.offset << ") on " << e.channel;
  return s.str();
}

uint64_t Fingerprint(const std::vector<uint8_t>& data) {
  uint64_t v = 0;
  for (size_t i = 0; i < 8 && i < data.size(); ++i) v = (v << 8) | data[i];
  return v;
}

template <typename Msg>
void AddKnownType(std::map<uint64_t, std::string>* types) {
  (*types)[static_cast<uint64_t>(Msg::getHash())] = std::string("mcmt.") + Msg::getTypeName();
}

const std::map<uint64_t, std::string>& KnownTypes() {
  static const std::map<uint64_t, std::string> types = [] {
    std::map<uint64_t, std::string> t;
    AddKnownType<detections_t>(&t);
    AddKnownType<object_pose_t>(&t);
    AddKnownType<rig_map_t>(&t);
    AddKnownType<mapper_status_t>(&t);
    AddKnownType<mapper_command_t>(&t);
    AddKnownType<camera_model_t>(&t);
    AddKnownType<marker_t>(&t);
    AddKnownType<pose3d_t>(&t);
    return t;
  }();
  return types;
}

std::string TypeOf(const std::vector<uint8_t>& data) {
  if (data.size() < 8) return "unknown (" + std::to_string(data.size()) + " bytes, no fingerprint)";
  const uint64_t fp = Fingerprint(data);
  auto it = KnownTypes().find(fp);
  if (it != KnownTypes().end()) {
    // "mcmt.detections_t" may come back from getTypeName() already qualified; avoid "mcmt.mcmt.".
    const std::string& name = it->second;
    return name.rfind("mcmt.mcmt.", 0) == 0 ? name.substr(5) : name;
  }
  char text[64];
  std::snprintf(text, sizeof(text), "unknown (fingerprint 0x%016" PRIx64 ")", fp);
  return text;
}

// Calls fn(event, index, part) for every event of every part, strictly.
template <typename Fn>
void ForEachEvent(const std::string& log, Fn fn) {
  for (const std::string& part : LogParts(log)) {
    EventLogReader reader(part);
    LogEvent event;
    int64_t index = 0;
    while (reader.Next(&event)) fn(event, index++, part);
  }
}

const char kTumHeader[] = "# timestamp tx ty tz qx qy qz qw (rig_from_object, seconds, metres)\n";

// One TUM line: seconds with microseconds, position, quaternion x y z w (q_wxyz is w, x, y, z).
std::string TumLine(int64_t utime, const double* p, const double* q_wxyz) {
  char seconds[48];
  std::snprintf(seconds, sizeof(seconds), "%lld.%06lld", static_cast<long long>(utime / 1000000),
                static_cast<long long>(utime % 1000000));
  return std::string(seconds) + " " + G17(p[0]) + " " + G17(p[1]) + " " + G17(p[2]) + " " + G17(q_wxyz[1]) +
         " " + G17(q_wxyz[2]) + " " + G17(q_wxyz[3]) + " " + G17(q_wxyz[0]) + "\n";
}

}  // namespace

// ---------------------------------------------------------------------------------------------------------
// Log -> CSV / TUM

LogExportResult ExportFromLog(const std::string& log, const LogExportRequest& request) {
  LogExportResult result;
  std::string det_csv = std::string(kDetectionsCsvHeader) + "\n";
  std::string poses_csv = std::string(kTrajectoryHeader) + "\n";
  std::string tum = kTumHeader;
  const bool want_det = !request.detections_csv.empty();
  const bool want_poses = !request.poses_csv.empty() || !request.tum.empty();
  ForEachEvent(log, [&](const LogEvent& e, int64_t index, const std::string& part) {
    if (want_det && IsDetectionsChannel(e.channel)) {
      detections_t det;
      std::string error;
      if (!Decode(e.data.data(), e.data.size(), &det, &error))
        throw LogFormatError(EventWhere(part, e, index) + ": " + error + ", found type " + TypeOf(e.data));
      if (det.camera.find_first_of(",\"\n\r") != std::string::npos)
        throw LogFormatError(EventWhere(part, e, index) + ": camera name '" + det.camera +
                             "' cannot be written to CSV (contains a comma, quote or newline)");
      ++result.detection_messages;
      for (const marker_t& m : det.markers) {
        det_csv += std::to_string(det.utime) + "," + std::to_string(det.seq) + "," + det.camera + "," +
                   std::to_string(m.id);
        for (int k = 0; k < 4; ++k) det_csv += "," + G17(m.corners[k][0]) + "," + G17(m.corners[k][1]);
        det_csv += "\n";
        ++result.detection_rows;
      }
    } else if (want_poses && e.channel == request.pose_channel) {
      object_pose_t pose;
      std::string error;
      if (!Decode(e.data.data(), e.data.size(), &pose, &error))
        throw LogFormatError(EventWhere(part, e, index) + ": " + error + ", found type " + TypeOf(e.data));
      if (pose.status != object_pose_t::STATUS_TRACKING && pose.status != object_pose_t::STATUS_AMBIGUOUS) {
        ++result.poses_skipped;
        return;
      }
      // The message's own numbers, in trajectory.csv's format (core's TrajectoryCsvLine would go through a
      // rotation matrix and could change the last digit of the quaternion).
      const double* p = pose.rig_from_object.position;
      const double* q = pose.rig_from_object.orientation;  // w x y z
      poses_csv += std::to_string(pose.utime) + "," + std::to_string(pose.seq);
      for (double v : {p[0], p[1], p[2], q[0], q[1], q[2], q[3], pose.rms_px}) poses_csv += "," + G17(v);
      poses_csv += "," + std::to_string(pose.num_cameras) + "," + std::to_string(pose.num_markers) + "\n";
      tum += TumLine(pose.utime, p, q);
      ++result.pose_rows;
    }
  });
  if (want_det) WriteFileAtomic(request.detections_csv, det_csv);
  if (!request.poses_csv.empty()) WriteFileAtomic(request.poses_csv, poses_csv);
  if (!request.tum.empty()) WriteFileAtomic(request.tum, tum);
  return result;
}

bool IsTrajectoryCsv(const std::string& path) {
  std::ifstream in(path);
  std::string first;
  return std::getline(in, first) &&
         (first == kTrajectoryHeader || first == std::string(kTrajectoryHeader) + "\r");
}

LogExportResult ExportFromTrajectory(const std::string& csv, const LogExportRequest& request) {
  LogExportResult result;
  std::string poses_csv = std::string(kTrajectoryHeader) + "\n", tum = kTumHeader;
  for (const TrajectoryRow& row : ReadTrajectory(csv)) {
    poses_csv += TrajectoryCsvLine(row) + "\n";
    const Eigen::Vector3d p = row.rig_from_object.translation();
    tum += TumLine(row.utime, p.data(), QuaternionWxyz(row.rig_from_object).data());
    ++result.pose_rows;
  }
  if (!request.poses_csv.empty()) WriteFileAtomic(request.poses_csv, poses_csv);
  if (!request.tum.empty()) WriteFileAtomic(request.tum, tum);
  return result;
}

std::string WhyPosesEmpty(const std::string& source, bool from_trajectory, const LogExportResult& r,
                          const std::string& pose_channel) {
  if (r.pose_rows > 0) return "";
  if (from_trajectory) return source + " has no rows: no frame had a pose";
  if (r.poses_skipped > 0)
    return "all " + std::to_string(r.poses_skipped) + " object_pose_t on " + pose_channel + " in " + source +
           " are LOST (no pose)";
  return "no object_pose_t on " + pose_channel + " in " + source +
         " (mcmt-tracker was not running while it was recorded); the mapper's poses are in "
         "OUTDIR/trajectory.csv: "
         "give it as --trajectory OUTDIR/trajectory.csv";
}

std::string WhyDetectionsEmpty(const std::string& log, const LogExportResult& r) {
  if (r.detection_rows > 0) return "";
  if (r.detection_messages == 0)
    return "no detections_t on " + std::string(kDetectionsChannelPrefix) + "* in " + log;
  return "none of the " + std::to_string(r.detection_messages) + " detections_t in " + log +
         " holds a marker";
}

// ---------------------------------------------------------------------------------------------------------
// Summary

LogSummary SummarizeLog(const std::string& log) {
  LogSummary s;
  s.parts = LogParts(log);
  for (const std::string& part : s.parts) {
    EventLogReader reader(part, /*resync=*/true);
    s.bytes += reader.file_size();
    LogEvent e;
    while (reader.Next(&e)) {
      ++s.events;
      if (s.first_timestamp == 0 || e.timestamp < s.first_timestamp) s.first_timestamp = e.timestamp;
      if (e.timestamp > s.last_timestamp) s.last_timestamp = e.timestamp;
      ChannelSummary& c = s.channels[e.channel];
      if (c.messages == 0) {
        c.type = TypeOf(e.data);
        c.first_timestamp = e.timestamp;
      }
      ++c.messages;
      c.bytes += static_cast<int64_t>(e.data.size());
      c.last_timestamp = e.timestamp;
      if (IsDetectionsChannel(e.channel)) {
        detections_t det;
        if (!Decode(e.data.data(), e.data.size(), &det)) {
          ++c.undecodable;
          continue;
        }
        CameraSummary& cam = s.cameras[det.camera];
        cam.channels.insert(e.channel);
        if (cam.frames == 0) {
          cam.first_seq = det.seq;
          cam.first_utime = det.utime;
        } else if (det.seq > cam.last_seq + 1) {
          cam.gaps.push_back({cam.last_seq + 1, det.seq - 1});
          cam.missing += det.seq - cam.last_seq - 1;
        } else if (det.seq <= cam.last_seq) {
          ++cam.out_of_order;
        }
        ++cam.frames;
        cam.last_seq = det.seq;
        cam.last_utime = det.utime;
        cam.markers += det.num_markers;
        for (const marker_t& m : det.markers) {
          cam.ids.insert(m.id);
          s.marker_ids.insert(m.id);
        }
      } else if (e.channel == kPoseChannel) {
        object_pose_t pose;
        if (!Decode(e.data.data(), e.data.size(), &pose)) {
          ++c.undecodable;
          continue;
        }
        ++s.pose_status[pose.status];
      } else if (e.channel == kMapChannel) {
        rig_map_t map;
        if (!Decode(e.data.data(), e.data.size(), &map)) {
          ++c.undecodable;
          continue;
        }
        ++s.maps;
      } else if (e.channel == kMapperStatusChannel) {
        mapper_status_t status;
        if (!Decode(e.data.data(), e.data.size(), &status)) {
          ++c.undecodable;
          continue;
        }
        s.last_mapper_status = status.message;
      }
    }
    for (const auto& [offset, length] : reader.skipped_regions())
      s.damage.push_back(part + ": skipped " + std::to_string(length) + " bytes of garbage at byte " +
                         std::to_string(offset));
    s.skipped_bytes += reader.skipped_bytes();
    if (reader.truncated_tail_bytes() > 0)
      s.damage.push_back(part + ": last event cut short (" + std::to_string(reader.truncated_tail_bytes()) +
                         " bytes ignored; the recorder was killed or the disk filled)");
  }
  return s;
}

static std::string IdList(const std::set<int>& ids) {
  // Compact: 0-5 8 10-12
  std::string out;
  auto it = ids.begin();
  while (it != ids.end()) {
    int first = *it, last = *it;
    auto next = std::next(it);
    while (next != ids.end() && *next == last + 1) {
      last = *next;
      ++next;
    }
    if (!out.empty()) out += " ";
    out += std::to_string(first);
    if (last > first) out += (last == first + 1 ? " " : "-") + std::to_string(last);
    it = next;
  }
  return out.empty() ? "none" : out;
}

std::string FormatSummary(const LogSummary& s) {
  std::ostringstream o;
  char line[512];
  o << "log: ";
  for (size_t i = 0; i < s.parts.size(); ++i) o << (i ? ", " : "") << s.parts[i];
  o << "\n";
  std::snprintf(line, sizeof(line), "size: %.3f MB, %lld events, %zu channels\n",
                static_cast<double>(s.bytes) / 1e6, static_cast<long long>(s.events), s.channels.size());
  o << line;
  const double span = static_cast<double>(s.last_timestamp - s.first_timestamp) / 1e6;
  if (s.events > 0) {
    std::snprintf(line, sizeof(line), "time span: %s .. %s (%.3f s, event receive times)\n",
                  IsoTime(s.first_timestamp).c_str(), IsoTime(s.last_timestamp).c_str(), span);
    o << line;
  }
  o << "channels:\n";
  std::snprintf(line, sizeof(line), "  %-28s %-36s %10s %10s %12s\n", "channel", "type", "messages", "rate/s",
                "bytes");
  o << line;
  for (const auto& [name, c] : s.channels) {
    const double cspan = static_cast<double>(c.last_timestamp - c.first_timestamp) / 1e6;
    const double rate = c.messages > 1 && cspan > 0 ? static_cast<double>(c.messages - 1) / cspan : 0.0;
    std::snprintf(line, sizeof(line), "  %-28s %-36s %10lld %10.2f %12lld\n", name.c_str(), c.type.c_str(),
                  static_cast<long long>(c.messages), rate, static_cast<long long>(c.bytes));
    o << line;
    if (c.undecodable > 0)
      o << "    warning: " << c.undecodable << " message(s) on " << name
        << " do not decode as the mcmt type of "
        << "that channel\n";
  }
  o << "cameras: " << s.cameras.size() << "\n";
  for (const auto& [name, cam] : s.cameras) {
    const double cspan = static_cast<double>(cam.last_utime - cam.first_utime) / 1e6;
    std::snprintf(line, sizeof(line),
                  "  %s: %lld frames, seq %lld..%lld, %.3f s, %.2f fps, %.2f markers/frame, ids %s\n",
                  name.c_str(), static_cast<long long>(cam.frames), static_cast<long long>(cam.first_seq),
                  static_cast<long long>(cam.last_seq), cspan,
                  cam.frames > 1 && cspan > 0 ? static_cast<double>(cam.frames - 1) / cspan : 0.0,
                  cam.frames ? static_cast<double>(cam.markers) / static_cast<double>(cam.frames) : 0.0,
                  IdList(cam.ids).c_str());
    o << line;
    if (cam.gaps.empty()) {
      o << "    seq gaps: none\n";
    } else {
      o << "    seq gaps: " << cam.gaps.size() << ", " << cam.missing << " frames missing:";
      for (size_t i = 0; i < cam.gaps.size() && i < 20; ++i) {
        const auto& g = cam.gaps[i];
        o << " " << g.first;
        if (g.second > g.first) o << ".." << g.second;
      }
      if (cam.gaps.size() > 20) o << " ...";
      o << "\n";
    }
    if (cam.out_of_order > 0) o << "    out of order or repeated seq: " << cam.out_of_order << "\n";
  }
  o << "marker ids seen: " << IdList(s.marker_ids) << " (" << s.marker_ids.size() << ")\n";
  if (!s.pose_status.empty()) {
    int64_t total = 0;
    for (const auto& [st, n] : s.pose_status) total += n;
    o << "poses: " << total;
    auto count = [&](int st) {
      auto it = s.pose_status.find(st);
      return it == s.pose_status.end() ? 0LL : static_cast<long long>(it->second);
    };
    o << " (tracking " << count(object_pose_t::STATUS_TRACKING) << ", ambiguous "
      << count(object_pose_t::STATUS_AMBIGUOUS) << ", lost " << count(object_pose_t::STATUS_LOST) << ")\n";
  }
  if (s.maps > 0) o << "maps: " << s.maps << "\n";
  if (!s.last_mapper_status.empty()) o << "last mapper status: " << s.last_mapper_status << "\n";
  if (s.damage.empty()) {
    o << "damage: none\n";
  } else {
    for (const std::string& d : s.damage) o << "damage: " << d << "\n";
  }
  return o.str();
}

// ---------------------------------------------------------------------------------------------------------
// Map from a log (the exports of a map are in core/map_export.h)

RigMap ReadMapOrLog(const std::string& path) {
  bool is_log = false;
  if (FILE* f = std::fopen(path.c_str(), "rb")) {
    uint8_t magic[4];
    is_log = std::fread(magic, 1, 4, f) == 4 && ((uint32_t(magic[0]) << 24) | (uint32_t(magic[1]) << 16) |
                                                 (uint32_t(magic[2]) << 8) | magic[3]) == kLcmSyncWord;
    std::fclose(f);
  }
  if (!is_log) return ReadMap(path);
  rig_map_t last;
  bool found = false;
  ForEachEvent(path, [&](const LogEvent& e, int64_t index, const std::string& part) {
    if (e.channel != kMapChannel) return;
    std::string error;
    if (!Decode(e.data.data(), e.data.size(), &last, &error))
      throw LogFormatError(EventWhere(part, e, index) + ": " + error + ", found type " + TypeOf(e.data));
    found = true;
  });
  if (!found) throw LogFormatError(path + ": no rig_map_t on " + std::string(kMapChannel) + " in this log");
  return FromRigMapMsg(last);
}

}  // namespace mcmt
