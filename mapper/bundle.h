// Step 5 of the paper: the global refinement with Ceres. Every marker observation (frame t, camera c,
// marker m) contributes 8 residuals (4 corners x, y) touching one camera block, one marker block and
// one frame block. Frames are eliminated first by the Schur complement.
#pragma once

#include <ceres/ceres.h>

#include <array>
#include <functional>
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

// Residual of one marker observation, 8 values:
//   p_cam(k) = cam_from_rig * rig_from_object * object_from_marker * u_k      (u_k: corner k, ArUco order)
//   r(2k..2k+1) = Project(p_cam(k)) - observed_k                                (pixels, distorted)
// Parameter blocks: cam_from_rig, object_from_marker, rig_from_object (PoseBlock each). Analytic
// Jacobians with respect to the left perturbations:
//   d p_cam / d(dr_cam, dt_cam)   = [ -[p_cam - t_cam]x , I ]
//   d p_cam / d(dr_frame, dt_frame) = R_cam [ -[p_rig - t_frame]x , I ]
//   d p_cam / d(dr_marker, dt_marker) = R_cam R_frame [ -[p_obj - t_marker]x , I ]
// chained with the camera model's d pixel / d p_cam. Evaluation fails (step rejected) when a corner
// falls behind the camera.
class ReprojectionCost : public ceres::SizedCostFunction<8, 7, 7, 7> {
 public:
  ReprojectionCost(const CameraModel* camera, const MarkerCorners2d& observed, double side);
  static ceres::CostFunction* Create(const CameraModel* camera, const MarkerCorners2d& observed,
                                     double side) {
    return new ReprojectionCost(camera, observed, side);
  }
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  const CameraModel* camera_;
  MarkerCorners2d observed_;
  MarkerCorners3d corners_;
};

struct BundleObservation {
  int camera = 0;
  int marker = 0;
  int frame = 0;
  MarkerCorners2d corners;
  double side = 0.0;
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
};

struct BundleSettings {
  double huber_px = 1.0;  // <= 0: no robust loss
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
std::vector<double> ObservationRms(const BundleProblem& problem,
                                   std::vector<double>* max_corner_px = nullptr);

}  // namespace mcmt
