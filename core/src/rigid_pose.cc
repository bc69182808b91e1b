#include "core/rigid_pose.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <cmath>
#include <limits>

#include "core/math.h"

namespace mcmt {
namespace {

Eigen::Vector3d InCamera(const PosePoint& p, const Eigen::Vector3d& p_world) {
  if (!p.cam_from_world) return p_world;
  return p.cam_from_world->linear() * p_world + p.cam_from_world->translation();
}

double Huber(double squared, double k, double* weight) {
  if (squared <= k * k) {
    *weight = 1.0;
    return squared;
  }
  const double d = std::sqrt(squared);
  *weight = k / d;
  return 2.0 * k * d - k * k;
}

}  // namespace

Rigid3 ApplyPoseStep(const Rigid3& pose, const Vector6d& delta, const Eigen::Vector3d& pivot) {
  const Eigen::Matrix3d dr = RotationFromVector(delta.head<3>());
  Rigid3 out = Rigid3::Identity();
  // Keep the rotation orthonormal over thousands of incremental updates.
  out.linear() = Eigen::Quaterniond(dr * pose.linear()).normalized().toRotationMatrix();
  out.translation() = dr * (pose.translation() - pivot) + pivot + delta.tail<3>();
  return out;
}

double PoseNormalEquations(const std::vector<PosePoint>& points, const Rigid3& world_from_body,
                           const Eigen::Vector3d& pivot, double huber_px, Matrix6d* h, Vector6d* g,
                           double* plain_cost) {
  h->setZero();
  g->setZero();
  double cost = 0.0, plain = 0.0;
  const Eigen::Matrix3d r = world_from_body.linear();
  const Eigen::Vector3d t = world_from_body.translation();
  for (const PosePoint& p : points) {
    const Eigen::Vector3d p_world = r * p.point + t;
    Eigen::Vector2d px;
    Eigen::Matrix<double, 2, 3> jp;
    if (!p.camera->Project(InCamera(p, p_world), &px, &jp)) {
      cost += kBehindCameraPenalty;
      plain += kBehindCameraPenalty;
      continue;
    }
    const Eigen::Vector2d res = p.sqrt_information * (px - p.pixel);
    const double sq = res.squaredNorm();
    double w = 1.0;
    cost += huber_px > 0 ? Huber(sq, huber_px, &w) : sq;
    plain += sq;
    const Eigen::Matrix<double, 2, 3> a =
        p.sqrt_information *
        (p.cam_from_world ? Eigen::Matrix<double, 2, 3>(jp * p.cam_from_world->linear()) : jp);
    Eigen::Matrix<double, 2, 6> j;
    j.leftCols<3>() = -a * Skew(p_world - pivot);
    j.rightCols<3>() = a;
    h->noalias() += w * j.transpose() * j;
    g->noalias() += w * j.transpose() * res;
  }
  if (plain_cost) *plain_cost = plain;
  return cost;
}

int RefineRigidPose(const std::vector<PosePoint>& points, const RigidPoseOptions& options,
                    Rigid3* world_from_body) {
  Matrix6d h;
  Vector6d g;
  double cost =
      PoseNormalEquations(points, *world_from_body, world_from_body->translation(), options.huber_px, &h, &g);
  double lambda = 1e-4;
  int it = 0;
  for (; it < options.max_iterations && cost > 1e-24; ++it) {
    Matrix6d a = h;
    a.diagonal() += lambda * h.diagonal() + Vector6d::Constant(1e-12);
    const Vector6d dx = a.ldlt().solve(-g);
    if (!dx.allFinite()) break;
    const Rigid3 candidate = ApplyPoseStep(*world_from_body, dx, world_from_body->translation());
    Matrix6d h_new;
    Vector6d g_new;
    const double cost_new =
        PoseNormalEquations(points, candidate, candidate.translation(), options.huber_px, &h_new, &g_new);
    if (cost_new < cost) {
      const double decrease = cost - cost_new;
      *world_from_body = candidate;
      h = h_new;
      g = g_new;
      cost = cost_new;
      lambda = std::max(lambda * 0.1, 1e-10);
      if (dx.norm() < 1e-9 || decrease < 1e-10 * cost_new) {
        ++it;
        break;
      }
    } else {
      lambda *= 10.0;
      if (lambda > 1e10) break;
    }
  }
  return it;
}

double PoseSquaredError(const std::vector<PosePoint>& points, const Rigid3& world_from_body) {
  double sum = 0.0;
  for (const PosePoint& p : points) {
    Eigen::Vector2d px;
    if (!p.camera->Project(InCamera(p, world_from_body.linear() * p.point + world_from_body.translation()),
                           &px, nullptr))
      return std::numeric_limits<double>::infinity();
    sum += (px - p.pixel).squaredNorm();
  }
  return sum;
}

}  // namespace mcmt
