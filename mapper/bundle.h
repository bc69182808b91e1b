// Step 5 of the paper: the global refinement with Ceres. Every marker observation (frame t, camera c,
// marker m) contributes 8 residuals (4 corners x, y) touching one camera block, one marker block and
// one frame block, and, when the camera's intrinsics or its clock are refined, its intrinsics block
// and its time offset block. Frames are eliminated first by the Schur complement (each residual touches
// exactly one frame block: time offsets move a frame's pose along a velocity held constant in a solve).
#pragma once

#include <ceres/ceres.h>

#include <array>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/marker.h"
#include "core/se3.h"

namespace mcmt {

// A pose parameter block: quaternion (x, y, z, w, Eigen's memory order) then translation (x, y, z).
// Its tangent is the left perturbation (dr, dt): R <- Exp(dr) * R, t <- t + dt.
using PoseBlock = std::array<double, 7>;
PoseBlock BlockFromRigid(const Rigid3& pose);
Rigid3 RigidFromBlock(const double* block);

class LeftPoseManifold : public ceres::Manifold {
 public:
  int AmbientSize() const override { return 7; }
  int TangentSize() const override { return 6; }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override;
  // The cost functions report their Jacobians directly with respect to the tangent (first 6 of the
  // 7 ambient columns, the 7th zero), so the Plus Jacobian is [I6; 0].
  bool PlusJacobian(const double* x, double* jacobian) const override;
  bool Minus(const double* y, const double* x, double* y_minus_x) const override;
  bool MinusJacobian(const double* x, double* jacobian) const override;
};

// A camera's intrinsics as a parameter block: fx, fy, cx, cy (pixels), then its distortion coefficients.
std::vector<double> IntrinsicsVector(const CameraModel& model);
// `base` (size, distortion model) with the intrinsics of `values` (IntrinsicsVector's layout).
CameraModel ModelWithIntrinsics(const CameraModel& base, const double* values);
// Names of the intrinsics block's entries: fx, fy, cx, cy, k1, k2, p1, p2, k3 (radtan) or k1..k4 (fisheye).
std::vector<std::string> IntrinsicsNames(const CameraModel& model);

// An observation's capture time relative to its frame: the frame block is the object's pose at the
// frame's time; the camera's clock reads utime at capture, its true capture time (in the reference
// camera's clock) is utime - offset - drift * clock_s, offset and drift being the camera's time offset
// block (seconds; the reference camera's is 0 and constant) and its drift block (seconds per second, only
// with with_drift), clock_s the reading against the problem's time reference (the session's middle):
// dt = time_s - offset - drift * clock_s with time_s = (utime - frame utime) / 1e6. The pose seen is the
// frame pose moved along the frame's velocity (a twist in the rig frame, per second, held constant in a
// solve):
//   rig_from_object(dt) = (Exp(dt * w) * R, t + dt * v)
struct ObservationTime {
  double time_s = 0.0;               // utime minus the frame's utime, seconds (before the offset)
  const double* velocity = nullptr;  // (w, v): rad/s, m/s
  bool with_drift = false;
  double clock_s = 0.0;  // utime minus the time reference, seconds (with_drift)
};

// What one observation's residual reads (SelfCalibrationCost and ReprojectionCost keep it each their own
// way) and the residual with its Jacobians, blocks of `sizes` (cam_from_rig, object_from_marker,
// rig_from_object, then the intrinsics when with_intrinsics, the time offset and the drift when `time`
// says so): SelfCalibrationCost's arithmetic below.
struct ObservationCostInputs {
  const CameraModel* camera = nullptr;
  const MarkerCorners2d* observed = nullptr;
  double side = 0.0;
  const CornerWeights* weights = nullptr;  // null: the corners weigh equally
  bool with_intrinsics = false;
  const ObservationTime* time = nullptr;  // null: the clocks are not unknowns
};
bool EvaluateObservation(const ObservationCostInputs& residual, const std::vector<int32_t>& sizes,
                         double const* const* parameters, double* residuals, double** jacobians);

// Residual of one marker observation with the camera's intrinsics and clock as unknowns. Parameter
// blocks: cam_from_rig, object_from_marker, rig_from_object (PoseBlock each), then the intrinsics
// (IntrinsicsVector's layout) when `with_intrinsics`, then the time offset (1, seconds) when `with_time`,
// then the drift (1, s/s) when time->with_drift.
// Jacobians analytic as ReprojectionCost's, with the frame pose moved by dt:
//   d p_rig / d(dr_frame) = -[p_rig - t(dt)]x Exp(dt w),  d p_rig / d offset = -(w x (p_rig - t(dt)) + v),
//   d p_rig / d drift = clock_s * d p_rig / d offset
//   d pixel / d(fx, fy, cx, cy) = [[xd, 0, 1, 0], [0, yd, 0, 1]],  d pixel / d k_i = diag(fx, fy) d(xd, yd) /
//   d k_i
// (the distortion is affine in its coefficients for radtan with 4 or 5 and for fisheye: a forward
// difference of the public Distort is exact there; for the rational 8-coefficient model a central one,
// O(h^2)).
class SelfCalibrationCost : public ceres::CostFunction {
 public:
  SelfCalibrationCost(const CameraModel* camera, const MarkerCorners2d& observed, double side,
                      bool with_intrinsics, const ObservationTime* time,
                      const CornerWeights* weights = nullptr);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  const CameraModel* camera_;  // size and distortion model (and the intrinsics when they are not a block)
  MarkerCorners2d observed_;
  double side_;  // the marker's corners in its frame: MarkerCornersInMarker(side_)
  bool weighted_;
  CornerWeights weights_;
  bool with_intrinsics_;
  ObservationTime time_;
  bool with_time_;
};

// Residual of one marker observation, 8 values:
//   p_cam(k) = cam_from_rig * rig_from_object * object_from_marker * u_k      (u_k: corner k, ArUco order)
//   r(2k..2k+1) = W_k (Project(p_cam(k)) - observed_k)                        (pixels, distorted)
// with W_k the corner's square-root information (CornerSqrtInformation; I when no weights are given).
// Parameter blocks: cam_from_rig, object_from_marker, rig_from_object (PoseBlock each). Analytic
// Jacobians with respect to the left perturbations:
//   d p_cam / d(dr_cam, dt_cam)   = [ -[p_cam - t_cam]x , I ]
//   d p_cam / d(dr_frame, dt_frame) = R_cam [ -[p_rig - t_frame]x , I ]
//   d p_cam / d(dr_marker, dt_marker) = R_cam R_frame [ -[p_obj - t_marker]x , I ]
// chained with the camera model's d pixel / d p_cam. Evaluation fails (step rejected) when a corner
// falls behind the camera.
// The same arithmetic as SelfCalibrationCost's with the intrinsics given and no clock (one function), but
// only what it reads is stored: the bundle holds one per observation through its solves, next to Ceres'
// Jacobian the largest part of the mapper's peak memory (an 8-camera board session: 128 instead of 448
// bytes per observation, the corner weights apart when there are any; the corners in the marker's frame
// from the side, no inner cost function with its own block sizes).
class ReprojectionCost : public ceres::SizedCostFunction<8, 7, 7, 7> {
 public:
  ReprojectionCost(const CameraModel* camera, const MarkerCorners2d& observed, double side,
                   const CornerWeights* weights = nullptr);
  static ceres::CostFunction* Create(const CameraModel* camera, const MarkerCorners2d& observed, double side,
                                     const CornerWeights* weights = nullptr) {
    return new ReprojectionCost(camera, observed, side, weights);
  }
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  const CameraModel* camera_;
  MarkerCorners2d observed_;
  double side_;
  std::unique_ptr<const CornerWeights> weights_;  // null: the corners weigh equally
};

// d pixel / d intrinsics (2 x (4 + n), row-major into `out`) at normalised coordinates (x, y). `camera`'s
// distortion coefficients are shifted for the differences and restored (no copy of the model per corner).
void IntrinsicsJacobian(CameraModel* camera, double x, double y, double* out);

struct BundleObservation {
  int camera = 0;
  int marker = 0;
  int frame = 0;
  MarkerCorners2d corners;
  double side = 0.0;
  double time_s = 0.0;   // utime minus the frame's utime, seconds (before the camera's offset)
  double clock_s = 0.0;  // utime minus the problem's time_reference_utime, seconds (clock drift)
};

// One camera's intrinsics block when they are refined.
struct BundleIntrinsics {
  bool refined = false;
  std::vector<double> values;   // IntrinsicsVector layout
  std::vector<double> prior;    // the given intrinsics
  std::vector<double> sigma;    // prior standard deviation per entry (same units); <= 0: no prior
  std::vector<int> constant;    // entries held at their value (not observable, or not asked for)
  double prior_scale_px = 1.0;  // residual of the prior = (value - prior) / sigma * prior_scale_px
};

struct BundleProblem {
  std::vector<PoseBlock> cam_from_rig;        // per camera
  std::vector<PoseBlock> object_from_marker;  // per marker
  std::vector<PoseBlock> rig_from_object;     // per frame
  std::vector<const CameraModel*> models;     // per camera
  // Blocks held constant (the gauge: the reference camera and marker; later, e.g., a layout held fixed
  // while cameras are re-estimated). Shorter than its block list (or empty): the rest vary.
  std::vector<char> camera_fixed;  // per camera
  std::vector<char> marker_fixed;  // per marker
  std::vector<char> frame_fixed;   // per frame
  std::vector<BundleObservation> observations;
  std::vector<char> active;  // per observation
  // Self-calibration (empty: the given intrinsics, synchronised clocks).
  std::vector<BundleIntrinsics> intrinsics;  // per camera
  std::vector<double> time_offset_s;         // per camera, seconds: true capture time = utime - offset
  std::vector<char> time_offset_fixed;       // per camera (the reference camera's, 0)
  // Per camera, s/s (empty: clocks that do not drift): true capture time = utime - offset - drift *
  // clock_s; held like the offsets (time_offset_fixed), with a weak prior (kDriftPriorSigma).
  std::vector<double> time_drift;
  int64_t time_reference_utime = 0;                   // clock_s = 0 here (the session's middle)
  std::vector<std::array<double, 6>> frame_velocity;  // per frame, (w, v) in the rig frame
  std::vector<double> frame_time_s;                   // per frame, for the velocities

  bool RefinesIntrinsics(int camera) const {
    return static_cast<size_t>(camera) < intrinsics.size() && intrinsics[camera].refined;
  }
  bool RefinesTime() const { return !time_offset_s.empty(); }
  bool RefinesDrift() const { return RefinesTime() && !time_drift.empty(); }
  // The camera's model at the current intrinsics.
  CameraModel Model(int camera) const;
  // Capture time of observation k relative to its frame's pose, seconds (0 without time offsets).
  double ObservationDt(size_t k) const;
};

// The drift's prior: 0 +- this (s/s, 1000 ppm), as a 1 px residual at one sigma: it only anchors a
// camera seen too briefly to tell a drift from an offset.
constexpr double kDriftPriorSigma = 1e-3;

// Frame velocities by differences of neighbouring frame poses (problem->frame_time_s, sorted): frames
// further apart than max_gap_s are not used (velocity 0 for an isolated frame).
void UpdateFrameVelocities(double max_gap_s, BundleProblem* problem);
// The largest gap between frames that give each other a velocity: a few of the session's typical frame
// intervals (a dropped frame or two is bridged, a pause is not).
double VelocityGapS(const BundleProblem& problem);

struct BundleSettings {
  double huber_px = 1.0;  // <= 0: no robust loss
  // Squared residuals of an observation weighted by cos(view angle)^this at the problem's start (0: none).
  double view_weight_power = 0.0;
  // Each corner's residual weighed by corner_weighting.For(observed corners) (none when equal).
  CornerWeighting corner_weighting;
  int max_iterations = 100;
  bool paper_stop = true;
  double paper_stop_px = 1e-4;
  int threads = 1;
  std::string linear_solver = "auto";
  // Called after every iteration with (iteration, cost, rms_px).
  std::function<void(int, double, double)> on_iteration;
};

struct BundleSummary {
  int iterations = 0;
  double initial_cost = 0.0;
  double final_cost = 0.0;
  double initial_rms_px = 0.0;
  double final_rms_px = 0.0;
  std::string termination;
  std::string linear_solver;
  bool usable = false;
  double seconds = 0.0;
};

BundleSummary SolveBundle(BundleProblem* problem, const BundleSettings& settings);

// RMS corner error (pixels) of every observation at the current parameters; +inf when a corner is
// behind the camera.
// With max_corner_px: also each observation's largest corner error.
// Covariance of every refined camera's intrinsics (IntrinsicsVector layout; rows and columns of the
// entries held constant are 0; empty for a camera not refined), marginal over every other unknown: the
// inverse Gauss-Newton information (J^T J with the priors) at the current parameters, for corners with
// noise sigma_px. Residuals with intrinsics given or constant do not need a block.
std::vector<Eigen::MatrixXd> IntrinsicsCovariance(BundleProblem* problem, double sigma_px);

// The information behind IntrinsicsCovariance at the current parameters, for covariances after entries
// are held: J^T J with the priors (unit corner noise) of every unknown but the frame poses, marginal over
// the frames (their Schur complement); per camera the column of its intrinsics block (-1: none) and the
// entries free there.
struct IntrinsicsInformation {
  Eigen::MatrixXd information;
  std::vector<int> column;                // per camera
  std::vector<std::vector<int>> entries;  // per camera: tangent index -> entry (IntrinsicsVector layout)
};
IntrinsicsInformation IntrinsicsInformationOf(BundleProblem* problem);
// IntrinsicsCovariance from `information` for the entries of `problem` free now (a subset of those free
// when it was computed; the parameters not moved since): holding an entry drops its row and column.
std::vector<Eigen::MatrixXd> IntrinsicsCovariance(const IntrinsicsInformation& information,
                                                  const BundleProblem& problem, double sigma_px);

// The object's pose observation k saw: its frame's pose moved to the capture time (ObservationTime).
Rigid3 ObservedFramePose(const BundleProblem& problem, size_t k);
// Frame `frame`'s pose moved by dt seconds along its velocity (the pose itself without clocks).
Rigid3 FramePoseAt(const BundleProblem& problem, int frame, double dt);

std::vector<double> ObservationRms(const BundleProblem& problem,
                                   std::vector<double>* max_corner_px = nullptr);

}  // namespace mcmt
