#include "logger/export.h"

#include <sys/stat.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
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
#include "core/objects.h"
#include "core/se3.h"
#include "mcmt/camera_model_t.hpp"
#include "mcmt/detections_t.hpp"
#include "mcmt/mapper_command_t.hpp"
#include "mcmt/mapper_status_t.hpp"
#include "mcmt/marker_t.hpp"
#include "mcmt/object_layout_t.hpp"
#include "mcmt/object_pose_t.hpp"
#include "mcmt/pose3d_t.hpp"
#include "mcmt/rig_map2_t.hpp"
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
    AddKnownType<rig_map2_t>(&t);
    AddKnownType<object_layout_t>(&t);
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
  const uint64_t fp = static_cast<uint64_t>(EncodedHash(data.data(), data.size()));
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

namespace {

// The poses of one stream as poses CSV and TUM text.
struct PoseText {
  PoseExport out;
  std::string poses_csv = TrajectoryHeader(false, true) + "\n";  // a tracker's poses: with the quality
  std::string tum = kTumHeader;
};

// Writes every stream's files (names: BodyPath for a body's stream), fills result->streams.
void WritePoseStreams(std::vector<PoseText>* streams, const LogExportRequest& request,
                      LogExportResult* result) {
  for (PoseText& p : *streams) {
    if (!request.poses_csv.empty())
      p.out.poses_csv = p.out.body.empty() ? request.poses_csv : BodyPath(request.poses_csv, p.out.body);
    if (!request.tum.empty())
      p.out.tum = p.out.body.empty() ? request.tum : BodyPath(request.tum, p.out.body);
  }
  if (streams->empty()) {  // no pose at all: the asked files, empty (WhyPosesEmpty says why)
    PoseText none;
    if (!request.poses_csv.empty()) WriteFileAtomic(request.poses_csv, none.poses_csv);
    if (!request.tum.empty()) WriteFileAtomic(request.tum, none.tum);
    return;
  }
  for (PoseText& p : *streams) {
    if (!p.out.poses_csv.empty()) WriteFileAtomic(p.out.poses_csv, p.poses_csv);
    if (!p.out.tum.empty()) WriteFileAtomic(p.out.tum, p.tum);
    result->pose_rows += p.out.rows;
    result->poses_skipped += p.out.skipped;
    result->streams.push_back(p.out);
  }
}

}  // namespace

LogExportResult ExportFromLog(const std::string& log, const LogExportRequest& request) {
  LogExportResult result;
  std::string det_csv = std::string(kDetectionsCsvHeader) + "\n";
  std::map<std::string, PoseText> by_channel;  // MCMT_POSE and every MCMT_POSE_<BODY>
  const std::string body_prefix = request.pose_channel + "_";
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
    } else if (want_poses && (e.channel == request.pose_channel ||
                              e.channel.compare(0, body_prefix.size(), body_prefix) == 0 ||
                              HasType<object_pose_t>(e.data.data(), e.data.size()))) {
      object_pose_t pose;
      std::string error;
      if (!Decode(e.data.data(), e.data.size(), &pose, &error))
        throw LogFormatError(EventWhere(part, e, index) + ": " + error + ", found type " + TypeOf(e.data));
      auto [it, fresh] = by_channel.try_emplace(e.channel);
      PoseText& stream = it->second;
      if (fresh) {
        stream.out.source = e.channel;
        if (e.channel != request.pose_channel) {
          stream.out.body = BodyOfPose(e.channel, pose.object);
          if (stream.out.body.find_first_not_of(
                  "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_") != std::string::npos)
            throw LogFormatError(EventWhere(part, e, index) + ": body name '" + stream.out.body +
                                 "' cannot be part of a file name (letters, digits and _ only)");
        }
      }
      if (pose.status != object_pose_t::STATUS_TRACKING && pose.status != object_pose_t::STATUS_AMBIGUOUS) {
        ++stream.out.skipped;
        return;
      }
      // The message's own numbers, in trajectory.csv's format (core's TrajectoryCsvLine would go through a
      // rotation matrix and could change the last digit of the quaternion).
      const double* p = pose.rig_from_object.position;
      const double* q = pose.rig_from_object.orientation;  // w x y z
      stream.poses_csv += std::to_string(pose.utime) + "," + std::to_string(pose.seq);
      for (double v : {p[0], p[1], p[2], q[0], q[1], q[2], q[3], pose.rms_px})
        stream.poses_csv += "," + G17(v);
      stream.poses_csv += "," + std::to_string(pose.num_cameras) + "," + std::to_string(pose.num_markers) +
                          PoseQualityCsv(FromObjectPoseMsg(pose).quality) + "\n";
      stream.tum += TumLine(pose.utime, p, q);
      ++stream.out.rows;
    }
  });
  if (want_det) WriteFileAtomic(request.detections_csv, det_csv);
  if (want_poses) {
    std::vector<PoseText> streams;
    for (auto& [channel, stream] : by_channel) streams.push_back(std::move(stream));
    WritePoseStreams(&streams, request, &result);
  }
  return result;
}

bool IsTrajectoryCsv(const std::string& path) {
  std::ifstream in(path);
  std::string first;
  return std::getline(in, first) && IsTrajectoryHeader(first);
}

LogExportResult ExportFromTrajectory(const std::string& csv, const LogExportRequest& request) {
  struct stat st;
  const bool is_dir = ::stat(csv.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
  std::vector<std::pair<std::string, std::string>> sources =
      is_dir ? MapperTrajectories(csv) : std::vector<std::pair<std::string, std::string>>{{"", csv}};
  if (is_dir && sources.size() == 1 && !sources[0].first.empty() &&
      ReadMap(csv + "/map.yaml").objects.size() == 1)
    sources[0].first.clear();  // a map with one body keeps the asked name
  std::vector<PoseText> streams;
  for (const auto& [body, path] : sources) {
    PoseText p;
    p.out.body = body;
    p.out.source = path;
    const std::vector<TrajectoryRow> rows = ReadTrajectory(path);
    const bool quality =
        std::any_of(rows.begin(), rows.end(), [](const TrajectoryRow& r) { return r.quality.has_value(); });
    p.poses_csv = TrajectoryHeader(false, quality) + "\n";
    for (const TrajectoryRow& row : rows) {
      p.poses_csv += TrajectoryCsvLine(row, false, quality) + "\n";
      const Eigen::Vector3d t = row.rig_from_object.translation();
      p.tum += TumLine(row.utime, t.data(), QuaternionWxyz(row.rig_from_object).data());
      ++p.out.rows;
    }
    streams.push_back(std::move(p));
  }
  LogExportResult result;
  WritePoseStreams(&streams, request, &result);
  return result;
}

std::string WhyPosesEmpty(const std::string& source, bool from_trajectory, const LogExportResult& r,
                          const std::string& pose_channel) {
  if (r.pose_rows > 0) return "";
  if (from_trajectory) return source + " has no rows: no frame had a pose";
  if (r.poses_skipped > 0)
    return "all " + std::to_string(r.poses_skipped) + " object_pose_t on " + pose_channel + " in " + source +
           " are LOST (no pose)";
  return "no object_pose_t on " + pose_channel + " in " + source + " nor on " + pose_channel +
         "_<BODY> (mcmt-tracker was not running while it was recorded); the mapper's poses are in "
         "OUTDIR/trajectory.csv: "
         "give it as --trajectory OUTDIR/trajectory.csv (several bodies: --trajectory OUTDIR)";
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
      } else if (e.channel == kPoseChannel || !BodyOfPoseChannel(e.channel, "").empty() ||
                 HasType<object_pose_t>(e.data.data(), e.data.size())) {
        object_pose_t pose;
        if (!Decode(e.data.data(), e.data.size(), &pose)) {
          ++c.undecodable;
          continue;
        }
        ++s.pose_status[pose.status];
      } else if (e.channel == kMapChannel) {
        MapMessage map;
        if (!DecodeMapMessage(e.data.data(), e.data.size(), &map)) {
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
  MapMessage last;  // rig_map2_t (mcmt-mapper) or rig_map_t (older logs)
  bool found = false;
  ForEachEvent(path, [&](const LogEvent& e, int64_t index, const std::string& part) {
    if (e.channel != kMapChannel) return;
    std::string error;
    if (!DecodeMapMessage(e.data.data(), e.data.size(), &last, &error))
      throw LogFormatError(EventWhere(part, e, index) + ": " + error + ", found type " + TypeOf(e.data));
    found = true;
  });
  if (!found)
    throw LogFormatError(path + ": no map (rig_map2_t or rig_map_t) on " + std::string(kMapChannel) +
                         " in this log");
  return last.map;
}

}  // namespace mcmt
