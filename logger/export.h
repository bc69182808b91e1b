// mcmt-export's engine: logs -> CSV / TUM / summary, trajectory CSV -> poses CSV / TUM, detections CSV ->
// log, the map of a log (its exports: core/map_export.h). Output files are written atomically (temporary
// name, then rename).
#pragma once

#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/detections_csv.h"
#include "core/files.h"
#include "core/log_writer.h"
#include "core/map_export.h"

namespace mcmt {

// ---- from a log ----------------------------------------------------------------------------------------

// Poses of several bodies (a log with MCMT_POSE_<BODY> channels, or the mapper's OUTDIR of a map with
// several bodies) go into one file per body: the asked path with "_<body>" before its extension
// (core/map_export.h's BodyPath: --tum poses.tum writes poses_tool.tum, poses_patient.tum); poses on
// MCMT_POSE itself (a single-object rig) keep the asked name.
struct LogExportRequest {
  std::string detections_csv;  // one row per marker of every detections_t on MCMT_DETECTIONS_*
  std::string poses_csv;       // trajectory.csv format from object_pose_t on MCMT_POSE (TRACKING/AMBIGUOUS)
  std::string tum;             // TUM: "timestamp tx ty tz qx qy qz qw", seconds, same poses
  std::string pose_channel = "MCMT_POSE";
};

// One stream of poses exported: a body's (name "" for MCMT_POSE / a single trajectory.csv).
struct PoseExport {
  std::string body;
  std::string source;          // the channel, or the trajectory file
  std::string poses_csv, tum;  // the files written ("" when not asked)
  int64_t rows = 0;
  int64_t skipped = 0;  // LOST
};

struct LogExportResult {
  int64_t detection_messages = 0;
  int64_t detection_rows = 0;
  int64_t pose_rows = 0;            // every stream's
  int64_t poses_skipped = 0;        // LOST (no valid pose)
  std::vector<PoseExport> streams;  // in channel order; empty when the log holds no pose
};

// Reads the log strictly (LogParts: a split recording is read part after part). A message on a
// channel an export needs that is not of the expected type throws LogFormatError naming the file,
// event, byte offset and channel. Channels nobody asked for are ignored.
LogExportResult ExportFromLog(const std::string& log, const LogExportRequest& request);

// Is this file a trajectory CSV (first line core's IsTrajectoryHeader: mcmt-mapper's trajectory.csv,
// mcmt-tracker's or mcmt-export's poses.csv)?
bool IsTrajectoryCsv(const std::string& path);
// request.poses_csv / request.tum from a trajectory CSV (pose_rows counts its rows), or from the mapper's
// OUTDIR (core's MapperTrajectories: one file per moving body). Throws FileFormatError naming the file and
// line.
LogExportResult ExportFromTrajectory(const std::string& csv, const LogExportRequest& request);
// Why an export came out empty (one line, naming the source and what to do), "" when it has rows.
std::string WhyPosesEmpty(const std::string& source, bool from_trajectory, const LogExportResult& result,
                          const std::string& pose_channel);
std::string WhyDetectionsEmpty(const std::string& log, const LogExportResult& result);

// What --summary reports. Tolerant: garbage is skipped (and reported), foreign types are listed.
struct ChannelSummary {
  std::string type;  // "mcmt.detections_t", ... or "unknown (fingerprint 0x...)" / "empty"
  int64_t messages = 0;
  int64_t bytes = 0;
  int64_t first_timestamp = 0, last_timestamp = 0;
  int64_t undecodable = 0;  // messages on an mcmt channel that do not decode as its type
};

struct CameraSummary {
  int64_t frames = 0;
  int64_t first_seq = -1, last_seq = -1;
  int64_t first_utime = 0, last_utime = 0;
  int64_t markers = 0;  // marker observations
  std::set<int> ids;
  std::vector<std::pair<int64_t, int64_t>> gaps;  // missing seq ranges [first, last]
  int64_t missing = 0;
  int64_t out_of_order = 0;  // seq <= previous seq
  std::set<std::string> channels;
};

struct LogSummary {
  std::vector<std::string> parts;
  uint64_t bytes = 0;
  int64_t events = 0;
  int64_t first_timestamp = 0, last_timestamp = 0;
  std::map<std::string, ChannelSummary> channels;
  std::map<std::string, CameraSummary> cameras;
  std::set<int> marker_ids;
  std::map<int, int64_t> pose_status;  // object_pose_t status -> count
  int64_t maps = 0;
  std::string last_mapper_status;
  uint64_t skipped_bytes = 0;       // garbage between events
  std::vector<std::string> damage;  // human-readable notes (garbage, truncated tail)
};

LogSummary SummarizeLog(const std::string& log);
std::string FormatSummary(const LogSummary& summary);

// ---- from a map -----------------------------------------------------------------------------------------

// map.yaml, or an LCM log: then the last map on MCMT_MAP, rig_map2_t (mcmt-mapper, several bodies) or
// rig_map_t (older logs) (throws naming the log when it has none).
RigMap ReadMapOrLog(const std::string& path);

// The map exports (Kalibr, ROS, OpenCV, PLY, OBJ) are in core/map_export.h.

}  // namespace mcmt
