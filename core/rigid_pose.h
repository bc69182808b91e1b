// The rigid-pose solver used wherever one pose is fitted to pixels: the tracker's rig_from_object per
// frame and the mapper's cam_from_object of a camera frame with several markers.
//
// Points x_i (body frame) seen by cameras: p_world = T x_i with T = world_from_body, p_cam = cam_from_world
// p_world, residual r_i = W_i (Project(p_cam) - u_i) (pixels; W_i the point's square-root information, I
// unless given). Cost E(T) = sum rho(|r_i|^2) (Huber, or plain squares). A step rotates about a pivot c
// (world frame) then translates, delta = (w, v):
//   p_world <- R(w) (p_world - c) + c + v,    d p_world / d delta = [-[p_world - c]x | I],
//   d r_i / d delta = W_i (d pixel / d p_cam) cam_R_world [-[p_world - c]x | I]   (analytic, 2x6 per point).
// Levenberg-Marquardt pivots about the body's origin (c = T's translation): with the world origin far
// from the body (a rig in its reference camera's frame, a camera frame for the mapper) rotation and
// translation steps stay decoupled; rotating about the world origin coupled them and left poses degrees
// off after 20 iterations. Solved on the IRLS-weighted normal equations (H + lambda diag(H)) dx = -g.
#pragma once

#include <vector>

#include "core/camera.h"
#include "core/se3.h"

namespace mcmt {

struct PosePoint {
  const CameraModel* camera = nullptr;
  const Rigid3* cam_from_world = nullptr;           // nullptr: the world frame is the camera's
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  // body frame
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();  // observed
  // W: the residual is W (projection - pixel), e.g. a marker corner's CornerSqrtInformation (core/marker.h).
  Eigen::Matrix2d sqrt_information = Eigen::Matrix2d::Identity();
};

// Added to the cost for every point that falls behind its camera, so that a step leading there is refused.
constexpr double kBehindCameraPenalty = 1e12;

// Robust cost at world_from_body (huber_px <= 0: plain squares), with J^T W J in *h and J^T W r in *g for
// a step rotating about `pivot`; *plain_cost (optional) gets the sum of squares without the robust weights.
double PoseNormalEquations(const std::vector<PosePoint>& points, const Rigid3& world_from_body,
                           const Eigen::Vector3d& pivot, double huber_px, Matrix6d* h, Vector6d* g,
                           double* plain_cost = nullptr);

struct RigidPoseOptions {
  int max_iterations = 20;
  double huber_px = 0.0;  // <= 0: plain least squares
};

// The step delta = (w, v) applied to world_from_body: rotation R(w) about `pivot`, then translation v (the
// step the normal equations above are written for).
Rigid3 ApplyPoseStep(const Rigid3& world_from_body, const Vector6d& delta, const Eigen::Vector3d& pivot);

// Levenberg-Marquardt from *world_from_body; returns the iterations taken. Stops on a step below 1e-9
// (rad, m), a relative decrease below 1e-10, or when no damping makes progress.
int RefineRigidPose(const std::vector<PosePoint>& points, const RigidPoseOptions& options,
                    Rigid3* world_from_body);

// Sum of squared pixel errors, +inf when a point is behind its camera.
double PoseSquaredError(const std::vector<PosePoint>& points, const Rigid3& world_from_body);

}  // namespace mcmt
