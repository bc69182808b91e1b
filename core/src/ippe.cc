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

}  // namespace

SquarePose EstimateSquarePose(const CameraModel& camera, const MarkerCorners2d& corners_px, double side) {
  SquarePose out;
  if (!(side > 0) || Degenerate(corners_px)) return out;
  const MarkerCorners3d corners3d = MarkerCornersInMarker(side);
  std::vector<cv::Point3d> object_points;
  std::vector<cv::Point2d> image_points;
  for (int i = 0; i < 4; ++i) {
    object_points.emplace_back(corners3d[i].x(), corners3d[i].y(), corners3d[i].z());
    const Eigen::Vector2d u = camera.Unproject(corners_px[i]);
    if (!u.allFinite()) return out;
    image_points.emplace_back(u.x(), u.y());
  }
  std::vector<cv::Mat> rvecs, tvecs;
  try {
    const cv::Mat identity = cv::Mat::eye(3, 3, CV_64F);
    cv::solvePnPGeneric(object_points, image_points, identity, cv::noArray(), rvecs, tvecs, false,
                        cv::SOLVEPNP_IPPE_SQUARE);
  } catch (const cv::Exception&) {
    return out;
  }
  std::vector<PoseHypothesis> hypotheses;
  for (size_t i = 0; i < rvecs.size() && i < 2; ++i) {
    cv::Mat r, t;
    rvecs[i].convertTo(r, CV_64F);
    tvecs[i].convertTo(t, CV_64F);
    const Eigen::Vector3d rvec(r.at<double>(0), r.at<double>(1), r.at<double>(2));
    const Eigen::Vector3d tvec(t.at<double>(0), t.at<double>(1), t.at<double>(2));
    if (!rvec.allFinite() || !tvec.allFinite()) continue;
    PoseHypothesis h;
    h.cam_from_marker = RigidFromRvecTvec(rvec, tvec);
    h.error_px = ReprojectionRms(camera, h.cam_from_marker, corners3d, corners_px);
    if (!std::isfinite(h.error_px)) continue;
    hypotheses.push_back(h);
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
