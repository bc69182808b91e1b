// The mapper's pipeline, one stage per function, each with typed input and output (Mapper::Solve calls
// them in this order; each is unit-tested alone in tests/mapper/test_mapper_stages.cc):
//
//   messages --AssembleFrames--> frames --CollectObservations--> Observations
//     --EstimateHypotheses--> (IPPE square poses, step 1)
//     --BuildMarkerGraph--> MarkerLayout (object_from_marker, the reference marker, rejected ids; step 3)
//     --FitViews--> ViewPoses (cam_from_object per camera frame)
//     --BuildCameraGraph--> CameraPlacement (rig_from_cam, the reference camera; step 2)
//     --InitialObjectPoses--> ObjectPoses (rig_from_object per frame, weak frames by continuity; step 4)
//     --MakeBundleProblem--> MapperBundle --RefineWithRejection--> (step 5, gross residuals, re-solves)
//     --DropUnreliableCameras--> (--allow-partial; a placeable reference) --FillMap--> RigMap, trajectory
//
// Both graphs are built by one edge builder (BuildGraphEdges in mapper/graph.h). The state a stage needs
// comes in through its arguments; nothing is shared behind the caller's back, so that later work (several
// bodies, a layout held fixed, new unknowns) can call the stages in another order or with other inputs.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/ippe.h"
#include "core/marker.h"
#include "core/se3.h"
#include "mapper/bundle.h"
#include "mapper/graph.h"
#include "mapper/mapper.h"

namespace mcmt {

// ---------------------------------------------------------------------------------------------------
// Inputs as the mapper stores them.

struct StoredMarker {
  int id;
  MarkerCorners2d corners;
};

struct StoredMessage {
  int64_t utime = 0;
  int64_t seq = 0;
  int camera = 0;
  std::vector<StoredMarker> markers;
};

struct Frame {
  int64_t utime = 0;
  int64_t seq = 0;
  std::vector<int> messages;  // indices into the messages
};

// Messages sorted by (utime, camera) join the current frame while within tolerance_us of its first
// message and from a camera not yet in it.
std::vector<Frame> AssembleFrames(const std::vector<StoredMessage>& messages, int num_cameras,
                                  int64_t tolerance_us);

// ---------------------------------------------------------------------------------------------------
// Observations (id whitelist, duplicates) and their square hypotheses.

struct Observation {
  int frame = 0;
  int camera = 0;
  int marker = 0;     // index into Observations::marker_ids
  int view = 0;       // (frame, camera) group
  int64_t utime = 0;  // of the camera's message (its capture time, in its own clock)
  MarkerCorners2d corners;
  double side = 0.0;
  int kept = 0;  // hypotheses kept by the ratio test (0: unusable)
};

struct Observations {
  std::vector<Observation> obs;  // ordered by frame, then message, then detection
  // Per observation its square's pose hypotheses (EstimateHypotheses), read by the graphs and the initial
  // object poses only: a vector of their own, released before the bundle adjustment (SolvePass), whose
  // peak they added 320 of the 448 bytes of every observation to while they were a member of it.
  std::vector<SquarePose> poses;
  std::vector<int> marker_ids;  // marker index -> id, in order of first detection
  std::map<int, int> marker_index;
  std::vector<int> camera_messages;        // detections messages per camera
  std::vector<std::pair<int, int>> views;  // [begin, end) of obs with the same view
  int NumMarkers() const { return static_cast<int>(marker_ids.size()); }
};

// Fills report->ignored_ids, duplicates, duplicate_examples. Throws MapperError when nothing is left.
Observations CollectObservations(const std::vector<StoredMessage>& messages, const std::vector<Frame>& frames,
                                 const std::vector<std::string>& camera_names, const MapperOptions& options,
                                 MapReport* report);

// Step 1: both IPPE hypotheses per observation, `kept` by the ratio test tau_e.
void EstimateHypotheses(const std::vector<CameraModel>& models, double tau_e, int threads,
                        Observations* observations);

// ---------------------------------------------------------------------------------------------------
// Step 3: the marker graph (first: it also finds the ids that are not on the object).

struct MarkerLayout {
  int reference = -1;                      // marker index
  std::vector<bool> placed;                // per marker
  std::vector<Rigid3> object_from_marker;  // per marker (identity where not placed)
  std::vector<int> observations;           // per marker: observations with a kept hypothesis
  std::vector<GraphEdge> edges;            // every co-observed pair
  double ObjectScale() const;              // largest placed marker distance from the origin, >= 5 cm
};

// The marker graph's items (mapper/graph.h): one per observation with a kept hypothesis, marker_from_cam
// and cam_from_marker per hypothesis, grouped by view (camera frame).
// pose_noise_px > 0: each hypothesis with its SquarePoseCovariance for that corner noise.
std::vector<GraphItem> MarkerItems(const Observations& observations, double pose_noise_px = 0.0);

// Fills report->rejected_markers (and warnings with --allow-partial); throws MapperError for a marker
// that cannot be connected (unless allow_partial) or a reference_marker never detected.
MarkerLayout BuildMarkerGraph(const Observations& observations, const MapperOptions& options, int threads,
                              MapReport* report);

// ---------------------------------------------------------------------------------------------------
// Step 2: camera poses through the object.

struct ViewPose {
  int frame = 0, camera = 0;
  std::vector<Rigid3> cam_from_object;  // a lone marker's kept hypotheses, or one fitted pose
  double fit_rms = -1.0;                // several markers: RMS pixel error of the fitted pose
};

// Per camera frame that sees a placed marker: cam_from_object candidates. Several markers give one pose
// fitted to all their corners (core's rigid-pose solver from the best of a few starts).
std::vector<ViewPose> FitViews(const Observations& observations, const MarkerLayout& layout,
                               const std::vector<CameraModel>& models, int threads);

struct CameraPlacement {
  int reference = -1;
  std::vector<bool> placed;
  std::vector<Rigid3> rig_from_cam;
  std::vector<GraphEdge> edges;
  std::vector<int> views;       // per camera: views with a placed marker
  std::vector<double> fit_rms;  // per camera: median fit_rms of its multi-marker views (-1: none)
};

// Fills report->dropped_cameras and warnings (--allow-partial); throws MapperError naming a camera
// that cannot be placed (unless allow_partial) or a reference_camera that never saw the object.
CameraPlacement BuildCameraGraph(const std::vector<ViewPose>& views, const Observations& observations,
                                 const std::vector<std::string>& camera_names, const MapperOptions& options,
                                 int threads, MapReport* report);

// ---------------------------------------------------------------------------------------------------
// Step 4: the object's pose per frame.

struct ObjectPoses {
  std::vector<Rigid3> rig_from_object;  // per frame
  std::vector<char> has_pose;           // per frame
  std::vector<char> usable;             // per observation: kept, marker and camera placed
};

// The medoid of the frame's candidates; frames seen by one camera (or whose observations disagree) are
// decided by continuity with the nearest decided frame within continuity_gap_s. Fills
// report->weak_frames, undecided_frames.
ObjectPoses InitialObjectPoses(const Observations& observations, const std::vector<Frame>& frames,
                               const MarkerLayout& layout, const CameraPlacement& cameras,
                               const MapperOptions& options, int threads, MapReport* report);

// ---------------------------------------------------------------------------------------------------
// Step 5: the bundle adjustment and what it rejects.

struct MapperBundle {
  BundleProblem problem;
  std::vector<int> observation;       // bundle observation -> index into Observations::obs
  std::vector<char> marker_rejected;  // per marker
};

// What names a rejected observation in the report.
struct ObservationNames {
  const std::vector<Frame>* frames;
  const std::vector<std::string>* camera_names;
  const std::vector<int>* marker_ids;
};

// Deactivates bundle observation k and records why.
void RejectObservation(const MapperBundle& bundle, const Observations& observations,
                       const ObservationNames& names, size_t k, double rms_px, const std::string& reason,
                       BundleProblem* problem, MapReport* report);

// The problem at the initial poses (reference camera and marker constant); observations behind a
// camera at the start are rejected.
MapperBundle MakeBundleProblem(const Observations& observations, const ObservationNames& names,
                               const MarkerLayout& layout, const CameraPlacement& cameras,
                               const ObjectPoses& poses, const std::vector<CameraModel>& models,
                               MapReport* report);

BundleSettings BundleSettingsFor(const MapperOptions& options, int threads);

// A solve whose result only starts or scales a later one (the time offsets' first pass, which finds the
// clocks the frames are re-assembled on; the poses-first solve before the intrinsics join) stops when the
// RMS improves by less than this multiple of the paper's threshold.
constexpr double kRoughStopFactor = 10.0;

// Solve, reject gross residuals (> outlier_px) and markers mostly rejected, re-solve, up to
// max_rejection_rounds times; with clocks, re-solved velocity_passes times more with the frames'
// velocities updated. Throws MapperError when a solve fails.
void RefineWithRejection(const Observations& observations, const ObservationNames& names,
                         const MarkerLayout& layout, const MapperOptions& options,
                         const BundleSettings& settings, MapperBundle* bundle, MapReport* report,
                         int velocity_passes = 2);

// A camera whose observations mostly do not fit after refinement was placed wrongly: an error naming
// it (which says when it is the reference), or with --allow-partial it is left out and the rest re-solved;
// a bad reference is replaced by the best-connected camera that fits (the map re-expressed in its frame).
void DropUnreliableCameras(const Observations& observations, const ObservationNames& names,
                           const MapperOptions& options, const BundleSettings& settings,
                           CameraPlacement* cameras, MapperBundle* bundle, MapReport* report);

// Which row each of num_messages messages went to (frames: the pass's, row_frames: FillMap's).
FrameMembership MembershipOf(const std::vector<Frame>& frames, const std::vector<int>& row_frames,
                             size_t num_messages);

// The map and trajectory at the bundle's current parameters, refined intrinsics included (statistics
// over active observations). row_frames (optional): the frame index of each trajectory row.
void FillMap(const MapperBundle& bundle, const Observations& observations, const ObservationNames& names,
             const MarkerLayout& layout, const CameraPlacement& cameras, const MapperOptions& options,
             RigMap* map, std::vector<TrajectoryRow>* trajectory, std::vector<int>* row_frames = nullptr);

// The options' consistency thresholds (consistency_deg, consistency_m, consistency_rel).
ConsistencyOptions ConsistencyFor(const MapperOptions& options);

// "a, b, c, ..." (at most `max` names).
std::string JoinNames(const std::vector<std::string>& names, size_t max = 12);
// v with `digits` digits after the point (messages and warnings).
std::string Fixed(double v, int digits);

}  // namespace mcmt
