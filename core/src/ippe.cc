#include "core/ippe.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/calib3d.hpp>
#include <vector>

namespace mcmt {
namespace {

// RMS over the 4 corners of |Project(cam_from_marker * corner) - observed|, distorted pixels.
double ReprojectionRms(const CameraModel& camera, const Rigid3& cam_from_marker,
                       const MarkerCorners3d& corners3d, const MarkerCorners2d& corners_px) {
  double sum = 0.0;
  for (int i = 0; i < 4; ++i) {
    Eigen::Vector2d pixel;
    if (!camera.Project(cam_from_marker * corners3d[i], &pixel))
      return std::numeric_limits<double>::infinity();
    sum += (pixel - corners_px[i]).squaredNorm();
  }
  return std::sqrt(sum / 4.0);
}

bool Degenerate(const MarkerCorners2d& c) {
  for (const auto& p : c)
    if (!p.allFinite()) return true;
  // Shoelace area of the quadrilateral (pixels^2).
  double area = 0.0;
  for (int i = 0; i < 4; ++i) {
    const auto& a = c[i];
    const auto& b = c[(i + 1) % 4];
    area += a.x() * b.y() - b.x() * a.y();
  }
  return std::abs(0.5 * area) < 1e-6;
}

// OpenCV's IPPE hands each pose's rotation back as a Rodrigues vector, converted from its rotation matrix
// as theta / (2 sin theta) (R32 - R23, R13 - R31, R21 - R12): near a half turn (theta -> pi) the
// antisymmetric part vanishes and the vector is its rounding noise over sin theta. A square facing the camera
// is close to such a rotation: any rotation taking the marker's z to the camera's -z is a half turn about an
// axis in the image plane, and tilting it about its in-plane axis perpendicular to that one keeps it exactly
// a half turn. On exact corners of such squares (the tracker's test: facing, tilted 0-40 deg about its own y,
// 1.2 m) the hypotheses came back 2-180 deg off: at 8 deg the best 17 deg off at 0.047 px, the other 75 deg
// off at 7.3 px (ratio 156); random facing squares come within 1e-3 deg of a half turn, and of 200000 (exact
// corners, 0.5-2 m, tilt 1-20 deg) 63 came back more than 1e-6 deg off, up to 0.04 deg, the other solution
// up to 0.9 deg from the mirror. So the square is solved in its frame turned by one of its four flips
// S_k = Rx(pi) Rz(k 90 deg) (S_k maps corner j to corner (3 - j + k) mod 4; solving with the image of
// corner (3 - j + k) mod 4 as corner j gives R S_k), k such that the new edge 0 -> 1 runs most along the
// image's +x: then R S_k takes z away from the camera and x along the image's x, a rotation of at most
// 105 deg (views up to 75 deg from frontal near the optical axis; 135 deg 45 deg off it, 154 deg at 85 deg
// views there), and R = (R S_k) S_k^T. Those 200000 squares: now at most 7e-9 deg off, 3e-6 deg.
std::array<int, 4> FlipsForSolve(const std::array<Eigen::Vector2d, 4>& normalised) {
  std::array<int, 4> flips = {0, 1, 2, 3};
  std::array<double, 4> dx;
  for (int k = 0; k < 4; ++k)
    dx[k] = (normalised[(2 + k) % 4] - normalised[(3 + k) % 4]).x();  // new corner 1 - new corner 0
  std::stable_sort(flips.begin(), flips.end(), [&](int a, int b) { return dx[a] > dx[b]; });
  return flips;
}

// S_k = Rx(pi) Rz(k 90 deg), exact.
Eigen::Matrix3d Flip(int k) {
  Eigen::Matrix3d rz = Eigen::Matrix3d::Identity();
  for (int i = 0; i < k; ++i) rz = (Eigen::Matrix3d() << 0, -1, 0, 1, 0, 0, 0, 0, 1).finished() * rz;
  return Eigen::Vector3d(1, -1, -1).asDiagonal() * rz;
}

// Both IPPE solutions of the square whose corners (normalised) are solved as corner j <- corner
// (3 - j + flip) mod 4, turned back to the marker's frame; hypotheses that are not finite are left out.
std::vector<PoseHypothesis> SolveFlipped(const CameraModel& camera, const MarkerCorners2d& corners_px,
                                         const std::array<Eigen::Vector2d, 4>& normalised,
                                         const MarkerCorners3d& corners3d, int flip) {
  std::vector<PoseHypothesis> hypotheses;
  std::vector<cv::Point3d> object_points;
  std::vector<cv::Point2d> image_points;
  for (int j = 0; j < 4; ++j) {
    object_points.emplace_back(corners3d[j].x(), corners3d[j].y(), corners3d[j].z());
    const Eigen::Vector2d& u = normalised[(3 - j + flip) % 4];
    image_points.emplace_back(u.x(), u.y());
  }
  const Eigen::Matrix3d flip_back = Flip(flip).transpose();
  std::vector<cv::Mat> rvecs, tvecs;
  try {
    const cv::Mat identity = cv::Mat::eye(3, 3, CV_64F);
    cv::solvePnPGeneric(object_points, image_points, identity, cv::noArray(), rvecs, tvecs, false,
                        cv::SOLVEPNP_IPPE_SQUARE);
  } catch (const cv::Exception&) {
    return hypotheses;
  }
  for (size_t i = 0; i < rvecs.size() && i < 2; ++i) {
    cv::Mat r, t;
    rvecs[i].convertTo(r, CV_64F);
    tvecs[i].convertTo(t, CV_64F);
    const Eigen::Vector3d rvec(r.at<double>(0), r.at<double>(1), r.at<double>(2));
    const Eigen::Vector3d tvec(t.at<double>(0), t.at<double>(1), t.at<double>(2));
    if (!rvec.allFinite() || !tvec.allFinite()) continue;
    PoseHypothesis h;
    h.cam_from_marker = RigidFromRvecTvec(rvec, tvec);
    h.cam_from_marker.linear() = h.cam_from_marker.linear() * flip_back;
    h.error_px = ReprojectionRms(camera, h.cam_from_marker, corners3d, corners_px);
    if (!std::isfinite(h.error_px)) continue;
    hypotheses.push_back(h);
  }
  return hypotheses;
}

}  // namespace

SquarePose EstimateSquarePose(const CameraModel& camera, const MarkerCorners2d& corners_px, double side) {
  SquarePose out;
  if (!(side > 0) || Degenerate(corners_px)) return out;
  const MarkerCorners3d corners3d = MarkerCornersInMarker(side);
  std::array<Eigen::Vector2d, 4> normalised;
  for (int i = 0; i < 4; ++i) {
    normalised[i] = camera.Unproject(corners_px[i]);
    if (!normalised[i].allFinite()) return out;
  }
  // The preferred flip first; the others only when its solve gives nothing finite: a square seen exactly
  // along its normal, exact corners, makes OpenCV take the square root of a rounding residue below 0, and
  // both solutions NaN (283 of 20000 such squares before the flip, 303 with the preferred flip alone; none
  // after trying the next flips).
  std::vector<PoseHypothesis> hypotheses;
  for (const int flip : FlipsForSolve(normalised)) {
    hypotheses = SolveFlipped(camera, corners_px, normalised, corners3d, flip);
    if (!hypotheses.empty()) break;
  }
  if (hypotheses.empty()) return out;
  std::sort(hypotheses.begin(), hypotheses.end(),
            [](const PoseHypothesis& a, const PoseHypothesis& b) { return a.error_px < b.error_px; });
  out.ok = true;
  out.num_hypotheses = static_cast<int>(hypotheses.size());
  out.hypotheses[0] = hypotheses[0];
  out.hypotheses[1] = hypotheses.size() > 1 ? hypotheses[1] : hypotheses[0];
  constexpr double kMaxRatio = 1e6;
  if (hypotheses.size() > 1) {
    const double e1 = hypotheses[0].error_px, e2 = hypotheses[1].error_px;
    if (e2 <= e1) {
      out.ratio = 1.0;  // equal errors (including both exact): no preference
    } else {
      out.ratio = (e1 * kMaxRatio <= e2) ? kMaxRatio : e2 / e1;
    }
  } else {
    out.ratio = kMaxRatio;
  }
  return out;
}

int NumKeptHypotheses(const SquarePose& pose, double tau_e) {
  if (!pose.ok) return 0;
  if (pose.num_hypotheses < 2 || pose.ratio >= tau_e) return 1;
  return 2;
}

double FacingCosine(const Rigid3& cam_from_marker) {
  const Eigen::Vector3d t = cam_from_marker.translation();
  const double norm = t.norm();
  if (norm <= 0) return 1.0;
  return std::abs(cam_from_marker.rotation().col(2).dot(t)) / norm;
}

}  // namespace mcmt
