// Real-time tracking of the object with a known map (the paper's section 6): per frame, the pose
// rig_from_object minimising the reprojection error of every mapped marker seen by every mapped camera.
//
// PoseEstimator: the per-frame solver (no LCM). Levenberg-Marquardt over 6 parameters with an analytic
// Jacobian, started from a prediction (constant velocity) or, when lost, from the single-marker IPPE
// hypotheses (best ratio first, every candidate scored against all observations). Markers whose
// residual stays gross are dropped and counted. One marker seen by one camera works and is flagged
// ambiguous when both planar solutions are plausible.
//
// TrackerNode: the process around it. Subscribes MCMT_DETECTIONS_.* and MCMT_MAP (live always: a newer map
// replaces the map file too; in a log only without a map file), assembles frames with core's
// FrameSynchronizer, publishes object_pose_t, keeps the trajectory.
#pragma once

#include <array>
#include <cstdint>
#include <cstdio>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/files.h"
#include "core/frame_sync.h"
#include "core/lcm_util.h"
#include "core/log_reader.h"
#include "core/map_covariance.h"
#include "core/marker.h"
#include "core/rigid_pose.h"
#include "core/se3.h"
#include "core/stop.h"
#include "mcmt/detections_t.hpp"
#include "mcmt/object_pose_t.hpp"
#include "mcmt/rig_map_t.hpp"
#include "tracker/health.h"

namespace mcmt {

// Settings of the tracker, from the rig YAML's `tracker:` section (keys as the field names).
struct TrackerOptions {
  std::string channel = "MCMT_POSE";  // output channel
  std::string object = "object";      // object name put in object_pose_t
  // Frame assembly: a frame is solved when every alive camera reported it, or deadline_ms after its
  // first detection (wall time live, message time with --log), so one slow camera never stalls the rest.
  double deadline_ms = 15.0;
  // Live: a frame missing a camera whose messages lag (measured per camera) waits for it up to this long
  // after the frame's first detection; deadline_ms is the wait for cameras without a measured lag.
  double max_wait_ms = 100.0;
  double sync_tolerance_ms = 2.0;  // detections within this of a frame's utime belong to it
  // Set by hand (tracker.sync_tolerance_ms or sync.tolerance_ms in the rig, or in code): used as it is.
  // Otherwise, with a map that carries clock offsets, the tracker measures the cameras' phases over their
  // first frames and widens the window when they are not triggered together (ChooseSyncWindow).
  bool sync_tolerance_set = false;
  double camera_timeout_s = 1.0;  // a camera silent this long (message time) is not waited for
  // A message whose utime is more than this ahead of its camera's clock (or of the other cameras', for
  // a camera's first messages) is rejected with a warning naming the camera; 0: no check.
  double max_clock_jump_s = 5.0;
  // Solver.
  int max_iterations = 20;             // Levenberg-Marquardt iterations per start
  double huber_px = 1.0;               // Huber threshold of the robust loss, pixels (corner distance)
  double outlier_px = 4.0;             // a marker observation whose RMS corner error exceeds this is dropped
  double ambiguity_ratio = 2.0;        // tau_e: see options.cc (IPPE ratio, or refined other pose)
  double max_gap_s = 0.5;              // no prediction across a gap longer than this (re-initialise)
  double min_sigma_px = 0.02;          // floor of the residual standard deviation used for the covariance
  double noise_prior_residuals = 8.0;  // nu0: pseudo-residuals at the map's noise in that deviation
  // The published covariance holds the map's error too when the map file has its covariance
  // (core/map_covariance.h; PoseEstimator::Describe); false: the frame's noise alone, as before.
  bool map_uncertainty = true;
  int max_start_markers = 12;  // when lost: IPPE hypotheses of at most this many observations
  // How a corner's x and y residuals weigh (keys corner_weights and corner_weight_floor; core/marker.h: a
  // corner where the marker's sides meet at a narrow angle is barely located along them).
  CornerWeighting corner_weighting;
  double status_period_s = 5.0;  // status line period (wall time); 0: none
  // Per-camera health (tracker/health.h), published on MCMT_TRACKER_STATUS; false: every camera is used.
  // Keys camera_health and health_* (health_gate_px, health_window_frames, ...).
  bool camera_health = true;
  HealthOptions health;
  // Several bodies (a version 2 map): one pose stream per moving body on channel + "_" + NAME
  // (MCMT_POSE_TOOL) and one per relative pose on channel + "_" + OF + "_IN_" + IN; `channels` (key
  // channels: {tool: X, tool_in_patient: Y}) overrides a stream's channel by its name.
  struct Relative {
    std::string of, in;  // publishes in_from_of: the pose of body `of` in body `in`'s frame
  };
  std::map<std::string, std::string> channels;
  std::vector<Relative> relative;  // key relative: [{of: tool, in: patient}]

  // Keys declared once in tracker/options.cc (TrackerOptionTable); the sync: section gives the defaults of
  // deadline_ms, sync_tolerance_ms and camera_timeout_s.
  static TrackerOptions FromConfig(const RigConfig& rig);  // throws OptionError naming file and key
  void Validate() const;  // the same checks for options built in code; throws OptionError naming the key
};
template <class T>
class OptionTable;
const OptionTable<TrackerOptions>& TrackerOptionTable();

// The frame assembly window chosen from the cameras' capture times (utime on the reference clock, the
// map's offsets applied) over their first frames. Each camera's frame interval is the median step of its
// times; the phase between two cameras the median distance from one's times to the nearest of the
// other's; the spread the largest phase between two cameras. A spread within `tolerance_ms`: the cameras
// are triggered together and the window stays `tolerance_ms`. Otherwise the window is half the frame
// interval of the slowest camera (so that no camera has two views in one frame), at most
// kMaxAutoSyncWindowMs; the views of a frame are then moved to their capture times along the body's
// velocity (PoseEstimator::SeenAt).
constexpr double kMaxAutoSyncWindowMs = 100.0;
struct SyncWindowChoice {
  double tolerance_ms = 0.0;
  bool widened = false;
  double spread_ms = 0.0;            // the largest phase between two cameras
  double slowest_interval_ms = 0.0;  // the slowest camera's frame interval (0: none measured)
  std::string reason;                // one line: what was measured, what was chosen
};
SyncWindowChoice ChooseSyncWindow(const std::map<std::string, std::vector<int64_t>>& capture_utimes,
                                  double tolerance_ms);

// A body the tracker knows of: from the map (or the rig's objects: list).
struct BodyName {
  std::string name;
  bool is_static = false;
};
// One pose stream of the tracker: a moving body's, or a relative pose's.
struct PoseStreamPlan {
  std::string name;      // the body's ("tool"), a relative pose's ("tool_in_patient")
  std::string channel;   // MCMT_POSE_TOOL, MCMT_POSE_TOOL_IN_PATIENT; a single object: tracker.channel
  int body = -1;         // a moving body: its index in the bodies; -1 for a relative pose
  int of = -1, in = -1;  // a relative pose: indices in the bodies (`in` may be a static body)
};
// The streams for these bodies (`single`: a one-object map, named tracker.object, on tracker.channel).
// Throws OptionError naming `file` and the key: a relative pose or a channel naming an unknown or static
// body, a body relative to itself, two streams on one channel, a stream on another mcmt channel.
std::vector<PoseStreamPlan> PlanPoseStreams(const TrackerOptions& options,
                                            const std::vector<BodyName>& bodies, bool single,
                                            const std::string& file = "");
// The bodies of a map: version 1 one body named `single_name`; version 2 every object.
std::vector<BodyName> MapBodies(const RigMap& map, const std::string& single_name);

// One marker seen by one camera in the frame being solved.
struct MarkerObservation {
  std::string camera;
  int id = 0;
  MarkerCorners2d corners;  // distorted pixels, ArUco order
  int64_t utime = 0;        // its view's capture time (the reference camera's clock)
  // Set by PoseEstimator::SeenAt for a view captured at another time than its frame's: the camera's pose
  // for it, cam_from_rig x the object's motion from the frame's time to the view's.
  bool moved = false;
  Rigid3 cam_from_rig = Rigid3::Identity();
};

// All markers of a frame's views (views sorted by camera name, so the result never depends on the
// order in which the cameras' messages arrived).
std::vector<MarkerObservation> ObservationsFromViews(const std::vector<detections_t>& views);

enum class PoseStatus : int8_t { kTracking = 0, kLost = 1, kAmbiguous = 2 };
const char* PoseStatusName(PoseStatus status);

struct PoseSolution {
  PoseStatus status = PoseStatus::kLost;
  Rigid3 rig_from_object = Rigid3::Identity();
  // Covariance in object_pose_t's order (tx, ty, tz, rx, ry, rz) for rig_from_object = Exp(delta) *
  // estimate: the frame's noise (scaled by the residual variance, floored at min_sigma_px^2) plus, with
  // the map's covariance, the map's error propagated through the solve.
  Matrix6d covariance = Matrix6d::Zero();
  // The frame's noise alone: `covariance` without the map's share.
  Matrix6d noise_covariance = Matrix6d::Zero();
  double rms_px = 0.0;               // RMS corner error of the observations used
  std::vector<std::string> cameras;  // cameras whose markers were used (sorted)
  std::vector<int> markers;          // distinct marker ids used (sorted)
  int num_observations = 0;          // marker observations used
  int num_rejected = 0;              // mapped observations dropped as outliers
  int num_unmapped = 0;              // observations of cameras or markers not in the map (ignored)
  int iterations = 0;                // LM iterations, all starts together
  bool from_prior = false;           // the prediction was the start that won
  double ippe_ratio = 0.0;           // single observation: its IPPE ratio (else 0)
  bool ok() const { return status != PoseStatus::kLost; }
};

class PoseEstimator {
 public:
  // Throws std::invalid_argument when the map has no camera or no marker or a bad camera model.
  // map_covariance: the map's (ReadMapCovariance), whose error then enters every pose's covariance.
  PoseEstimator(const RigMap& map, const TrackerOptions& options = {},
                const MapCovariance* map_covariance = nullptr);

  // prior: predicted rig_from_object (nullptr when lost). Deterministic for the same inputs.
  PoseSolution Solve(const std::vector<MarkerObservation>& observations, const Rigid3* prior) const;

  const RigMap& map() const { return map_; }

  // The observation's object seen moved by rig_motion (the object at the view's capture time =
  // rig_motion x rig_from_object at the frame's): its camera's pose for it becomes cam_from_rig x
  // rig_motion (unchanged for a camera not in the map).
  void SeenAt(const Rigid3& rig_motion, MarkerObservation* observation) const;

  // The observation's corners as core's rigid-pose points (world = rig, body = object; pointers into this
  // estimator and into `observation`), for the normal equations that judge cameras (tracker/health.cc);
  // empty when its camera or marker is not mapped or a corner is not finite.
  std::vector<PosePoint> PosePoints(const MarkerObservation& observation) const;

  // RMS corner error of the mapped observations at `pose` (-1 when none is mapped; +inf when a corner
  // falls behind its camera).
  double RmsAt(const std::vector<MarkerObservation>& observations, const Rigid3& pose) const;

 private:
  struct Camera {
    std::string name;
    CameraModel model;
    Rigid3 rig_from_cam;
    Rigid3 cam_from_rig = Rigid3::Identity();
  };
  struct Marker {
    int id = 0;
    double size = 0.0;
    Rigid3 object_from_marker;
    std::array<Eigen::Vector3d, 4> corners_object;  // corners in the object frame
  };
  struct Obs {
    int camera = 0;
    int marker = 0;
    const MarkerCorners2d* pixels = nullptr;
    const Rigid3* cam_from_rig = nullptr;  // the camera's, or the observation's when moved
  };
  struct Refined {
    Rigid3 pose;
    std::vector<char> inlier;
    int num_inliers = 0;
    double cost = 0.0;  // sum of squared corner errors over the inliers
    int iterations = 0;
    bool valid = false;
  };

  // The mapped observations with finite corners (the others counted in *unmapped).
  std::vector<Obs> Mapped(const std::vector<MarkerObservation>& observations, int* unmapped) const;
  // One observation's indices; false when its camera or marker is not mapped or a corner is not finite.
  bool ToObs(const MarkerObservation& observation, Obs* obs) const;
  // Per-observation RMS corner error at `pose` (infinite when a corner is behind the camera).
  double ObservationRms(const Obs& obs, const Rigid3& pose) const;
  // The corners of the active observations, for core's rigid-pose solver (core/rigid_pose.h).
  std::vector<PosePoint> Points(const std::vector<Obs>& obs, const std::vector<char>& active) const;
  // Levenberg-Marquardt on the active observations.
  void Optimise(const std::vector<Obs>& obs, const std::vector<char>& active, Rigid3* pose,
                int* iterations) const;
  // LM with outlier rejection from one start.
  Refined RefineFrom(const std::vector<Obs>& obs, const Rigid3& start) const;
  static bool Better(const Refined& a, const Refined& b);
  // A pose from one observed square (either of an ambiguous square's two), scored against all observations
  // (inliers within 3 outlier_px, a capped squared error).
  struct Hypothesis {
    Rigid3 pose;
    double ratio;  // the square's IPPE ratio
    int inliers;
    double cost;
  };
  // The single-square hypotheses of the observations with the largest image footprint (max_start_markers;
  // they give the best single-square poses), best first: most inliers, then lowest cost, then highest ratio.
  std::vector<Hypothesis> SquareHypotheses(const std::vector<Obs>& obs) const;
  // The best hypotheses refined; one replaces *best if better (against the prediction's result: more
  // inliers, or as many at half the cost).
  void RefineHypotheses(const std::vector<Obs>& obs, Refined* best, bool* from_prior, int* iterations) const;
  // sol's pose, covariance, RMS, counts, cameras, markers and status from the refined solution.
  void Describe(const std::vector<Obs>& obs, const Refined& best, PoseSolution* sol) const;
  // The map's share of the pose covariance (rotation first, about the rig origin): blocks[i] the active
  // observation i's J^T J at `pose`, h_inverse the inverse of their sum.
  Matrix6d MapShare(const std::vector<Obs>& obs, const std::vector<char>& active, const Rigid3& pose,
                    const std::vector<Matrix6d>& blocks, const Matrix6d& h_inverse) const;

  RigMap map_;
  TrackerOptions options_;
  std::vector<Camera> cameras_;
  std::vector<Marker> markers_;
  std::optional<MapCovariance> map_covariance_;
  std::vector<int> camera_entry_, marker_entry_;  // per camera / marker: its entry in map_covariance_, or -1
  std::map<std::string, int> camera_index_;
  std::map<int, int> marker_index_;
};

// Throws std::runtime_error (one line) when the map's cameras are not cameras of the rig config.
void CheckMapMatchesRig(const RigMap& map, const RigConfig& rig, const std::string& map_name);

// Constant-velocity prediction from the two last poses: pose at `utime`. With one pose: that pose.
class MotionModel {
 public:
  explicit MotionModel(double max_gap_s = 0.5) : max_gap_us_(static_cast<int64_t>(max_gap_s * 1e6)) {}
  void Update(int64_t utime, const Rigid3& rig_from_object);
  void Reset() { count_ = 0; }
  // False (no prediction) when nothing is known or the last pose is older than max_gap.
  bool Predict(int64_t utime, Rigid3* predicted) const;
  // The object's motion in the rig frame from `from` to `to` at constant velocity (Predict(to) x
  // Predict(from)^-1); false without a velocity (fewer than two poses, or too far apart).
  bool Motion(int64_t from, int64_t to, Rigid3* rig_motion) const;

 private:
  int64_t max_gap_us_;
  int count_ = 0;
  int64_t utime_[2] = {0, 0};  // [0] newest
  Rigid3 pose_[2];
};

struct TrackerStats {
  int64_t frames = 0;   // frames solved (with a map)
  int64_t tracked = 0;  // TRACKING or AMBIGUOUS
  int64_t ambiguous = 0;
  int64_t lost = 0;
  int64_t rejected = 0;        // outlier observations
  int64_t no_map = 0;          // frames dropped before a map was known
  int64_t bad_messages = 0;    // undecodable detections
  int64_t unknown_camera = 0;  // detections of cameras not in the map
  int64_t map_switches = 0;
  int64_t late_views = 0;       // views that arrived after their frame was solved (dropped)
  int64_t duplicates = 0;       // repeated messages (same camera, seq, utime), dropped
  int64_t invalid = 0;          // messages dropped for their content (camera vs channel, camera model)
  int64_t invalid_markers = 0;  // markers with non-finite or absurd corners, dropped
  int64_t clock_jumps = 0;      // messages whose utime is far from their camera's or the others' (dropped)
};

// What the tracker published on one pose stream (a moving body's or a relative pose's).
struct PoseStream {
  std::string name;                       // "tool", "tool_in_patient"; a single object: tracker.object
  std::string channel;                    // where its object_pose_t go
  bool single = false;                    // the one stream of a single-object map (--out writes OUT itself)
  std::vector<TrajectoryRow> trajectory;  // its TRACKING/AMBIGUOUS poses (keep_trajectory)
  int64_t frames = 0;                     // frames solved
  int64_t tracked = 0;                    // of them with a pose
};

struct TrackerNodeOptions {
  TrackerOptions tracker;
  bool log_mode = false;         // reading a log: frame deadlines in message time
  bool keep_trajectory = false;  // remember TRACKING/AMBIGUOUS poses for --out
  // When set (with keep_trajectory): every kept pose is also appended to this file (trajectory.csv
  // format) and flushed at once, so a tracker killed mid-run loses nothing it computed. Created (or
  // truncated) by the constructor, which throws naming the file when it cannot be written. With several
  // bodies each stream has its own, BodyPath(OUT, name) + ".partial" for partial_path OUT.partial (the
  // single one is then removed).
  std::string partial_path;
  bool quiet = false;  // no status lines (warnings are always printed)
  // The map file's covariance (ReadMapCovariance): with tracker.map_uncertainty the poses' covariances
  // hold the map's error. Used with the map file's map only: a map from MCMT_MAP has none.
  std::optional<MapCovariance> map_covariance;
};

class TrackerNode {
 public:
  // lcm: where detections (and MCMT_MAP) come from. map: the map file's content, or nullopt to wait
  // for MCMT_MAP. output: where poses are published; nullptr: on `lcm`, except in log mode (nowhere).
  // Throws when the map does not match the rig.
  TrackerNode(lcm::LCM& lcm, const RigConfig& rig, const TrackerNodeOptions& options,
              std::optional<RigMap> map, lcm::LCM* output = nullptr);
  ~TrackerNode();
  TrackerNode(const TrackerNode&) = delete;
  TrackerNode& operator=(const TrackerNode&) = delete;

  // Handles messages until stop is requested or (log mode) the log ends; then solves what is pending.
  void Run(const StopToken& stop);
  // Log mode: reads the log with core's reader (damage skipped and reported) and tracks its frames in
  // capture-time order whatever the order of the events (the detections between two maps of the log
  // are sorted by utime, camera, seq); then solves what is pending.
  LogReadReport RunLog(const std::string& path, const StopToken& stop);
  // Solves and publishes every pending frame (end of a log, or shutdown).
  void Flush();
  // Solves frames whose deadline passed (live mode; called by Run).
  void Poll();

  // The raw handlers (public so that tests can feed bytes directly).
  void OnDetections(const std::string& channel, const void* data, size_t size);
  void OnMap(const void* data, size_t size);

  bool has_map() const { return estimator_ != nullptr; }
  // Every pose stream of the map in use (empty before a map): the moving bodies, then the relative poses.
  const std::vector<PoseStream>& streams() const { return streams_; }
  const HealthMonitor* health() const { return health_.get(); }  // null without a map or health
  const TrackerStats& stats() const { return stats_; }
  // The first stream's poses (the single object's, or the first moving body's).
  const std::vector<TrajectoryRow>& trajectory() const;
  std::string StatusLine() const;

 private:
  void HandleDetections(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void HandleMap(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void SetMap(const RigMap& map, const std::string& origin);
  void ProcessFrames(std::vector<SyncedFrame> frames, int64_t trigger_wall_us);
  void ProcessFrame(const SyncedFrame& frame, int64_t last_arrival_wall_us);
  // The pose streams of `map` (PlanPoseStreams): bodies, relative poses, their partial files; a stream of
  // the same name keeps its trajectory across a map switch. Throws OptionError (bad channels, names).
  void SetStreams(const RigMap& map);
  // Solves every moving body of the frame (each judging the cameras that see it when health is on: a
  // camera's residuals pooled over the bodies it sees; excluded cameras left out of every body).
  std::vector<PoseSolution> SolveBodies(const std::vector<MarkerObservation>& obs, int64_t utime);
  // Keeps (trajectory, partial file) and publishes one stream's solution for the frame.
  void Emit(size_t stream, const SyncedFrame& frame, const PoseSolution& sol, double latency_ms);
  void CheckStaleCameras();
  void WarnOnce(const std::string& key, const std::string& text);
  void MaybePrintStatus();
  // A checked message (utime on the reference clock) into the frame synchronizer; frames due solved.
  void AssembleDetections(const detections_t& msg, int64_t arrival_wall);
  // The window measured (ChooseSyncWindow over the held messages): the synchronizer made with it, the
  // held messages assembled in their order, the choice said once on stderr.
  void ChooseWindowAndReplay();
  // One camera's judgement in a frame, pooled over the bodies it was judged on.
  struct CameraJudgement {
    double squares = 0.0;  // sum over bodies of rms^2 x markers (rms under the pose from the others)
    int markers = 0;
    bool gated = false;  // its markers were left out of a body's pose in this frame
  };
  struct FrameJudgement {
    std::map<std::string, CameraJudgement> cameras;  // the cameras judged
    std::set<std::string> seen;                      // cameras with a mapped marker on a body with a pose
    std::map<std::string, int> companions;           // of those: most other cameras on one of its bodies
  };
  // A body's pose without excluded and gated cameras, every camera of it judged under the pose from the
  // others (tracker/health.cc); the judgements added to *frame.
  PoseSolution SolveJudgingCameras(const PoseEstimator& estimator, const std::vector<MarkerObservation>& obs,
                                   const Rigid3* prior, FrameJudgement* frame);
  // The frame's judgements into the monitor; cameras never judged said once; MCMT_TRACKER_STATUS.
  void UpdateHealth(const FrameJudgement& frame, int64_t utime);
  void PublishHealth(int64_t utime, const std::string& message);

  lcm::LCM& lcm_;
  lcm::LCM* output_;
  const RigConfig& rig_;
  TrackerNodeOptions options_;
  // A moving body of the map in use: its own map (RigMap::ObjectMap), estimator and motion model.
  struct Body {
    size_t stream = 0;  // its index in streams_
    std::unique_ptr<PoseEstimator> estimator;
    MotionModel motion;
  };
  struct Relative {
    size_t stream = 0;
    int of = -1;  // index in bodies_
    int in = -1;  // index in bodies_, -1: a static body at rig_from_in
    Rigid3 rig_from_in = Rigid3::Identity();
  };
  const PoseEstimator* estimator_ = nullptr;  // the first moving body's
  std::vector<Body> bodies_;
  std::vector<Relative> relatives_;
  std::map<int, size_t> body_of_marker_;  // marker id -> index in bodies_ (several bodies)
  std::vector<PoseStream> streams_;
  std::vector<std::unique_ptr<std::FILE, int (*)(std::FILE*)>> stream_partials_;
  std::unique_ptr<HealthMonitor> health_;           // per camera of the map
  int64_t last_health_utime_ = INT64_MIN;           // last MCMT_TRACKER_STATUS (frame utime)
  std::string health_change_;                       // a map switch, for the next MCMT_TRACKER_STATUS
  std::map<std::string, int> companions_;           // per camera: most other cameras seen with it on a body
  std::map<std::string, int64_t> last_seen_utime_;  // per camera: last frame it saw a body with a pose
  int64_t map_utime_ = INT64_MIN;
  std::unique_ptr<FrameSynchronizer> sync_;  // over the map's cameras
  FrameSyncOptions sync_options_;            // the synchronizer's (its tolerance chosen or set)
  // Choosing the window (a map with clock offsets, tolerance not set): the first messages are held.
  bool measuring_window_ = false;
  std::vector<std::pair<detections_t, int64_t>> held_;  // message (reference clock), arrival wall time
  int64_t last_published_utime_ = INT64_MIN;
  std::vector<lcm::Subscription*> subscriptions_;
  std::set<std::string> warned_;
  std::set<std::string> reported_stale_;
  std::map<std::string, int64_t> late_views_;  // per camera
  DuplicateFilter duplicates_;
  bool waits_for_map_ = false;  // no map file: maps come from MCMT_MAP
  bool map_from_file_ = false;  // the map in use is the map file's (options_.map_covariance is its)
  TrackerStats stats_;
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> partial_{nullptr, &std::fclose};
  std::vector<double> latencies_ms_;  // since the last status line
  int64_t last_status_wall_us_ = 0;
  int64_t status_frames_ = 0, status_tracked_ = 0;
};

}  // namespace mcmt
