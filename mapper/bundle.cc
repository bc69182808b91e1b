#include "mapper/bundle.h"

#include <ceres/normal_prior.h>

#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <numeric>
#include <optional>

#include "core/ippe.h"
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

ReprojectionCost::ReprojectionCost(const CameraModel* camera, const MarkerCorners2d& observed, double side,
                                   const CornerWeights* weights)
    : camera_(camera),
      observed_(observed),
      side_(side),
      weights_(weights ? std::make_unique<const CornerWeights>(*weights) : nullptr) {}

bool ReprojectionCost::Evaluate(double const* const* parameters, double* residuals,
                                double** jacobians) const {
  const ObservationCostInputs r{camera_, &observed_, side_, weights_.get(), false, nullptr};
  return EvaluateObservation(r, parameter_block_sizes(), parameters, residuals, jacobians);
}

std::vector<double> IntrinsicsVector(const CameraModel& model) {
  std::vector<double> v = {model.fx, model.fy, model.cx, model.cy};
  v.insert(v.end(), model.distortion.begin(), model.distortion.end());
  return v;
}

CameraModel ModelWithIntrinsics(const CameraModel& base, const double* values) {
  CameraModel m = base;
  m.fx = values[0];
  m.fy = values[1];
  m.cx = values[2];
  m.cy = values[3];
  for (size_t i = 0; i < m.distortion.size(); ++i) m.distortion[i] = values[4 + i];
  return m;
}

std::vector<std::string> IntrinsicsNames(const CameraModel& model) {
  std::vector<std::string> names = {"fx", "fy", "cx", "cy"};
  static const char* radtan[] = {"k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6"};
  static const char* fisheye[] = {"k1", "k2", "k3", "k4"};
  for (size_t i = 0; i < model.distortion.size() && i < 8; ++i)
    names.push_back(model.model == DistortionModel::kFisheye ? fisheye[i % 4] : radtan[i]);
  return names;
}

void IntrinsicsJacobian(CameraModel* camera, double x, double y, double* out) {
  const int n = 4 + static_cast<int>(camera->distortion.size());
  Eigen::Map<Eigen::Matrix<double, 2, Eigen::Dynamic, Eigen::RowMajor>> j(out, 2, n);
  double xd, yd;
  camera->Distort(x, y, &xd, &yd);
  j.leftCols<4>() << xd, 0, 1, 0, 0, yd, 0, 1;
  // Radtan with 4 or 5 coefficients and fisheye are affine in their coefficients: a forward difference is
  // exact (n - 4 calls of Distort instead of 2 (n - 4)); the rational model's needs the central one.
  const bool affine = !(camera->model == DistortionModel::kRadTan && camera->distortion.size() >= 8);
  const double h = 1e-4;
  for (int i = 0; i < n - 4; ++i) {
    double& coefficient = camera->distortion[i];
    const double saved = coefficient;
    double xp = 0, yp = 0, xm = xd, ym = yd;
    coefficient = saved + h;
    camera->Distort(x, y, &xp, &yp);
    if (!affine) {
      coefficient = saved - h;
      camera->Distort(x, y, &xm, &ym);
    }
    coefficient = saved;
    const double step = affine ? h : 2 * h;
    j(0, 4 + i) = camera->fx * (xp - xm) / step;
    j(1, 4 + i) = camera->fy * (yp - ym) / step;
  }
}

SelfCalibrationCost::SelfCalibrationCost(const CameraModel* camera, const MarkerCorners2d& observed,
                                         double side, bool with_intrinsics, const ObservationTime* time,
                                         const CornerWeights* weights)
    : camera_(camera),
      observed_(observed),
      side_(side),
      weighted_(weights != nullptr),
      weights_(weights ? *weights : CornerWeights()),
      with_intrinsics_(with_intrinsics),
      time_(time ? *time : ObservationTime{}),
      with_time_(time != nullptr) {
  set_num_residuals(8);
  std::vector<int32_t>* sizes = mutable_parameter_block_sizes();
  *sizes = {7, 7, 7};
  if (with_intrinsics_) sizes->push_back(4 + static_cast<int>(camera->distortion.size()));
  if (with_time_) sizes->push_back(1);
  if (with_time_ && time_.with_drift) sizes->push_back(1);
}

bool SelfCalibrationCost::Evaluate(double const* const* parameters, double* residuals,
                                   double** jacobians) const {
  const ObservationCostInputs r{camera_,
                                &observed_,
                                side_,
                                weighted_ ? &weights_ : nullptr,
                                with_intrinsics_,
                                with_time_ ? &time_ : nullptr};
  return EvaluateObservation(r, parameter_block_sizes(), parameters, residuals, jacobians);
}

namespace {

// Residuals and Jacobian rows (blocks of `sizes` columns) of each corner k multiplied by weights[k].
void Weigh(const CornerWeights& weights, const std::vector<int32_t>& sizes, double* residuals,
           double** jacobians) {
  for (int k = 0; k < 4; ++k) {
    const Eigen::Matrix2d& w = weights[k];
    Eigen::Map<Eigen::Vector2d> r(residuals + 2 * k);
    r = w * r;
    if (!jacobians) continue;
    for (size_t b = 0; b < sizes.size(); ++b) {
      if (!jacobians[b]) continue;
      Eigen::Map<Eigen::Matrix<double, 2, Eigen::Dynamic, Eigen::RowMajor>> rows(
          jacobians[b] + 2 * k * sizes[b], 2, sizes[b]);
      rows = w * rows;
    }
  }
}

}  // namespace

bool EvaluateObservation(const ObservationCostInputs& in, const std::vector<int32_t>& sizes,
                         double const* const* parameters, double* residuals, double** jacobians) {
  const bool with_intrinsics = in.with_intrinsics, with_time = in.time != nullptr;
  const bool with_drift = with_time && in.time->with_drift;
  const ObservationTime time = with_time ? *in.time : ObservationTime{};
  const MarkerCorners2d& observed = *in.observed;
  const MarkerCorners3d corners = MarkerCornersInMarker(in.side);
  const int intrinsics_block = with_intrinsics ? 3 : -1;
  const int time_block = with_time ? (with_intrinsics ? 4 : 3) : -1;
  const int drift_block = with_drift ? time_block + 1 : -1;
  CameraModel refined;  // also IntrinsicsJacobian's scratch (its coefficients shifted and restored)
  if (with_intrinsics) refined = ModelWithIntrinsics(*in.camera, parameters[intrinsics_block]);
  const CameraModel& camera = with_intrinsics ? refined : *in.camera;
  const Rigid3 cam_from_rig = RigidFromBlock(parameters[0]);
  const Rigid3 object_from_marker = RigidFromBlock(parameters[1]);
  Rigid3 rig_from_object = RigidFromBlock(parameters[2]);
  // The pose at the capture time: rotation Exp(dt w) * R, translation t + dt v.
  Eigen::Vector3d w = Eigen::Vector3d::Zero(), v = Eigen::Vector3d::Zero();
  Eigen::Matrix3d r_dt = Eigen::Matrix3d::Identity();
  if (with_time && time.velocity) {
    w = Eigen::Vector3d(time.velocity[0], time.velocity[1], time.velocity[2]);
    v = Eigen::Vector3d(time.velocity[3], time.velocity[4], time.velocity[5]);
    // capture time = utime - offset (- drift * clock_s)
    double dt = time.time_s - parameters[time_block][0];
    if (with_drift) dt -= parameters[drift_block][0] * time.clock_s;
    r_dt = RotationFromVector(dt * w);
    rig_from_object.linear() = r_dt * rig_from_object.linear();
    rig_from_object.translation() += dt * v;
  }
  const Eigen::Matrix3d& r_cam = cam_from_rig.linear();
  const Eigen::Matrix3d r_cam_frame = r_cam * rig_from_object.linear();
  const int n_intr = 4 + static_cast<int>(camera.distortion.size());
  using RowJ = Eigen::Matrix<double, 8, 7, Eigen::RowMajor>;
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector3d p_obj = object_from_marker * corners[k];
    const Eigen::Vector3d p_rig = rig_from_object * p_obj;
    const Eigen::Vector3d p_cam = cam_from_rig * p_rig;
    Eigen::Vector2d pixel;
    Eigen::Matrix<double, 2, 3> dpix;
    if (!camera.Project(p_cam, &pixel, jacobians ? &dpix : nullptr)) return false;
    residuals[2 * k] = pixel.x() - observed[k].x();
    residuals[2 * k + 1] = pixel.y() - observed[k].y();
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
      j.block<2, 3>(2 * k, 0) = -d * Skew(p_rig - rig_from_object.translation()) * r_dt;
      j.block<2, 3>(2 * k, 3) = d;
      j.block<2, 1>(2 * k, 6).setZero();
    }
    if (intrinsics_block >= 0 && jacobians[intrinsics_block]) {
      const double iz = 1.0 / p_cam.z();
      IntrinsicsJacobian(&refined, p_cam.x() * iz, p_cam.y() * iz,
                         jacobians[intrinsics_block] + 2 * k * n_intr);
    }
    if (time_block >= 0 && (jacobians[time_block] || (drift_block >= 0 && jacobians[drift_block]))) {
      const Eigen::Vector2d d = -dpix * r_cam * (w.cross(p_rig - rig_from_object.translation()) + v);
      if (jacobians[time_block]) {
        jacobians[time_block][2 * k] = d.x();
        jacobians[time_block][2 * k + 1] = d.y();
      }
      if (drift_block >= 0 && jacobians[drift_block]) {
        jacobians[drift_block][2 * k] = d.x() * time.clock_s;
        jacobians[drift_block][2 * k + 1] = d.y() * time.clock_s;
      }
    }
  }
  if (in.weights) Weigh(*in.weights, sizes, residuals, jacobians);
  return true;
}

CameraModel BundleProblem::Model(int camera) const {
  if (!RefinesIntrinsics(camera)) return *models[camera];
  return ModelWithIntrinsics(*models[camera], intrinsics[camera].values.data());
}

double BundleProblem::ObservationDt(size_t k) const {
  if (!RefinesTime()) return 0.0;
  const BundleObservation& o = observations[k];
  const double drift = RefinesDrift() ? time_drift[o.camera] * o.clock_s : 0.0;
  return o.time_s - time_offset_s[o.camera] - drift;
}

// Frames further apart than this many typical frame intervals do not give each other a velocity (time
// offsets). Relative to the session's own frame rate (a fixed 0.1 s left every frame of a 6 fps recording
// without a velocity, so its offsets were unobservable).
constexpr double kVelocityGapFrames = 2.5;

double VelocityGapS(const BundleProblem& bp) {
  std::vector<double> intervals;
  for (size_t f = 1; f < bp.frame_time_s.size(); ++f)
    if (bp.frame_time_s[f] > bp.frame_time_s[f - 1])
      intervals.push_back(bp.frame_time_s[f] - bp.frame_time_s[f - 1]);
  return kVelocityGapFrames * Median(intervals, 0.0);
}

void UpdateFrameVelocities(double max_gap_s, BundleProblem* bp) {
  const size_t n = bp->rig_from_object.size();
  bp->frame_velocity.assign(n, {0, 0, 0, 0, 0, 0});
  auto usable = [&](size_t a, size_t b) {
    const double gap = std::abs(bp->frame_time_s[b] - bp->frame_time_s[a]);
    return gap > 0 && gap <= max_gap_s;
  };
  for (size_t f = 0; f < n; ++f) {
    const size_t lo = f > 0 && usable(f - 1, f) ? f - 1 : f;
    const size_t hi = f + 1 < n && usable(f, f + 1) ? f + 1 : f;
    if (lo == hi) continue;
    const Rigid3 a = RigidFromBlock(bp->rig_from_object[lo].data());
    const Rigid3 b = RigidFromBlock(bp->rig_from_object[hi].data());
    const double span = bp->frame_time_s[hi] - bp->frame_time_s[lo];
    const Eigen::Vector3d w = VectorFromRotation(b.linear() * a.linear().transpose()) / span;
    const Eigen::Vector3d v = (b.translation() - a.translation()) / span;
    bp->frame_velocity[f] = {w.x(), w.y(), w.z(), v.x(), v.y(), v.z()};
  }
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

// Observation k's times for SelfCalibrationCost (the frame's velocity when the clocks are refined).
ObservationTime ObservationTimeOf(const BundleProblem& bp, size_t k) {
  const BundleObservation& o = bp.observations[k];
  ObservationTime time;
  time.time_s = o.time_s;
  time.with_drift = bp.RefinesDrift();
  time.clock_s = o.clock_s;
  if (bp.RefinesTime()) time.velocity = bp.frame_velocity[o.frame].data();
  return time;
}

// The kinds of parameter block, in SelfCalibrationCost's order.
enum class BlockKind { kCamera, kMarker, kFrame, kIntrinsics, kTimeOffset, kDrift };

// Whether the solve holds the whole block `index` of `kind` constant: the gauge's fixed poses, a fixed
// clock (its offset and drift), intrinsics with every entry constant. (Intrinsics with some entries
// constant hold those through a SubsetManifold: BundleIntrinsics::constant.) The one rule BuildProblem
// and the information's unknowns (FreeEntries) both follow.
bool HeldWhole(const BundleProblem& bp, BlockKind kind, int index) {
  auto fixed = [index](const std::vector<char>& v) {
    return static_cast<size_t>(index) < v.size() && v[index];
  };
  switch (kind) {
    case BlockKind::kCamera:
      return fixed(bp.camera_fixed);
    case BlockKind::kMarker:
      return fixed(bp.marker_fixed);
    case BlockKind::kFrame:
      return fixed(bp.frame_fixed);
    case BlockKind::kIntrinsics:
      return bp.intrinsics[index].constant.size() >= bp.intrinsics[index].values.size();
    case BlockKind::kTimeOffset:
    case BlockKind::kDrift:
      return fixed(bp.time_offset_fixed);
  }
  return false;
}

// The kind of block b of observation k's residual (ObservationBlocks' order) and its index.
std::pair<BlockKind, int> ObservationBlockKind(const BundleProblem& bp, size_t k, int b) {
  const BundleObservation& o = bp.observations[k];
  if (b == 0) return {BlockKind::kCamera, o.camera};
  if (b == 1) return {BlockKind::kMarker, o.marker};
  if (b == 2) return {BlockKind::kFrame, o.frame};
  if (bp.RefinesIntrinsics(o.camera) && b == 3) return {BlockKind::kIntrinsics, o.camera};
  const int after = bp.RefinesIntrinsics(o.camera) ? 4 : 3;
  return {b == after && bp.RefinesTime() ? BlockKind::kTimeOffset : BlockKind::kDrift, o.camera};
}

// The parameter blocks of observation k's residual (SelfCalibrationCost's order) and their sizes.
std::vector<std::pair<double*, int>> ObservationBlocks(BundleProblem* bp, size_t k) {
  const BundleObservation& o = bp->observations[k];
  std::vector<std::pair<double*, int>> blocks = {{bp->cam_from_rig[o.camera].data(), 7},
                                                 {bp->object_from_marker[o.marker].data(), 7},
                                                 {bp->rig_from_object[o.frame].data(), 7}};
  if (bp->RefinesIntrinsics(o.camera)) {
    std::vector<double>& values = bp->intrinsics[o.camera].values;
    blocks.push_back({values.data(), static_cast<int>(values.size())});
  }
  if (bp->RefinesTime()) blocks.push_back({&bp->time_offset_s[o.camera], 1});
  if (bp->RefinesDrift()) blocks.push_back({&bp->time_drift[o.camera], 1});
  return blocks;
}

// The square root of the intrinsics prior's information, entry k (0: no prior on it): pixels per unit.
double IntrinsicsPriorWeight(const BundleIntrinsics& in, int k) {
  return in.sigma[k] > 0 ? in.prior_scale_px / in.sigma[k] : 0.0;
}

void AddSelfCalibrationResidual(BundleProblem* bp, size_t i, const CornerWeights* weights,
                                ceres::LossFunction* loss, ceres::Problem* problem) {
  const BundleObservation& o = bp->observations[i];
  const ObservationTime time = ObservationTimeOf(*bp, i);
  std::vector<double*> blocks;
  for (const auto& block : ObservationBlocks(bp, i)) blocks.push_back(block.first);
  problem->AddResidualBlock(
      new SelfCalibrationCost(bp->models[o.camera], o.corners, o.side, bp->RefinesIntrinsics(o.camera),
                              bp->RefinesTime() ? &time : nullptr, weights),
      loss, blocks);
}

// Intrinsics blocks (entries held constant through a SubsetManifold, a Gaussian prior on the others) and
// time offsets of the cameras in use; returns the number of blocks added to the reduced system.
int AddSelfCalibrationBlocks(BundleProblem* bp, const std::vector<char>& camera_used,
                             ceres::ParameterBlockOrdering* ordering,
                             std::vector<std::unique_ptr<ceres::Manifold>>* subsets,
                             ceres::Problem* problem) {
  int added = 0;
  for (size_t c = 0; c < camera_used.size(); ++c) {
    if (!camera_used[c]) continue;
    if (bp->RefinesIntrinsics(static_cast<int>(c))) {
      BundleIntrinsics& in = bp->intrinsics[c];
      double* block = in.values.data();
      const int n = static_cast<int>(in.values.size());
      if (HeldWhole(*bp, BlockKind::kIntrinsics, static_cast<int>(c))) {
        problem->SetParameterBlockConstant(block);
      } else if (!in.constant.empty()) {
        subsets->emplace_back(new ceres::SubsetManifold(n, in.constant));
        problem->SetManifold(block, subsets->back().get());
      }
      Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, n);
      for (int k = 0; k < n; ++k) a(k, k) = IntrinsicsPriorWeight(in, k);
      const Eigen::VectorXd b = Eigen::Map<const Eigen::VectorXd>(in.prior.data(), n);
      problem->AddResidualBlock(new ceres::NormalPrior(a, b), nullptr, block);
      ordering->AddElementToGroup(block, 3);  // intrinsics (see the note on groups in BuildProblem)
      ++added;
    }
    if (bp->RefinesTime()) {
      double* block = &bp->time_offset_s[c];
      if (HeldWhole(*bp, BlockKind::kTimeOffset, static_cast<int>(c)))
        problem->SetParameterBlockConstant(block);
      ordering->AddElementToGroup(block, 4);  // clock offsets
      ++added;
    }
    if (bp->RefinesDrift()) {
      double* block = &bp->time_drift[c];
      if (HeldWhole(*bp, BlockKind::kDrift, static_cast<int>(c))) {
        problem->SetParameterBlockConstant(block);
      } else {
        Eigen::MatrixXd a(1, 1);
        a(0, 0) = 1.0 / kDriftPriorSigma;
        problem->AddResidualBlock(new ceres::NormalPrior(a, Eigen::VectorXd::Zero(1)), nullptr, block);
      }
      ordering->AddElementToGroup(block, 5);  // clock drifts
      ++added;
    }
  }
  return added;
}

// Manifold, constness and elimination group (`group`) of every used block of one kind; returns how many.
int SetBlocks(const BundleProblem& bp, BlockKind kind, std::vector<PoseBlock>* blocks,
              const std::vector<char>& used, int group, ceres::Manifold* manifold, ceres::Problem* problem,
              ceres::ParameterBlockOrdering* ordering) {
  int n = 0;
  for (size_t k = 0; k < used.size(); ++k) {
    if (!used[k]) continue;
    double* block = (*blocks)[k].data();
    problem->SetManifold(block, manifold);
    if (HeldWhole(bp, kind, static_cast<int>(k))) problem->SetParameterBlockConstant(block);
    ordering->AddElementToGroup(block, group);
    ++n;
  }
  return n;
}

// Levenberg-Marquardt's first trust region (Ceres' default 1e4) with intrinsics or clocks among the
// unknowns: a focal length trades with its camera's distance and an offset with the object's motion, weak
// directions of J^T J that the default damping (1 / radius, relative to its diagonal) kept from moving
// for many iterations while the radius grew 3x per step: bench_selfcal's everything row's solve with the
// intrinsics took 9 iterations to the 1e-6 px stop (the RMS falling by 1e-4 px an iteration), 3 from
// 1e8, to the same RMS (0.2791268 px) and cameras; a step that fails shrinks the radius as before.
constexpr double kSelfCalibrationTrustRegionRadius = 1e8;

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

namespace {

// The Ceres problem of a BundleProblem: what it points to lives as long as it (members destroyed in
// reverse order: the problem first).
struct BuiltProblem {
  LeftPoseManifold manifold;
  std::unique_ptr<ceres::LossFunction> loss;
  std::vector<std::unique_ptr<ceres::LossFunction>> weighted;  // per observation (view weighting)
  std::vector<std::unique_ptr<ceres::Manifold>> subsets;
  std::unique_ptr<ceres::Problem> problem;
  ceres::ParameterBlockOrdering* ordering = nullptr;  // owned by the solver options once solved
  std::vector<char> camera_used, marker_used, frame_used;
  int num_corners = 0;
  int num_reduced = 0;
};

// cos of the angle between marker o's normal and the direction from its centre to the camera, at the
// problem's current estimate (clamped to [0.05, 1]).
double ViewCosine(const BundleProblem& bp, const BundleObservation& o) {
  const Rigid3 cam_from_marker = RigidFromBlock(bp.cam_from_rig[o.camera].data()) *
                                 RigidFromBlock(bp.rig_from_object[o.frame].data()) *
                                 RigidFromBlock(bp.object_from_marker[o.marker].data());
  return std::clamp(FacingCosine(cam_from_marker), 0.05, 1.0);
}

void BuildProblem(BundleProblem* bp, const BundleSettings& settings, BuiltProblem* out) {
  const double huber_px = settings.huber_px, view_weight_power = settings.view_weight_power;
  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  out->problem.reset(new ceres::Problem(problem_options));
  ceres::Problem& problem = *out->problem;
  // Huber on the 8-residual block: sqrt(s) = 2 * RMS corner error, so a = 2 * huber_px puts the kink
  // where the observation's RMS corner error reaches huber_px.
  if (huber_px > 0) out->loss.reset(new ceres::HuberLoss(2.0 * huber_px));
  out->camera_used.assign(bp->cam_from_rig.size(), 0);
  out->marker_used.assign(bp->object_from_marker.size(), 0);
  out->frame_used.assign(bp->rig_from_object.size(), 0);
  for (size_t i = 0; i < bp->observations.size(); ++i) {
    if (!bp->active[i]) continue;
    const BundleObservation& o = bp->observations[i];
    ceres::LossFunction* loss = out->loss.get();
    if (view_weight_power > 0) {
      out->weighted.emplace_back(new ceres::ScaledLoss(loss, std::pow(ViewCosine(*bp, o), view_weight_power),
                                                       ceres::DO_NOT_TAKE_OWNERSHIP));
      loss = out->weighted.back().get();
    }
    const std::optional<CornerWeights> weights = settings.corner_weighting.For(o.corners);
    const CornerWeights* w = weights ? &*weights : nullptr;
    if (bp->RefinesIntrinsics(o.camera) || bp->RefinesTime()) {
      AddSelfCalibrationResidual(bp, i, w, loss, &problem);
    } else {
      problem.AddResidualBlock(ReprojectionCost::Create(bp->models[o.camera], o.corners, o.side, w), loss,
                               bp->cam_from_rig[o.camera].data(), bp->object_from_marker[o.marker].data(),
                               bp->rig_from_object[o.frame].data());
    }
    out->camera_used[o.camera] = out->marker_used[o.marker] = out->frame_used[o.frame] = 1;
    out->num_corners += 4;
  }
  if (out->num_corners == 0) return;
  // Ceres orders the blocks of one group by address: cameras, markers, intrinsics and clock offsets (separate
  // vectors, anywhere on the heap relative to each other) get a group each, so the reduced system's order --
  // and the last bits of the solution -- do not depend on where the heap put them. Frames (group 0) are
  // eliminated first.
  out->ordering = new ceres::ParameterBlockOrdering;
  out->num_reduced = SetBlocks(*bp, BlockKind::kCamera, &bp->cam_from_rig, out->camera_used, 1,
                               &out->manifold, &problem, out->ordering);
  out->num_reduced += SetBlocks(*bp, BlockKind::kMarker, &bp->object_from_marker, out->marker_used, 2,
                                &out->manifold, &problem, out->ordering);
  SetBlocks(*bp, BlockKind::kFrame, &bp->rig_from_object, out->frame_used, 0, &out->manifold, &problem,
            out->ordering);
  out->num_reduced += AddSelfCalibrationBlocks(bp, out->camera_used, out->ordering, &out->subsets, &problem);
}

}  // namespace

BundleSummary SolveBundle(BundleProblem* bp, const BundleSettings& settings) {
  const auto start = std::chrono::steady_clock::now();
  BundleSummary out;
  BuiltProblem built;
  BuildProblem(bp, settings, &built);
  if (built.num_corners == 0) {
    out.termination = "no observations";
    return out;
  }
  ceres::Problem& problem = *built.problem;
  ceres::ParameterBlockOrdering* ordering = built.ordering;
  const int num_reduced = built.num_reduced;
  const int num_corners = built.num_corners;

  ceres::Solver::Options options = SolverOptions(settings, num_reduced, &out.linear_solver);
  options.linear_solver_ordering.reset(ordering);
  if (!bp->intrinsics.empty() || bp->RefinesTime())
    options.initial_trust_region_radius = kSelfCalibrationTrustRegionRadius;
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

Rigid3 ObservedFramePose(const BundleProblem& bp, size_t k) {
  return FramePoseAt(bp, bp.observations[k].frame, bp.ObservationDt(k));
}

Rigid3 FramePoseAt(const BundleProblem& bp, int frame, double dt) {
  const Rigid3 pose = RigidFromBlock(bp.rig_from_object[frame].data());
  if (!bp.RefinesTime() || bp.frame_velocity.size() <= static_cast<size_t>(frame)) return pose;
  return MovedAlong(pose, bp.frame_velocity[frame], dt);
}

namespace {

// Where one residual block's rows of the information's Jacobian come from: its reduced unknowns' columns
// (increasing) and per column the block and the entry of that block's Jacobian (row-major, `width`
// entries a row) it reads.
struct RowsLayout {
  std::vector<int> cols;
  std::vector<int> block, entry, width;
};

// One residual block's rows (`rows`, at most 8 + the intrinsics' size): its Jacobian per parameter block
// (ambient, row-major), its reduced columns after `layout`, and its frame (-1: none) with that frame's 6
// columns the first 6 entries of each row of block `frame_block` (`frame_width` a row).
struct InformationRows {
  int frame = -1;
  int rows = 0;
  const RowsLayout* layout = nullptr;
  const double* const* jacobians = nullptr;
  int frame_block = 2, frame_width = 7;
};

// The information (J^T J) of the unknowns other than the frame poses, marginal over the frames: each
// residual touches one frame block, so the frames' part of J^T J is block-diagonal (6 x 6 per frame) and
// the Schur complement S = H_rr - H_rf H_ff^-1 H_fr is formed frame by frame (dense, a few hundred
// unknowns; the sparse factorisation of the whole J^T J it replaces took several times as long). The
// residual blocks are added frame by frame (the rows without a frame first), each frame's in the order of
// the observations; consecutive blocks with the same columns are gathered and added as one product.
// S is symmetric: only its lower triangle is accumulated (each pair of unknowns once), copied to the upper
// one at the end.
// Adds J^T J of the first `rows` rows of row-major `j` (one column per entry of `cols`, increasing) to the
// lower triangle of s at rows and columns `cols`: each entry the sum over the rows in their order, two
// columns at a time (Eigen's 2-lane packets; plain loops over these small blocks cost several times their
// arithmetic). kRows > 0: `rows` known at compile time (column a's entries held in registers).
template <int kRows>
void AddGram(const double* j, int rows, const std::vector<int>& cols, Eigen::MatrixXd* s) {
  using Lanes = Eigen::Array2d;
  const int k = static_cast<int>(cols.size());
  const int n = kRows > 0 ? kRows : rows;
  for (int a = 0; a < k; ++a) {
    Lanes x[kRows > 0 ? kRows : 1];
    if constexpr (kRows > 0)
      for (int i = 0; i < kRows; ++i) x[i] = Lanes::Constant(j[i * k + a]);
    double* column = s->data() + static_cast<size_t>(cols[a]) * s->rows();
    int b = a;
    for (; b + 3 < k; b += 4) {  // four columns: two packets
      Lanes v = Lanes::Zero(), w = Lanes::Zero();
      for (int i = 0; i < n; ++i) {
        const Lanes xi = kRows > 0 ? x[i] : Lanes::Constant(j[i * k + a]);
        v += xi * Eigen::Map<const Lanes>(j + i * k + b);
        w += xi * Eigen::Map<const Lanes>(j + i * k + b + 2);
      }
      column[cols[b]] += v[0];
      column[cols[b + 1]] += v[1];
      column[cols[b + 2]] += w[0];
      column[cols[b + 3]] += w[1];
    }
    for (; b + 1 < k; b += 2) {
      Lanes v = Lanes::Zero();
      for (int i = 0; i < n; ++i)
        v += (kRows > 0 ? x[i] : Lanes::Constant(j[i * k + a])) * Eigen::Map<const Lanes>(j + i * k + b);
      column[cols[b]] += v[0];
      column[cols[b + 1]] += v[1];
    }
    if (b < k) {
      double v = 0.0;
      for (int i = 0; i < n; ++i) v += j[i * k + a] * j[i * k + b];
      column[cols[b]] += v;
    }
  }
}

class FramesMarginaliser {
 public:
  explicit FramesMarginaliser(int num_reduced)
      : s_(Eigen::MatrixXd::Zero(num_reduced, num_reduced)), slot_(num_reduced, -1), hrf_(num_reduced, 6) {
    hff_.setZero();
  }
  void Add(const InformationRows& r) {
    if (started_ && r.frame != frame_) FinishFrame();
    started_ = true;
    frame_ = r.frame;
    const RowsLayout& layout = *r.layout;
    if (group_rows_ > 0 && layout.cols != cols_) FinishGroup();
    const int k = static_cast<int>(layout.cols.size());
    if (group_rows_ == 0) {
      cols_ = layout.cols;
      jr_.resize(std::max(8, r.rows), k);
      jf_.resize(std::max(8, r.rows), 6);
    } else if (group_rows_ + r.rows > jr_.rows()) {
      jr_.conservativeResize(std::max(2 * group_rows_, group_rows_ + r.rows), Eigen::NoChange);
      jf_.conservativeResize(jr_.rows(), Eigen::NoChange);
    }
    for (int a = 0; a < k; ++a) {
      const double* from = r.jacobians[layout.block[a]] + layout.entry[a];
      for (int i = 0; i < r.rows; ++i) jr_(group_rows_ + i, a) = from[i * layout.width[a]];
    }
    if (frame_ >= 0)
      for (int i = 0; i < r.rows; ++i)
        for (int a = 0; a < 6; ++a)
          jf_(group_rows_ + i, a) = r.jacobians[r.frame_block][i * r.frame_width + a];
    group_rows_ += r.rows;
  }
  Eigen::MatrixXd Finish() {
    FinishFrame();
    for (int c = 1; c < s_.cols(); ++c)
      for (int r = 0; r < c; ++r) s_(r, c) = s_(c, r);
    return std::move(s_);
  }

 private:
  void FinishGroup();
  void FinishFrame();

  Eigen::MatrixXd s_;
  std::vector<int> slot_, seen_;  // a frame's reduced unknowns and their rows in hrf_
  Eigen::Matrix<double, Eigen::Dynamic, 6> hrf_;
  Eigen::Matrix<double, 6, 6> hff_;
  std::vector<int> cols_;
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> jr_;  // the group's rows over cols_
  Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor> jf_;
  Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor> bt_, xt_;  // a frame's H_rf and H_rf H_ff^-1
  Eigen::Matrix<double, 6, Eigen::Dynamic, Eigen::RowMajor> xk_;       // xt_ transposed
  std::vector<size_t> column_;
  int group_rows_ = 0, frame_ = -1;
  bool started_ = false;
};

void FramesMarginaliser::FinishGroup() {
  if (group_rows_ == 0) return;
  const int k = static_cast<int>(cols_.size());
  if (group_rows_ == 8)  // one observation's rows: the usual group
    AddGram<8>(jr_.data(), group_rows_, cols_, &s_);
  else
    AddGram<0>(jr_.data(), group_rows_, cols_, &s_);
  if (frame_ >= 0) {
    const auto f = jf_.topRows(group_rows_);
    hff_ += f.transpose() * f;
    for (int a = 0; a < k; ++a) {
      if (slot_[cols_[a]] < 0) {
        slot_[cols_[a]] = static_cast<int>(seen_.size());
        hrf_.row(seen_.size()).setZero();
        seen_.push_back(cols_[a]);
      }
      Eigen::Matrix<double, 1, 6> rf = Eigen::Matrix<double, 1, 6>::Zero();
      for (int i = 0; i < group_rows_; ++i) rf += jr_(i, a) * jf_.row(i);
      hrf_.row(slot_[cols_[a]]) += rf;
    }
  }
  group_rows_ = 0;
}

void FramesMarginaliser::FinishFrame() {
  FinishGroup();
  if (!seen_.empty()) {
    // B H_ff^-1 B^T, symmetric: each pair (x <= y, in the order first seen) once into the lower triangle,
    // bt_.row(x).dot(xt_.row(y)) summed as Eigen's 6-long dot does (even and odd entries apart), two y at
    // a time.
    const int n = static_cast<int>(seen_.size());
    bt_ = hrf_.topRows(n);
    xt_ = Eigen::LDLT<Eigen::Matrix<double, 6, 6>>(hff_).solve(bt_.transpose()).transpose();
    xk_ = xt_.transpose();
    column_.resize(n);  // each unknown's column's start in s_
    for (int y = 0; y < n; ++y) column_[y] = static_cast<size_t>(seen_[y]) * s_.rows();
    double* s = s_.data();
    // The lower triangle's entry of s_ for the unknowns of slots x and y.
    auto at = [&](int x, int y) -> double& {
      return s[seen_[y] > seen_[x] ? column_[x] + seen_[y] : column_[y] + seen_[x]];
    };
    using Lanes = Eigen::Array2d;
    using Load = Eigen::Map<const Lanes>;
    const double *x0 = &xk_(0, 0), *x1 = &xk_(1, 0), *x2 = &xk_(2, 0), *x3 = &xk_(3, 0), *x4 = &xk_(4, 0),
                 *x5 = &xk_(5, 0);
    for (int x = 0; x < n; ++x) {
      const double* b = &bt_(x, 0);
      const Lanes p0 = Lanes::Constant(b[0]), p1 = Lanes::Constant(b[1]), p2 = Lanes::Constant(b[2]),
                  p3 = Lanes::Constant(b[3]), p4 = Lanes::Constant(b[4]), p5 = Lanes::Constant(b[5]);
      int y = x;
      for (; y + 1 < n; y += 2) {
        const Lanes v = (p0 * Load(x0 + y) + (p2 * Load(x2 + y) + p4 * Load(x4 + y))) +
                        (p1 * Load(x1 + y) + (p3 * Load(x3 + y) + p5 * Load(x5 + y)));
        at(x, y) -= v[0];
        at(x, y + 1) -= v[1];
      }
      if (y < n)
        at(x, y) -=
            (b[0] * x0[y] + (b[2] * x2[y] + b[4] * x4[y])) + (b[1] * x1[y] + (b[3] * x3[y] + b[5] * x5[y]));
    }
  }
  for (int c : seen_) slot_[c] = -1;
  seen_.clear();
  hff_.setZero();
}

}  // namespace

namespace {

// The unknowns of the information's Jacobian (IntrinsicsInformationOf): per parameter block its first
// column (-1: held constant or unused) and its free entries' ambient indices (the tangent's order). Columns
// in the order Ceres' Problem::GetParameterBlocks gives the blocks of BuildProblem (as first met among the
// active observations' residual blocks), the frames' after the others (6 each).
struct InformationColumns {
  std::map<const double*, int> column;
  std::map<const double*, std::vector<int>> free;
  int num_reduced = 0;
  int num_frames = 0;
};

// The free entries of block b of observation k's residual (empty: held constant), as BuildProblem holds
// them (HeldWhole; the intrinsics' constant entries).
std::vector<int> FreeEntries(const BundleProblem& bp, size_t k, int b, int size) {
  const auto [kind, index] = ObservationBlockKind(bp, k, b);
  std::vector<int> free;
  if (HeldWhole(bp, kind, index)) return free;
  const std::vector<int>* held = kind == BlockKind::kIntrinsics ? &bp.intrinsics[index].constant : nullptr;
  for (int i = 0; i < (size == 7 ? 6 : size); ++i)
    if (!held || std::find(held->begin(), held->end(), i) == held->end()) free.push_back(i);
  return free;
}

InformationColumns ColumnsForInformation(BundleProblem* bp) {
  InformationColumns out;
  std::vector<const double*> frames;
  for (size_t k = 0; k < bp->observations.size(); ++k) {
    if (!bp->active[k]) continue;
    const std::vector<std::pair<double*, int>> blocks = ObservationBlocks(bp, k);
    for (size_t b = 0; b < blocks.size(); ++b) {
      if (out.free.count(blocks[b].first)) continue;
      out.free[blocks[b].first] = FreeEntries(*bp, k, static_cast<int>(b), blocks[b].second);
      if (out.free[blocks[b].first].empty()) continue;
      if (b == 2) {
        frames.push_back(blocks[b].first);
      } else {
        out.column[blocks[b].first] = out.num_reduced;
        out.num_reduced += static_cast<int>(out.free[blocks[b].first].size());
      }
    }
  }
  for (size_t f = 0; f < frames.size(); ++f)
    out.column[frames[f]] = out.num_reduced + 6 * static_cast<int>(f);
  out.num_frames = static_cast<int>(frames.size());
  return out;
}

// The reduced columns of the rows of a residual block over `blocks` (its parameter blocks and their
// ambient sizes): increasing, with where each reads its Jacobian. The frames' columns are left out.
RowsLayout LayoutOf(const std::vector<std::pair<const double*, int>>& blocks,
                    const InformationColumns& columns) {
  std::vector<std::pair<int, std::pair<int, int>>> entries;  // (column, (block, ambient index))
  for (size_t b = 0; b < blocks.size(); ++b) {
    const auto it = columns.column.find(blocks[b].first);
    if (it == columns.column.end() || it->second >= columns.num_reduced) continue;
    const std::vector<int>& free = columns.free.at(blocks[b].first);
    for (size_t a = 0; a < free.size(); ++a)
      entries.push_back({it->second + static_cast<int>(a), {static_cast<int>(b), free[a]}});
  }
  std::sort(entries.begin(), entries.end());
  RowsLayout out;
  for (const auto& e : entries) {
    out.cols.push_back(e.first);
    out.block.push_back(e.second.first);
    out.entry.push_back(e.second.second);
    out.width.push_back(blocks[e.second.first].second);
  }
  return out;
}

// The rows of the priors (AddSelfCalibrationBlocks' order: per camera in use, its intrinsics' then its
// drift's), added to `m`.
void AddPriorRows(BundleProblem* bp, const InformationColumns& columns, FramesMarginaliser* m) {
  std::vector<char> used(bp->cam_from_rig.size(), 0);
  for (size_t k = 0; k < bp->observations.size(); ++k)
    if (bp->active[k]) used[bp->observations[k].camera] = 1;
  InformationRows rows;
  for (size_t c = 0; c < used.size(); ++c) {
    if (!used[c]) continue;
    if (bp->RefinesIntrinsics(static_cast<int>(c))) {
      const BundleIntrinsics& in = bp->intrinsics[c];
      const int n = static_cast<int>(in.values.size());
      std::vector<double> a(n * n, 0.0);
      for (int k = 0; k < n; ++k) a[k * n + k] = IntrinsicsPriorWeight(in, k);
      const RowsLayout layout = LayoutOf({{in.values.data(), n}}, columns);
      const double* jacobians[] = {a.data()};
      rows.rows = n;
      rows.layout = &layout;
      rows.jacobians = jacobians;
      m->Add(rows);
    }
    if (bp->RefinesDrift() && !bp->time_offset_fixed[c]) {
      const double a = 1.0 / kDriftPriorSigma;
      const RowsLayout layout = LayoutOf({{&bp->time_drift[c], 1}}, columns);
      const double* jacobians[] = {&a};
      rows.rows = 1;
      rows.layout = &layout;
      rows.jacobians = jacobians;
      m->Add(rows);
    }
  }
}

// An observation's Jacobian (per parameter block, ambient, row-major) and the reduced columns' layouts per
// camera and marker (made when first needed).
struct ObservationScratch {
  std::vector<std::unique_ptr<RowsLayout>> layouts;
  std::vector<double> jacobian;
  double* blocks[6];
};

// Observation k's rows (corner residuals without loss) at the current parameters over the free unknowns,
// its frame `frame` (-1: held), its Jacobian in `scratch`. False when a corner is behind its camera.
bool ObservationRows(BundleProblem* bp, size_t k, int frame, const InformationColumns& columns,
                     ObservationScratch* scratch, InformationRows* out) {
  const BundleObservation& o = bp->observations[k];
  const ObservationTime time = ObservationTimeOf(*bp, k);
  const SelfCalibrationCost cost(bp->models[o.camera], o.corners, o.side, bp->RefinesIntrinsics(o.camera),
                                 bp->RefinesTime() ? &time : nullptr);
  const std::vector<std::pair<double*, int>> blocks = ObservationBlocks(bp, k);
  std::unique_ptr<RowsLayout>& layout = scratch->layouts[o.camera * bp->object_from_marker.size() + o.marker];
  if (!layout)
    layout = std::make_unique<RowsLayout>(
        LayoutOf(std::vector<std::pair<const double*, int>>(blocks.begin(), blocks.end()), columns));
  int size = 0;
  for (const auto& b : blocks) size += 8 * b.second;
  scratch->jacobian.assign(size, 0.0);
  const double* parameters[6];
  size = 0;
  for (size_t b = 0; b < blocks.size(); ++b) {
    parameters[b] = blocks[b].first;
    scratch->blocks[b] = scratch->jacobian.data() + size;
    size += 8 * blocks[b].second;
  }
  double residuals[8];
  if (!cost.Evaluate(parameters, residuals, scratch->blocks)) return false;
  out->frame = frame;
  out->rows = 8;
  out->layout = layout.get();
  out->jacobians = scratch->blocks;
  return true;
}

}  // namespace

IntrinsicsInformation IntrinsicsInformationOf(BundleProblem* bp) {
  IntrinsicsInformation out;
  out.column.assign(bp->cam_from_rig.size(), -1);
  out.entries.resize(bp->cam_from_rig.size());
  const InformationColumns columns = ColumnsForInformation(bp);
  if (columns.column.empty()) return out;
  // The Jacobian's rows (the corners', then the priors') frame by frame, those without a frame first.
  std::vector<std::pair<int, size_t>> order;  // (frame, observation)
  for (size_t k = 0; k < bp->observations.size(); ++k) {
    if (!bp->active[k]) continue;
    const auto it = columns.column.find(bp->rig_from_object[bp->observations[k].frame].data());
    order.push_back({it == columns.column.end() ? -1 : (it->second - columns.num_reduced) / 6, k});
  }
  std::stable_sort(
      order.begin(), order.end(),
      [](const std::pair<int, size_t>& a, const std::pair<int, size_t>& b) { return a.first < b.first; });
  FramesMarginaliser marginaliser(columns.num_reduced);
  ObservationScratch scratch;
  scratch.layouts.resize(bp->cam_from_rig.size() * bp->object_from_marker.size());
  InformationRows rows;
  bool priors = false;
  for (const auto& [frame, k] : order) {
    if (frame >= 0 && !priors) {
      AddPriorRows(bp, columns, &marginaliser);
      priors = true;
    }
    if (!ObservationRows(bp, k, frame, columns, &scratch, &rows)) return out;
    marginaliser.Add(rows);
  }
  if (!priors) AddPriorRows(bp, columns, &marginaliser);
  out.information = marginaliser.Finish();
  for (size_t c = 0; c < out.column.size(); ++c) {
    if (!bp->RefinesIntrinsics(static_cast<int>(c))) continue;
    const BundleIntrinsics& in = bp->intrinsics[c];
    const auto it = columns.column.find(in.values.data());
    if (it == columns.column.end()) continue;
    out.column[c] = it->second;
    out.entries[c] = columns.free.at(in.values.data());
  }
  return out;
}

std::vector<Eigen::MatrixXd> IntrinsicsCovariance(const IntrinsicsInformation& info, const BundleProblem& bp,
                                                  double sigma_px) {
  std::vector<Eigen::MatrixXd> out(bp.cam_from_rig.size());
  const int num_reduced = static_cast<int>(info.information.rows());
  if (num_reduced == 0) return out;
  // The unknowns still free: every column but those of the intrinsics entries held since (their rows and
  // columns dropped: the frames' Schur complement of the rest is that submatrix).
  std::vector<char> keep(num_reduced, 1);
  for (size_t c = 0; c < out.size(); ++c) {
    if (info.column[c] < 0) continue;
    const std::vector<int>& entries = info.entries[c];
    for (size_t a = 0; a < entries.size(); ++a) {
      const std::vector<int>& constant = bp.intrinsics[c].constant;
      const bool held = !bp.RefinesIntrinsics(static_cast<int>(c)) ||
                        std::find(constant.begin(), constant.end(), entries[a]) != constant.end();
      if (held) keep[info.column[c] + a] = 0;
    }
  }
  std::vector<int> index(num_reduced, -1), kept;  // information column -> submatrix column
  for (int i = 0; i < num_reduced; ++i)
    if (keep[i]) {
      index[i] = static_cast<int>(kept.size());
      kept.push_back(i);
    }
  const int n_kept = static_cast<int>(kept.size());
  Eigen::MatrixXd sub(n_kept, n_kept);
  for (int a = 0; a < n_kept; ++a)
    for (int b = 0; b < n_kept; ++b) sub(a, b) = info.information(kept[a], kept[b]);
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(sub);
  if (ldlt.info() != Eigen::Success) return out;
  for (size_t c = 0; c < out.size(); ++c) {
    if (!bp.RefinesIntrinsics(static_cast<int>(c))) continue;
    const int n = static_cast<int>(bp.intrinsics[c].values.size());
    out[c] = Eigen::MatrixXd::Zero(n, n);
    if (info.column[c] < 0) continue;
    std::vector<int> entries, columns;  // free entries and their submatrix columns
    for (size_t a = 0; a < info.entries[c].size(); ++a)
      if (index[info.column[c] + a] >= 0) {
        entries.push_back(info.entries[c][a]);
        columns.push_back(index[info.column[c] + a]);
      }
    Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n_kept, static_cast<int>(entries.size()));
    for (size_t a = 0; a < entries.size(); ++a) rhs(columns[a], a) = 1.0;
    const Eigen::MatrixXd x = ldlt.solve(rhs);
    for (size_t a = 0; a < entries.size(); ++a)
      for (size_t b = 0; b < entries.size(); ++b)
        out[c](entries[a], entries[b]) = sigma_px * sigma_px * x(columns[a], b);
  }
  return out;
}

std::vector<Eigen::MatrixXd> IntrinsicsCovariance(BundleProblem* bp, double sigma_px) {
  return IntrinsicsCovariance(IntrinsicsInformationOf(bp), *bp, sigma_px);
}

std::vector<double> ObservationRms(const BundleProblem& bp, std::vector<double>* max_corner_px) {
  std::vector<double> out(bp.observations.size(), std::numeric_limits<double>::infinity());
  if (max_corner_px) max_corner_px->assign(bp.observations.size(), std::numeric_limits<double>::infinity());
  for (size_t i = 0; i < bp.observations.size(); ++i) {
    const BundleObservation& o = bp.observations[i];
    const Rigid3 cam_from_marker = RigidFromBlock(bp.cam_from_rig[o.camera].data()) *
                                   ObservedFramePose(bp, i) *
                                   RigidFromBlock(bp.object_from_marker[o.marker].data());
    const MarkerCorners3d corners = MarkerCornersInMarker(o.side);
    const CameraModel model = bp.Model(o.camera);
    double sum = 0.0, max_sq = 0.0;
    bool ok = true;
    for (int k = 0; k < 4 && ok; ++k) {
      Eigen::Vector2d pixel;
      if (!model.Project(cam_from_marker * corners[k], &pixel, nullptr)) {
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
