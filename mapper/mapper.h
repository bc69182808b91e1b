// The mapper: from detections of a rigid marker object seen by fixed cameras, finds every camera's
// pose (rig_from_cam), the marker layout (object_from_marker) and the object's pose in every frame
// (rig_from_object): the paper's graph initialisation (steps 1-4) then a Ceres bundle adjustment (step 5)
// with robust loss, gross-residual rejection and removal of marker ids that are not rigidly attached.
//
//   mcmt::Mapper mapper(mcmt::MapperOptions::FromConfig(rig));
//   for (const auto& d : detections) mapper.Add(d);
//   mcmt::MapResult result = mapper.Solve();       // throws MapperError with a one-line reason
//   mcmt::WriteMapOutputs("out", result);          // map.yaml, trajectory.csv, report.json, *_initial
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/files.h"
#include "core/marker.h"
#include "core/se3.h"
#include "mcmt/detections_t.hpp"

namespace mcmt {

class MapperError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Self-calibration of the intrinsics (mapper/intrinsics.h has the method).
enum class IntrinsicsRefinement { kNone, kFocal, kFocalCenter, kAll };
IntrinsicsRefinement IntrinsicsRefinementFromName(const std::string& name);  // throws std::invalid_argument
std::string IntrinsicsRefinementName(IntrinsicsRefinement refinement);

// Prior standard deviations of the given intrinsics.
struct IntrinsicsSigma {
  double focal_rel = 0.05;    // fx, fy: relative (0.05: 5 % of the focal length)
  double center_px = 20.0;    // cx, cy, pixels
  double radial = 0.05;       // k1, k2, k3 (and fisheye k1..k4)
  double tangential = 0.005;  // p1, p2
};

struct IntrinsicsSettings {
  IntrinsicsRefinement refine = IntrinsicsRefinement::kNone;
  std::vector<std::string> cameras;  // only these (empty: all)
  IntrinsicsSigma sigma;
  double observability_ratio = 0.5;  // refined only where posterior sigma < ratio * prior sigma
};

// What the self-calibration did with one camera (report.json).
struct IntrinsicsReport {
  std::string camera;
  int index = 0;  // camera index in the problem
  std::vector<std::string> names;
  std::vector<double> given, refined;
  std::vector<double> prior_sigma;      // per entry
  std::vector<double> posterior_sigma;  // per entry (refined entries; 0 for the others)
  std::vector<char> is_refined;         // per entry
  std::vector<std::string> held;        // "cx: ..." why an entry asked for stays at its prior
  double coverage = 0.0;                // fraction of an 8 x 6 grid of image cells holding corners
  int views = 0;
};

// One rigid body of a rig with several (the rig's objects:; core/objects.h).
struct MapperBody {
  std::string name;
  bool is_static = false;
  std::vector<int> ids;  // explicit ids
  bool other = false;    // every id no other body claims
  MarkerSizes sizes;
  bool auto_ids = false;  // ids: auto (objects: auto: with no name): found by the mapper (bodies_auto.h)
};

// What `objects: auto` / `ids: auto` found (mapper/bodies_auto.h; report.json "auto_objects").
struct FoundBody {
  std::string name;
  bool is_static = false;
  std::vector<int> ids;  // sorted
  int observations = 0;
  std::vector<std::string> cameras;  // that see it
  std::string declared_as;           // the `ids: auto` object it became (empty: named by the mapper)
};

struct ForeignId {
  int id = 0;
  int observations = 0;
  std::string reason;
};

struct AutoBodies {
  bool ran = false;
  std::vector<FoundBody> bodies;
  std::vector<ForeignId> foreign;  // ids seen that join no body
  std::string objects_yaml;        // a ready objects: section (objects.yaml beside map.yaml)
};

struct MapperOptions {
  // Step 1: keep both IPPE hypotheses when e2 / e1 < tau_e.
  double tau_e = 2.0;
  // Graph edge cost e = (d / s) * max(1, tau_n / s).
  double tau_n = 10.0;
  // Robust loss: an observation's Huber threshold on its RMS corner error, pixels.
  double huber_px = 1.0;
  // Corners of a marker seen at a view angle theta (between its normal and the direction to the camera,
  // from the current estimate) are located less precisely the more the marker is foreshortened: their
  // squared residuals are weighted by cos(theta)^view_weight_power (2: sigma ~ 1 / cos theta; 0: no
  // weighting). On renders of the paper's rig the detector's RMS corner error grows as 1 / cos^1.5-2 above
  // 60 deg (issue 15); 3 takes mcmt-sim's default imaging at 1.0 m from 0.86 to 0.19 mm, but makes the
  // conditions whose corners are biased (blur, no margin, webcam) worse (BENCHMARKS.md): off by default.
  double view_weight_power = 0.0;
  // How a corner's x and y residuals weigh: "equal", or "sides": the detector's corners are intersections
  // of the marker's fitted sides, each located along its normal; a corner where two sides meet at a
  // narrow angle (a marker seen steeply) is barely located along them (CornerSqrtInformation, core/marker.h).
  // Keys corner_weights (mode) and corner_weight_floor (floor).
  CornerWeighting corner_weighting;
  // After the first solve, observations whose RMS corner error exceeds this are rejected (gross), pixels.
  double outlier_px = 5.0;
  // Outlier rounds: solve, reject, re-solve at most this many times.
  int max_rejection_rounds = 3;
  int max_iterations = 100;
  // The paper's stopping rule: stop when the RMS reprojection error improves by less than paper_stop_px.
  bool paper_stop = true;
  double paper_stop_px = 1e-4;
  int threads = 0;  // 0: all cores
  // "auto" (dense Schur for small reduced systems, sparse Schur otherwise), "sparse_schur",
  // "dense_schur", "iterative_schur".
  std::string linear_solver = "auto";
  bool refine = true;  // false: initialisation only
  // Intrinsics refined in the bundle adjustment (refine_intrinsics, intrinsics_sigma, ...).
  IntrinsicsSettings intrinsics;
  // Per-camera clock offsets against the reference camera (true capture time = utime - offset),
  // estimated in the bundle adjustment; frames are first assembled with max_time_offset_ms, then again
  // with the clocks corrected.
  bool estimate_time_offsets = false;
  double max_time_offset_ms = 25.0;
  // With the offsets: a linear drift per camera (true capture time = utime - offset - drift * (utime -
  // the session's middle)), reported as time_drift_ppm.
  bool estimate_clock_drift = false;

  // References: best connected unless named.
  std::string reference_camera;
  int reference_marker = -1;

  // Frames: detections whose utime lies within this of a frame's first detection join it (the rig's
  // sync.tolerance_ms).
  double sync_tolerance_ms = 2.0;
  int64_t sync_tolerance_us() const { return static_cast<int64_t>(std::llround(sync_tolerance_ms * 1000.0)); }
  // Map the connected part instead of failing on a camera or marker that cannot be connected (and write a
  // map no camera supports, with a warning).
  bool allow_partial = false;
  // A map is an error (mapper/diagnostics.h UnsupportedMapText) when every camera with enough inliers has
  // a reprojection RMS above unsupported_rms_ratio x the RMS its corner noise predicts and above
  // unsupported_side_fraction x its markers' median side (0: no check).
  double unsupported_rms_ratio = 3.0;
  double unsupported_side_fraction = 0.04;
  // The printed marker size's relative 1-sigma, percent: a scale every marker shares, which the map absorbs
  // whole; the covariance the mapper writes (map.yaml covariance, report.json diagnostics) holds it as a
  // common scale about the reference camera and marker (mapper/diagnostics.cc MarkerSizeScaleDirection).
  // 0: the size is exact. The estimate is not changed.
  double marker_size_sigma_percent = 0.0;

  // Marker ids that do not belong to the rigid object: a marker must be seen together with another
  // marker (same camera, same frame) in at least min_marker_support frames, in at least
  // marker_inlier_fraction of which their relative pose agrees (within consistency_deg and
  // consistency_m + consistency_rel * distance) with the chosen (medoid) relative pose.
  int min_marker_support = 3;
  double marker_inlier_fraction = 0.3;
  double consistency_deg = 15.0;
  double consistency_m = 0.02;
  double consistency_rel = 0.15;
  // ... or, in the marker graph, within the square poses' noise: the squared Mahalanobis distance of a
  // frame's relative pose from the edge's under twice the frame's covariance (composed of its two squares'
  // IPPE poses with consistency_noise_px on every corner coordinate, mapper/graph.h SquarePoseCovariance) at
  // most chi^2(6 dof, 0.999) = 22.46. A 10-16 px square's pose is pinned only where its corners are: the
  // tolerances above rejected 18 of 26 frames of a marker pair that the true corners + noise agree in
  // (0: the tolerances above only).
  double consistency_noise_px = 0.5;
  // After refinement, a marker with more than this fraction of its observations rejected is dropped.
  double marker_reject_fraction = 0.5;
  // At most this many co-observation events per camera or marker pair enter the medoid (strided subset).
  int max_pair_events = 3000;
  // A frame whose markers are all seen by one camera (planar ambiguity) takes, among both hypotheses of
  // each of its markers, the pose nearest in rotation to the nearest decided frame at most this far away
  // in time (0: the paper's rule alone).
  double continuity_gap_s = 0.5;
  // Cameras that moved during the session (mapper/epochs.h): split into two epochs when the change-point
  // statistic exceeds move_min_score and the epochs differ by move_min_deg or move_min_mm.
  bool detect_moves = true;
  double move_min_score = 200.0;
  double move_min_deg = 0.15;
  double move_min_mm = 1.5;
  double move_min_rms_ratio =
      2.0;  // ... and its RMS with one pose exceeds this multiple of the median camera's
  // Maintenance (mcmt-mapper --maintain, mapper/maintain.h): frames seen by the others collected before a
  // suspect camera is re-estimated (a new camera: maintain_added_frames); the result is published when the
  // camera's RMS is at most maintain_max_rms_ratio x the other cameras' median.
  int maintain_frames = 200;
  int maintain_added_frames = 300;
  double maintain_max_rms_ratio = 2.0;

  // From the rig: expected cameras (empty: whatever sends detections), marker id whitelist, sizes.
  std::vector<std::string> cameras;
  std::vector<int> marker_ids;
  MarkerSizes sizes;
  std::string dictionary;
  // Several bodies (the rig's objects:, more than one; mapper/bodies.h): empty for a single object.
  // rig_frame: a static body whose frame becomes the rig frame (empty: the reference camera's).
  std::vector<MapperBody> bodies;
  std::string rig_frame;

  // Reads the rig's `mapper:` section (keys as the fields above, declared in mapper/options.cc) and
  // `sync: {tolerance_ms}`; throws OptionError naming the file and key.
  static MapperOptions FromConfig(const RigConfig& rig);
  // The same checks as FromConfig, for options built in code (file empty) or read from `file`.
  void Validate(const std::string& file = "") const;  // throws OptionError
};

// Every `mapper:` key: name, member, unit, check, help (loading, validation and docs).
template <class T>
class OptionTable;
const OptionTable<MapperOptions>& MapperOptionTable();

// Progress for status messages and terminal bars.
struct MapperProgress {
  enum Stage { kInitialising = 1, kRefining = 2, kDone = 3 };
  Stage stage = kInitialising;
  std::string step;  // "frames", "hypotheses", "markers", "cameras", "object poses", "refine", ...
  int iteration = 0;
  int max_iterations = 0;
  double cost = 0.0;
  double rms_px = 0.0;
  std::string message;
};

struct RejectedMarker {
  int id = 0;
  int observations = 0;
  std::string reason;
};

struct RejectedObservation {
  int64_t utime = 0;
  int64_t seq = 0;
  std::string camera;
  int id = 0;
  double rms_px = 0.0;  // RMS corner error when rejected
  std::string reason;
};

// A camera that moved during the session (mapper/epochs.h), or since the old map (mapper/update.h).
struct MovedCamera {
  std::string camera;
  int64_t seq = 0;              // first frame seq after the move (offline update: -1, moved before the log)
  int64_t utime = 0;            // that frame's utime
  double translation_mm = 0.0;  // camera centre, latest pose against the earlier one
  double rotation_deg = 0.0;
  Rigid3 rig_from_cam_before = Rigid3::Identity();
  int observations_before = 0;  // observations the earlier pose kept (in one session)
};

struct MapReport {
  int detections_messages = 0;
  int frames_assembled = 0;
  int frames_used = 0;
  int observations_total = 0;  // marker observations after the id whitelist
  int observations_used = 0;
  int ambiguous_observations = 0;  // both IPPE hypotheses kept
  int ignored_ids = 0;             // detections of ids outside markers.ids
  int duplicates = 0;              // same id twice in one camera frame (both dropped)
  int weak_frames = 0;             // frames seen by one camera only (object pose decided by continuity)
  int undecided_frames = 0;        // ... of which with no decided frame near enough (medoid kept)
  std::vector<std::string> duplicate_examples;
  std::vector<RejectedMarker> rejected_markers;
  std::vector<RejectedObservation> rejected_observations;
  std::vector<std::string> dropped_cameras;  // --allow-partial: cameras that could not be placed
  std::vector<MovedCamera> moved_cameras;    // solved with one pose per epoch; the map holds the latest
  std::vector<std::string> added_cameras;    // offline update: cameras the old map lacked
  std::vector<std::string> warnings;
  double initial_rms_px = 0.0;
  double final_rms_px = 0.0;
  int iterations = 0;
  int solves = 0;
  std::string termination;
  std::string linear_solver;
  int threads = 0;
  double marker_size_sigma_percent = 0.0;    // MapperOptions', for the diagnostics' covariance
  std::vector<IntrinsicsReport> intrinsics;  // cameras whose intrinsics were considered for refinement
  AutoBodies auto_bodies;                    // objects: auto / ids: auto
  std::vector<std::pair<std::string, double>> stage_seconds;  // in order
  double total_seconds = 0.0;
};

// How the bundle grouped the input into the trajectory's frames (for mapper/diagnostics.h): per detections
// message the trajectory row of its frame (-1: none), per row its frame's utime as assembled (on the clocks
// of the pass that assembled it: the utime report.rejected_observations name the frame by). Empty when not
// known (the diagnostics then find rows by time).
struct FrameMembership {
  std::vector<int> row_of_detection;
  std::vector<int64_t> frame_utime_of_row;
};

struct MapResult {
  RigMap map;                                     // refined
  RigMap initial_map;                             // after the graph initialisation, before refinement
  std::vector<TrajectoryRow> trajectory;          // refined rig_from_object per frame
  std::vector<TrajectoryRow> initial_trajectory;  // initial
  // Several bodies: per body of map.objects, its refined and initial trajectories (empty for a static
  // body); `trajectory` is then the first moving body's.
  std::vector<std::vector<TrajectoryRow>> object_trajectories, initial_object_trajectories;
  MapReport report;
  std::vector<detections_t> detections;  // the input, as given to Add() (for mapper/diagnostics.h)
  FrameMembership membership;            // of `detections` in `trajectory`
};

// Per-camera counts while collecting (live progress).
struct CameraCollectStats {
  std::string name;
  int frames = 0;        // detections messages
  int observations = 0;  // marker observations
  std::set<int> ids;
  bool connected = false;  // shares a frame with marker observations with the best-connected group
};

class Mapper {
 public:
  explicit Mapper(MapperOptions options);
  ~Mapper();

  // Adds one camera's detections for one frame (any order, any camera).
  void Add(const detections_t& detections);
  void Reset();
  int NumMessages() const;
  // Frames as the max over cameras of messages received (cheap, for --frames).
  int NumFramesApprox() const;
  // Collect-time statistics; `connected` assembles frames (O(n log n)).
  std::vector<CameraCollectStats> CollectStats() const;

  void SetProgressCallback(std::function<void(const MapperProgress&)> callback);

  // Runs the whole method. Throws MapperError with a one-line reason (disconnected camera, no data...).
  MapResult Solve();

  // The offline update (mapper/update.h): Solve() starts from this map (its layout held fixed unless
  // refine_layout), re-estimates the cameras that moved (only_cameras not empty: only those may be) and
  // adds the rig's cameras it lacks.
  void SetBaseMap(const RigMap& old_map, bool refine_layout,
                  const std::vector<std::string>& only_cameras = {});

  const MapperOptions& options() const { return options_; }

 private:
  struct Impl;
  MapperOptions options_;
  std::unique_ptr<Impl> impl_;
};

// OUTDIR/map.yaml, trajectory.csv, report.json, map_initial.yaml, trajectory_initial.csv, residuals.csv
// (atomic each; creates OUTDIR). Returns the per-camera verdict lines (mapper/diagnostics.h).
std::string WriteMapOutputs(const std::string& outdir, const MapResult& result);
std::string ReportJson(const MapResult& result);

}  // namespace mcmt
