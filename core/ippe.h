// Pose of one square from its four corners: both planar (IPPE) solutions with their reprojection
// errors and the ratio between them (the paper's step 1).
#pragma once

#include <array>

#include "core/camera.h"
#include "core/marker.h"
#include "core/se3.h"

namespace mcmt {

struct PoseHypothesis {
  Rigid3 cam_from_marker = Rigid3::Identity();
  double error_px = 0.0;  // RMS over the 4 corners of the distorted reprojection error, pixels
};

struct SquarePose {
  bool ok = false;                           // false if the corners are degenerate
  std::array<PoseHypothesis, 2> hypotheses;  // sorted: hypotheses[0] has the smaller error
  int num_hypotheses = 0;                    // 2 normally; 1 if the solver returned one
  // e2 / e1 >= 1 (capped at 1e6 when e1 is ~0). Large: the best hypothesis is sure.
  double ratio = 1.0;
  const PoseHypothesis& best() const { return hypotheses[0]; }
};

// corners_px: distorted pixels in ArUco order. Undistorts with the camera model, solves with
// cv::solvePnPGeneric(SOLVEPNP_IPPE_SQUARE) in the square's frame turned by one of its flips (so that the
// rotation OpenCV converts to a Rodrigues vector is never near a half turn; ippe.cc), measures errors in
// distorted pixels.
SquarePose EstimateSquarePose(const CameraModel& camera, const MarkerCorners2d& corners_px, double side);

// The hypotheses worth keeping under the paper's rule: only the best when ratio >= tau_e, else both.
int NumKeptHypotheses(const SquarePose& pose, double tau_e);

// Cosine of the angle between the square's normal and the direction from its centre to the camera
// (1: seen face-on; 1 also for a square at the camera's centre).
double FacingCosine(const Rigid3& cam_from_marker);

}  // namespace mcmt
