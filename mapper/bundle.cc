#include "mapper/bundle.h"

#include <chrono>
#include <cmath>
#include <limits>

#include "core/math.h"

namespace mcmt {
namespace {

Eigen::Quaterniond QuaternionExp(const Eigen::Vector3d& w) {
  const double angle = w.norm();
  if (angle < 1e-12) return Eigen::Quaterniond(1.0, 0.5 * w.x(), 0.5 * w.y(), 0.5 * w.z()).normalized();
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, w / angle));
}

Eigen::Vector3d QuaternionLog(const Eigen::Quaterniond& q_in) {
  Eigen::Quaterniond q = q_in.normalized();
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  const double s = q.vec().norm();
  if (s < 1e-12) return 2.0 * q.vec();
  const double angle = 2.0 * std::atan2(s, q.w());
  return q.vec() * (angle / s);
}

}  // namespace

PoseBlock BlockFromRigid(const Rigid3& pose) {
  const Eigen::Quaterniond q(pose.rotation());
  PoseBlock b;
  b[0] = q.x();
  b[1] = q.y();
  b[2] = q.z();
  b[3] = q.w();
  b[4] = pose.translation().x();
  b[5] = pose.translation().y();
  b[6] = pose.translation().z();
  return b;
}

Rigid3 RigidFromBlock(const double* block) {
  const Eigen::Quaterniond q(block[3], block[0], block[1], block[2]);
  Rigid3 pose = Rigid3::Identity();
  pose.linear() = q.normalized().toRotationMatrix();
  pose.translation() = Eigen::Vector3d(block[4], block[5], block[6]);
  return pose;
}

bool LeftPoseManifold::Plus(const double* x, const double* delta, double* x_plus_delta) const {
  const Eigen::Map<const Eigen::Quaterniond> q(x);
  Eigen::Map<Eigen::Quaterniond> q_out(x_plus_delta);
  q_out = (QuaternionExp(Eigen::Vector3d(delta[0], delta[1], delta[2])) * q).normalized();
  for (int i = 0; i < 3; ++i) x_plus_delta[4 + i] = x[4 + i] + delta[3 + i];
  return true;
}

bool LeftPoseManifold::PlusJacobian(const double*, double* jacobian) const {
  Eigen::Map<Eigen::Matrix<double, 7, 6, Eigen::RowMajor>> j(jacobian);
  j.setZero();
  j.topRows<6>().setIdentity();
  return true;
}

bool LeftPoseManifold::Minus(const double* y, const double* x, double* y_minus_x) const {
  const Eigen::Map<const Eigen::Quaterniond> qy(y), qx(x);
  const Eigen::Vector3d w = QuaternionLog(qy * qx.conjugate());
  for (int i = 0; i < 3; ++i) {
    y_minus_x[i] = w[i];
    y_minus_x[3 + i] = y[4 + i] - x[4 + i];
  }
  return true;
}

bool LeftPoseManifold::MinusJacobian(const double*, double* jacobian) const {
  Eigen::Map<Eigen::Matrix<double, 6, 7, Eigen::RowMajor>> j(jacobian);
  j.setZero();
  j.leftCols<6>().setIdentity();
  return true;
}

ReprojectionCost::ReprojectionCost(const CameraModel* camera, const MarkerCorners2d& observed, double side)
    : camera_(camera), observed_(observed), corners_(MarkerCornersInMarker(side)) {}

bool ReprojectionCost::Evaluate(double const* const* parameters, double* residuals,
                                double** jacobians) const {
  const Rigid3 cam_from_rig = RigidFromBlock(parameters[0]);
  const Rigid3 object_from_marker = RigidFromBlock(parameters[1]);
  const Rigid3 rig_from_object = RigidFromBlock(parameters[2]);
  const Eigen::Matrix3d& r_cam = cam_from_rig.linear();
  const Eigen::Matrix3d r_cam_frame = r_cam * rig_from_object.linear();
  using RowJ = Eigen::Matrix<double, 8, 7, Eigen::RowMajor>;
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector3d p_obj = object_from_marker * corners_[k];
    const Eigen::Vector3d p_rig = rig_from_object * p_obj;
    const Eigen::Vector3d p_cam = cam_from_rig * p_rig;
    Eigen::Vector2d pixel;
    Eigen::Matrix<double, 2, 3> dpix;
    if (!camera_->Project(p_cam, &pixel, jacobians ? &dpix : nullptr)) return false;
    residuals[2 * k] = pixel.x() - observed_[k].x();
    residuals[2 * k + 1] = pixel.y() - observed_[k].y();
    if (!jacobians) continue;
    if (jacobians[0]) {
      Eigen::Map<RowJ> j(jacobians[0]);
      j.block<2, 3>(2 * k, 0) = -dpix * Skew(p_cam - cam_from_rig.translation());
      j.block<2, 3>(2 * k, 3) = dpix;
      j.block<2, 1>(2 * k, 6).setZero();
    }
    if (jacobians[1]) {
      Eigen::Map<RowJ> j(jacobians[1]);
      const Eigen::Matrix<double, 2, 3> d = dpix * r_cam_frame;
      j.block<2, 3>(2 * k, 0) = -d * Skew(p_obj - object_from_marker.translation());
      j.block<2, 3>(2 * k, 3) = d;
      j.block<2, 1>(2 * k, 6).setZero();
    }
    if (jacobians[2]) {
      Eigen::Map<RowJ> j(jacobians[2]);
      const Eigen::Matrix<double, 2, 3> d = dpix * r_cam;
      j.block<2, 3>(2 * k, 0) = -d * Skew(p_rig - rig_from_object.translation());
      j.block<2, 3>(2 * k, 3) = d;
      j.block<2, 1>(2 * k, 6).setZero();
    }
  }
  return true;
}

namespace {

class ProgressCallback : public ceres::IterationCallback {
 public:
  ProgressCallback(const BundleSettings& settings, int num_corners)
      : settings_(settings), num_corners_(num_corners) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    const double rms = std::sqrt(2.0 * summary.cost / std::max(1, num_corners_));
    if (settings_.on_iteration) settings_.on_iteration(summary.iteration, summary.cost, rms);
    if (summary.iteration > 0 && summary.step_is_successful && settings_.paper_stop) {
      if (last_rms_ - rms < settings_.paper_stop_px) return ceres::SOLVER_TERMINATE_SUCCESSFULLY;
    }
    if (summary.step_is_successful || summary.iteration == 0) last_rms_ = rms;
    return ceres::SOLVER_CONTINUE;
  }

 private:
  const BundleSettings& settings_;
  int num_corners_;
  double last_rms_ = std::numeric_limits<double>::infinity();
};

}  // namespace

namespace {

// Residual blocks of the active observations; returns the number of corners. *used flags the blocks.
int AddObservations(BundleProblem* bp, ceres::LossFunction* loss, ceres::Problem* problem,
                    std::vector<char>* camera_used, std::vector<char>* marker_used,
                    std::vector<char>* frame_used) {
  int num_corners = 0;
  for (size_t i = 0; i < bp->observations.size(); ++i) {
    if (!bp->active[i]) continue;
    const BundleObservation& o = bp->observations[i];
    problem->AddResidualBlock(ReprojectionCost::Create(bp->models[o.camera], o.corners, o.side), loss,
                              bp->cam_from_rig[o.camera].data(), bp->object_from_marker[o.marker].data(),
                              bp->rig_from_object[o.frame].data());
    (*camera_used)[o.camera] = (*marker_used)[o.marker] = (*frame_used)[o.frame] = 1;
    num_corners += 4;
  }
  return num_corners;
}

// Manifold, constness and elimination group (`group`) of every used block of one kind; returns how many.
int SetBlocks(std::vector<PoseBlock>* blocks, const std::vector<char>& used, const std::vector<char>& fixed,
              int group, ceres::Manifold* manifold, ceres::Problem* problem,
              ceres::ParameterBlockOrdering* ordering) {
  int n = 0;
  for (size_t k = 0; k < used.size(); ++k) {
    if (!used[k]) continue;
    double* block = (*blocks)[k].data();
    problem->SetManifold(block, manifold);
    if (k < fixed.size() && fixed[k]) problem->SetParameterBlockConstant(block);
    ordering->AddElementToGroup(block, group);
    ++n;
  }
  return n;
}

// The linear solver ("auto": dense Schur for small reduced systems) and stopping rules.
ceres::Solver::Options SolverOptions(const BundleSettings& settings, int num_reduced, std::string* solver) {
  ceres::Solver::Options options;
  *solver = settings.linear_solver;
  if (*solver == "auto") *solver = num_reduced <= 200 ? "dense_schur" : "sparse_schur";
  if (*solver == "dense_schur") {
    options.linear_solver_type = ceres::DENSE_SCHUR;
  } else if (*solver == "iterative_schur") {
    options.linear_solver_type = ceres::ITERATIVE_SCHUR;
    options.preconditioner_type = ceres::SCHUR_JACOBI;
  } else {
    *solver = "sparse_schur";
    options.linear_solver_type = ceres::SPARSE_SCHUR;
  }
  options.num_threads = std::max(1, settings.threads);
  options.max_num_iterations = settings.max_iterations;
  options.function_tolerance = 1e-10;
  options.gradient_tolerance = 1e-12;
  options.parameter_tolerance = 1e-10;
  options.logging_type = ceres::SILENT;
  options.update_state_every_iteration = false;
  return options;
}

}  // namespace

BundleSummary SolveBundle(BundleProblem* bp, const BundleSettings& settings) {
  const auto start = std::chrono::steady_clock::now();
  BundleSummary out;
  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  LeftPoseManifold manifold;
  // Huber on the 8-residual block: sqrt(s) = 2 * RMS corner error, so a = 2 * huber_px puts the kink
  // where the observation's RMS corner error reaches huber_px.
  std::unique_ptr<ceres::LossFunction> loss;
  if (settings.huber_px > 0) loss.reset(new ceres::HuberLoss(2.0 * settings.huber_px));
  std::vector<char> camera_used(bp->cam_from_rig.size(), 0), marker_used(bp->object_from_marker.size(), 0),
      frame_used(bp->rig_from_object.size(), 0);
  const int num_corners = AddObservations(bp, loss.get(), &problem, &camera_used, &marker_used, &frame_used);
  if (num_corners == 0) {
    out.termination = "no observations";
    return out;
  }
  // Ceres orders the blocks of one group by address: cameras and markers (separate vectors, anywhere on the
  // heap relative to each other) get a group each, so the reduced system's order -- and the last bits of
  // the solution -- do not depend on where the heap put them. Frames (group 0) are eliminated first.
  auto* ordering = new ceres::ParameterBlockOrdering;
  int num_reduced =
      SetBlocks(&bp->cam_from_rig, camera_used, bp->camera_fixed, 1, &manifold, &problem, ordering);
  num_reduced +=
      SetBlocks(&bp->object_from_marker, marker_used, bp->marker_fixed, 2, &manifold, &problem, ordering);
  SetBlocks(&bp->rig_from_object, frame_used, bp->frame_fixed, 0, &manifold, &problem, ordering);
  ceres::Solver::Options options = SolverOptions(settings, num_reduced, &out.linear_solver);
  options.linear_solver_ordering.reset(ordering);
  ProgressCallback callback(settings, num_corners);
  options.callbacks.push_back(&callback);

  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  out.iterations = static_cast<int>(summary.iterations.size()) - 1;
  out.initial_cost = summary.initial_cost;
  out.final_cost = summary.final_cost;
  out.initial_rms_px = std::sqrt(2.0 * summary.initial_cost / num_corners);
  out.final_rms_px = std::sqrt(2.0 * summary.final_cost / num_corners);
  out.termination = ceres::TerminationTypeToString(summary.termination_type);
  if (summary.termination_type == ceres::USER_SUCCESS) out.termination = "PAPER_STOP";
  out.usable = summary.IsSolutionUsable();
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

std::vector<double> ObservationRms(const BundleProblem& bp, std::vector<double>* max_corner_px) {
  std::vector<double> out(bp.observations.size(), std::numeric_limits<double>::infinity());
  if (max_corner_px) max_corner_px->assign(bp.observations.size(), std::numeric_limits<double>::infinity());
  for (size_t i = 0; i < bp.observations.size(); ++i) {
    const BundleObservation& o = bp.observations[i];
    const Rigid3 cam_from_marker = RigidFromBlock(bp.cam_from_rig[o.camera].data()) *
                                   RigidFromBlock(bp.rig_from_object[o.frame].data()) *
                                   RigidFromBlock(bp.object_from_marker[o.marker].data());
    const MarkerCorners3d corners = MarkerCornersInMarker(o.side);
    double sum = 0.0, max_sq = 0.0;
    bool ok = true;
    for (int k = 0; k < 4 && ok; ++k) {
      Eigen::Vector2d pixel;
      if (!bp.models[o.camera]->Project(cam_from_marker * corners[k], &pixel, nullptr)) {
        ok = false;
      } else {
        const double sq = (pixel - o.corners[k]).squaredNorm();
        sum += sq;
        max_sq = std::max(max_sq, sq);
      }
    }
    if (ok) {
      out[i] = std::sqrt(sum / 4.0);
      if (max_corner_px) (*max_corner_px)[i] = std::sqrt(max_sq);
    }
  }
  return out;
}

}  // namespace mcmt
