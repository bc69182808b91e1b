// mcmt-eval's metrics: an estimate (map.yaml and/or a trajectory) against the simulator's ground truth,
// after rigid (Horn / Umeyama, no scale) alignments, as the paper measures.
//
// Alignments (the estimate's frames are its own choice: reference camera, reference marker):
//  - rig:    A = gt_rig_from_est_rig, Umeyama on the camera centres (>= 3 cameras; with 1 or 2 cameras,
//            the first common camera's full pose).
//  - object: B = gt_object_from_est_object, Umeyama on the 4 corners of every common marker, each in
//            its object frame (so marker sizes count).
//  - poses:  the estimated object pose in ground-truth frames is A * rig_from_object_est * inv(B): it is
//            composed from the two alignments above, never fitted to the trajectory itself, so it does
//            not absorb trajectory errors. Translation error = distance between the positions of the
//            ground-truth object origin; rotation error = angle of the relative rotation. A variant with
//            its own Horn alignment of the trajectory positions (paper style) is reported alongside.
// Figures: camera position (mm) and rotation (deg) errors per camera; object configuration error (mm)
// = mean distance of marker corners after alignment, per marker; object translation (mm) and rotation
// (deg) errors per frame; each with mean / median / max / RMS; fraction of frames with a pose.
#pragma once

#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "core/files.h"
#include "sim/sim.h"

namespace mcmt {
namespace sim {

struct Stats {
  int count = 0;
  double mean = 0, median = 0, max = 0, rms = 0;
};
Stats ComputeStats(std::vector<double> values);

struct CameraError {
  std::string name;
  double position_mm = 0, rotation_deg = 0;
};
struct MarkerError {
  int id = 0;
  double corner_mm = 0;  // mean over the 4 corners
  double size_mm = 0;    // estimated minus true side
};

struct EvalResult {
  bool has_map = false, has_trajectory = false;
  // Cameras
  int gt_cameras = 0, mapped_cameras = 0;
  std::vector<std::string> missing_cameras;
  std::vector<CameraError> cameras;
  Stats camera_position_mm, camera_rotation_deg;
  // Metric scale: the least-squares ratio of all camera-to-camera distances, estimate over truth, minus
  // 1 (NAN with fewer than 2 cameras).
  double scale_error = NAN;
  // Object configuration
  int gt_markers = 0, mapped_markers = 0;
  std::vector<int> missing_markers;
  std::vector<MarkerError> markers;
  Stats configuration_mm;
  // Object poses
  int gt_frames = 0, frames_with_pose = 0;
  Stats object_translation_mm, object_rotation_deg;
  Stats object_translation_aligned_mm;  // own Horn alignment of trajectory positions (paper style)
  // Poses with a status and covariance (a tracker's: TrajectoryRow::quality), counted once per frame as
  // above. The errors of TRACKING and AMBIGUOUS poses apart, and how often an error is beyond 3 sigma along
  // the covariance's worst direction. That sigma bounds every direction, so of a right covariance's 3-D
  // errors at most P(chi-square(3) > 9) = 2.9 % lie beyond it (rotation likewise). Without the map's
  // covariance (map.yaml's, core/map_covariance.h) the tracker's covariance holds the map fixed: the map's
  // own error (the camera and layout figures) is not in it. Poses whose sigma is not finite are left out of
  // the fractions.
  int frames_with_quality = 0, ambiguous_frames = 0, frames_with_sigma = 0;
  Stats tracking_translation_mm, tracking_rotation_deg, ambiguous_translation_mm, ambiguous_rotation_deg;
  double beyond_3sigma_position = NAN, beyond_3sigma_rotation = NAN;  // fractions of frames_with_sigma
  // The same for object_translation_aligned_mm's errors: the trajectory's own rigid alignment takes out
  // what every pose shares (most of the map's error), leaving the frame-to-frame noise the covariance
  // describes.
  double beyond_3sigma_position_aligned = NAN;
  double map_rms_px = 0;
  Rigid3 gt_rig_from_est_rig = Rigid3::Identity();
  Rigid3 gt_object_from_est_object = Rigid3::Identity();
};

class EvalInputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Throws EvalInputError (naming the camera / marker / seq) when the inputs do not belong together:
// a camera or marker in the map that the ground truth lacks, a trajectory seq not in the ground truth,
// no camera or marker in common.
EvalResult Evaluate(const GroundTruth& truth, const RigMap* map,
                    const std::vector<TrajectoryRow>* trajectory);

// The ground truth as an estimator expresses it: rig frame = camera truth.cameras[ref_camera]'s frame,
// object frame = marker truth.markers[ref_marker]'s frame (as the mapper chooses its references).
// trajectory (optional): every frame's rig_from_object in those frames (utime, seq, pose only).
RigMap MapFromGroundTruth(const GroundTruth& truth, size_t ref_camera = 0, size_t ref_marker = 0,
                          std::vector<TrajectoryRow>* trajectory = nullptr);

// Trajectory from trajectory.csv / poses.csv, or from an LCM log of object_pose_t on MCMT_POSE
// (poses with status TRACKING or AMBIGUOUS), recognised by content.
std::vector<TrajectoryRow> ReadTrajectoryAny(const std::string& path);

// The map of one body of a map with several (`object`, mcmt-eval --object): its cameras and layout; for a
// static body, `trajectory` (when empty) gets its one pose at every ground-truth frame. A version 1 map is
// returned as it is (`object` must then be empty or its only object). Throws EvalInputError naming the
// map's objects when `object` is missing or unknown.
RigMap SelectObject(const RigMap& map, const std::string& object, const GroundTruth& truth,
                    std::vector<TrajectoryRow>* trajectory);

std::string FormatTable(const EvalResult& result);
std::string FormatJson(const EvalResult& result);

// ---- several bodies (a version 2 map: mcmt-eval without --object) -------------------------------------

struct BodyResult {
  std::string name;
  bool is_static = false;
  EvalResult result;  // the body's layout, and its poses (a static body: its one pose in every frame)
};

// Every body of `map` against its own ground truth (`truths` by body name: the cameras, its markers in its
// own frame, its pose per frame). A moving body is compared with trajectories->at(name) when there is one
// (else its layout only); a static body's one rig_from_object in every ground-truth frame. The cameras are
// aligned once per body on the same camera centres, so every body's camera figures are the same. Throws
// EvalInputError naming the body without a ground truth, or when the map holds one object (version 1).
std::vector<BodyResult> EvaluateBodies(const std::map<std::string, GroundTruth>& truths, const RigMap& map,
                                       const std::map<std::string, std::vector<TrajectoryRow>>* trajectories);

// ground_truth_<body>.yaml beside `ground_truth` (mcmt-sim --scene bodies) for every body of the map;
// throws EvalInputError naming the missing file and body.
std::map<std::string, GroundTruth> ReadBodyTruths(const std::string& ground_truth, const RigMap& map);

// Trajectories by body: the mapper's OUTDIR (trajectory_<body>.csv), the tracker's --out PATH
// (PATH_<body>.csv; both core's BodyTrajectoryFiles for `map`), or an LCM log with object_pose_t on
// any channel but MCMT_POSE (MCMT_POSE_<BODY> or renamed by tracker.channels; the body named by core's
// BodyOfPose; TRACKING and
// AMBIGUOUS poses). Streams of no body of the map (relative poses, MCMT_POSE_TOOL_IN_PATIENT) are kept
// under their name and ignored by EvaluateBodies.
std::map<std::string, std::vector<TrajectoryRow>> ReadBodyTrajectories(const std::string& path,
                                                                       const RigMap& map);

// The cameras once, then per body its layout and pose figures and its marker table.
std::string FormatBodiesTable(const std::vector<BodyResult>& bodies);
// {"cameras": ..., "map_rms_px": ..., "bodies": [{"name", "static", "markers": ..., "poses": ... | null}]}
// (markers and poses as FormatJson's markers and object; a static body's poses: its one pose per frame).
std::string FormatBodiesJson(const std::vector<BodyResult>& bodies);

}  // namespace sim
}  // namespace mcmt
