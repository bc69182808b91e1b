// map.yaml and trajectory.csv, written atomically (temporary file in the same folder, then rename).
// Doubles are written with 17 significant digits so files round-trip exactly.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/camera.h"

namespace YAML {
class Node;
}
#include "core/se3.h"

namespace mcmt {

class FileFormatError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Writes `content` to `path` through `path.tmp.<pid>` + rename; never leaves a half-written file.
void WriteFileAtomic(const std::string& path, const std::string& content);
// A double with 17 significant digits (parses back to the same double), non-finite values spelled as YAML
// does (.nan, .inf, -.inf): how every mcmt YAML file writes numbers.
std::string YamlNumber(double v);

std::string ReadFile(const std::string& path);  // throws FileFormatError naming the file

constexpr int kMapVersion = 1;        // one object
constexpr int kMapVersionBodies = 2;  // several bodies: objects: (written when RigMap::objects is not empty)

struct MapCamera {
  std::string name;
  CameraModel model;
  Rigid3 rig_from_cam = Rigid3::Identity();
  int observations = 0;  // marker observations used
  double rms_px = 0.0;   // RMS reprojection error of its corners
  double max_px = 0.0;   // largest corner error
  // The camera's clock against the reference camera's: its true capture time is utime - ClockUs(utime),
  // ClockUs = time_offset_us + 1e-6 * time_drift_ppm * (utime - RigMap::time_reference_utime) (the
  // mapper's mapper.time_offsets and mapper.clock_drift; 0: synchronised, and not written).
  double time_offset_us = 0.0;
  double time_drift_ppm = 0.0;
  // How far the camera's clock is ahead of the reference camera's at its reading `utime`, us.
  double ClockUs(int64_t utime, int64_t time_reference_utime) const {
    return time_offset_us + 1e-6 * time_drift_ppm * static_cast<double>(utime - time_reference_utime);
  }
};

struct MapMarker {
  int id = 0;
  double size = 0.0;  // side, metres
  Rigid3 object_from_marker = Rigid3::Identity();
  int observations = 0;
  double rms_px = 0.0;
  double max_px = 0.0;
};

// One rigid body of a version 2 map: its layout in its own frame (the reference marker's), and for a
// static body its one pose for the whole session.
struct MapObject {
  std::string name;
  bool is_static = false;
  int reference_marker = 0;
  std::vector<MapMarker> markers;
  Rigid3 rig_from_object = Rigid3::Identity();  // static bodies
  double rms_px = 0.0;
  int num_frames = 0;  // moving bodies: frames with a pose
  int num_observations = 0;
};

struct RigMap {
  int version = kMapVersion;
  std::string dictionary;
  std::string reference_camera;
  int reference_marker = 0;
  std::vector<MapCamera> cameras;
  std::vector<MapMarker> markers;
  double rms_px = 0.0;
  int num_frames = 0;
  int num_observations = 0;
  // Where the cameras' time offsets hold when their clocks drift (MapCamera::ClockUs; written only then).
  int64_t time_reference_utime = 0;

  // Version 2 (several bodies): every body; `markers` and `reference_marker` are the first moving body's
  // (FirstMovingObject). Empty
  // in a version 1 map. rig_frame: the static body whose frame is the rig frame (empty: the reference
  // camera's).
  std::vector<MapObject> objects;
  std::string rig_frame;

  const MapCamera* FindCamera(const std::string& name) const;
  const MapMarker* FindMarker(int id) const;
  const MapObject* FindObject(const std::string& name) const;
  // A message of `camera` stamped `utime` by its clock, on the reference camera's clock: utime -
  // ClockUs(utime), rounded (the tracker's frames, the mapper's passes, the maintenance's frames); utime
  // itself for a camera the map lacks.
  int64_t ReferenceUtime(const std::string& camera, int64_t utime) const;
  // Some camera's clock is not the reference camera's (a time offset or drift was mapped).
  bool HasClocks() const;
  // The map of body k alone, as a version 1 map (the cameras and its markers).
  RigMap ObjectMap(size_t k) const;
};

// Clocks measured on messages already corrected by `applied`'s clocks (RigMap::ReferenceUtime) made whole:
// each camera of *map gets its clock plus applied's (the offsets at one time reference: *map's when its
// clocks drift, else applied's; the drifts added).
void ComposeClocks(const RigMap& applied, RigMap* map);

// The first moving body of a version 2 map (0 when all are static): the one `markers` holds.
size_t FirstMovingObject(const RigMap& map);

void WriteMap(const std::string& path, const RigMap& map);
RigMap ReadMap(const std::string& path);  // throws FileFormatError naming file and key; checks version

// trajectory.csv: header "utime,seq,tx,ty,tz,qw,qx,qy,qz,rms_px,cameras,markers", one row per frame
// with a solution; the pose is rig_from_object. The mapper's with time offsets adds the columns
// "wx,wy,wz,vx,vy,vz" (kTrajectoryVelocityHeader): the velocity its bundle adjustment moved the frame's
// pose along to each observation's capture time. The tracker's poses.csv (and mcmt-export's from
// object_pose_t) adds "status,sigma_position_m,sigma_rotation_rad" (PoseQuality), after the velocity's
// when both are there.

// A tracker's pose: its status and its 1-sigma uncertainty along the worst direction, from object_pose_t's
// status and covariance (QualityOfPose).
struct PoseQuality {
  bool ambiguous = false;           // STATUS_AMBIGUOUS (a single square; may be its mirror), else TRACKING
  double sigma_position_m = 0.0;    // sqrt of the largest eigenvalue of the origin's PositionCovariance
  double sigma_rotation_rad = 0.0;  // sqrt of the largest eigenvalue of the rotation block
};
// `covariance` in object_pose_t's order (x, y, z, then rotation; a perturbation in the rig frame).
PoseQuality QualityOfPose(const Rigid3& rig_from_object, const Matrix6d& covariance, bool ambiguous);

struct TrajectoryRow {
  int64_t utime = 0;
  int64_t seq = 0;
  Rigid3 rig_from_object = Rigid3::Identity();
  double rms_px = 0.0;
  int cameras = 0;
  int markers = 0;
  // (wx, wy, wz) rad/s, (vx, vy, vz) m/s, a twist in the rig frame: the pose dt seconds after utime is
  // (Exp(dt w) R, t + dt v) with (R, t) = rig_from_object. None: the row has no velocity.
  std::optional<std::array<double, 6>> velocity;
  // None: the row has no status nor covariance (the mapper's trajectory).
  std::optional<PoseQuality> quality;
};

// The row re-expressed in another rig frame: pose and velocity (rotated) of new_rig_from_rig * pose.
void MoveToRig(const Rigid3& new_rig_from_rig, TrajectoryRow* row);

extern const char kTrajectoryHeader[];
extern const char kTrajectoryVelocityHeader[];  // kTrajectoryHeader + ",wx,wy,wz,vx,vy,vz"
// kTrajectoryHeader [+ the velocity's columns] [+ ",status,sigma_position_m,sigma_rotation_rad"].
std::string TrajectoryHeader(bool velocity, bool quality);
// One of the four headers (a trailing '\r' allowed).
bool IsTrajectoryHeader(const std::string& line);
// No newline; with `velocity`, the six velocity columns follow (empty when the row has none), with
// `quality` the three PoseQuality columns ("tracking" or "ambiguous", then the two sigmas; empty when the
// row has none).
std::string TrajectoryCsvLine(const TrajectoryRow& row, bool velocity = false, bool quality = false);
// The three quality fields, each after a comma (",ambiguous,0.0012,0.0034"; ",,," for none).
std::string PoseQualityCsv(const std::optional<PoseQuality>& quality);
// With the velocity columns when some row has a velocity, the quality columns when some row has one or
// `quality` asks for them (the tracker's poses.csv has them even with no row).
void WriteTrajectory(const std::string& path, const std::vector<TrajectoryRow>& rows, bool quality = false);
// Any of the headers; throws FileFormatError naming the file, the line and the column.
std::vector<TrajectoryRow> ReadTrajectory(const std::string& path);

// A body's file beside the asked one: "dir/name.ext" + "tool" -> "dir/name_tool.ext" (no extension:
// "dir/name_tool"): the tracker's poses_<body>.csv for --out poses.csv, the exporter's per-body files.
std::string BodyPath(const std::string& path, const std::string& body);

// The trajectories of the mapper's OUTDIR as (body, path): OUTDIR/trajectory.csv for a single-object map
// (body ""), one OUTDIR/trajectory_<body>.csv per moving body of OUTDIR/map.yaml's objects. Throws
// FileFormatError naming the file that is missing.
std::vector<std::pair<std::string, std::string>> MapperTrajectories(const std::string& outdir);
// The moving bodies' trajectories of a map with objects, given as `path`: the mapper's OUTDIR
// (MapperTrajectories), or the tracker's --out PATH (BodyPath(PATH, body) per moving body, those that
// exist). Throws FileFormatError naming the path and the files looked for when there is none.
std::vector<std::pair<std::string, std::string>> BodyTrajectoryFiles(const std::string& path,
                                                                     const RigMap& map);

// The first key that appears twice in one mapping anywhere in `root` (yaml-cpp keeps both and answers
// lookups with the first), as "LINE: duplicated key 'KEY' (first at line N)"; "" when none.
std::string DuplicateYamlKey(const YAML::Node& root);

}  // namespace mcmt
