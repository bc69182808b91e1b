// PoseEstimator: rig_from_object of one frame from the markers seen by the mapped cameras.
#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <set>
#include <stdexcept>

#include "core/ippe.h"
#include "core/marker.h"
#include "core/math.h"
#include "core/rigid_pose.h"
#include "tracker/tracker.h"

namespace mcmt {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

}  // namespace

const char* PoseStatusName(PoseStatus status) {
  switch (status) {
    case PoseStatus::kTracking:
      return "tracking";
    case PoseStatus::kLost:
      return "lost";
    case PoseStatus::kAmbiguous:
      return "ambiguous";
  }
  return "?";
}

std::vector<MarkerObservation> ObservationsFromViews(const std::vector<detections_t>& views) {
  std::vector<const detections_t*> sorted;
  for (const auto& v : views) sorted.push_back(&v);
  std::stable_sort(sorted.begin(), sorted.end(),
                   [](const detections_t* a, const detections_t* b) { return a->camera < b->camera; });
  std::vector<MarkerObservation> out;
  for (const detections_t* v : sorted) {
    for (const auto& m : v->markers) {
      MarkerObservation o;
      o.camera = v->camera;
      o.id = m.id;
      o.utime = v->utime;
      for (int k = 0; k < 4; ++k) o.corners[k] = Eigen::Vector2d(m.corners[k][0], m.corners[k][1]);
      out.push_back(o);
    }
  }
  return out;
}

PoseEstimator::PoseEstimator(const RigMap& map, const TrackerOptions& options,
                             const MapCovariance* map_covariance)
    : map_(map), options_(options) {
  options_.Validate();
  if (map.cameras.empty()) throw std::invalid_argument("the map has no camera");
  if (map.markers.empty()) throw std::invalid_argument("the map has no marker");
  for (const auto& c : map.cameras) {
    try {
      c.model.Validate();
    } catch (const std::exception& e) {
      throw std::invalid_argument("map camera '" + c.name + "': " + e.what());
    }
    if (camera_index_.count(c.name)) throw std::invalid_argument("map camera '" + c.name + "' appears twice");
    Camera cam;
    cam.name = c.name;
    cam.model = c.model;
    cam.rig_from_cam = c.rig_from_cam;
    const Eigen::Matrix3d r = c.rig_from_cam.linear();
    cam.cam_from_rig.linear() = r.transpose();
    cam.cam_from_rig.translation() = -r.transpose() * c.rig_from_cam.translation();
    camera_index_[c.name] = static_cast<int>(cameras_.size());
    cameras_.push_back(cam);
  }
  for (const auto& m : map.markers) {
    if (!(m.size > 0))
      throw std::invalid_argument("map marker " + std::to_string(m.id) + ": size must be > 0");
    if (marker_index_.count(m.id))
      throw std::invalid_argument("map marker " + std::to_string(m.id) + " appears twice");
    Marker mk;
    mk.id = m.id;
    mk.size = m.size;
    mk.object_from_marker = m.object_from_marker;
    const double h = 0.5 * m.size;
    const Eigen::Vector3d local[4] = {{-h, h, 0}, {h, h, 0}, {h, -h, 0}, {-h, -h, 0}};
    for (int k = 0; k < 4; ++k) mk.corners_object[k] = m.object_from_marker * local[k];
    marker_index_[m.id] = static_cast<int>(markers_.size());
    markers_.push_back(mk);
  }
  if (map_covariance && map_covariance->matrix.rows() == static_cast<int>(6 * map_covariance->Entries())) {
    map_covariance_ = *map_covariance;
    for (const Camera& c : cameras_) camera_entry_.push_back(map_covariance_->CameraEntry(c.name));
    for (const Marker& m : markers_) marker_entry_.push_back(map_covariance_->MarkerEntry(m.id));
  }
}

double PoseEstimator::ObservationRms(const Obs& obs, const Rigid3& pose) const {
  const Camera& cam = cameras_[obs.camera];
  const Marker& mk = markers_[obs.marker];
  double sum = 0.0;
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector3d p_cam = *obs.cam_from_rig * (pose * mk.corners_object[k]);
    Eigen::Vector2d px;
    if (!cam.model.Project(p_cam, &px, nullptr)) return kInf;
    sum += (px - (*obs.pixels)[k]).squaredNorm();
  }
  return std::sqrt(sum / 4.0);
}

double PoseEstimator::RmsAt(const std::vector<MarkerObservation>& observations, const Rigid3& pose) const {
  double sum = 0.0;
  int n = 0;
  for (const MarkerObservation& o : observations) {
    const auto c = camera_index_.find(o.camera);
    const auto m = marker_index_.find(o.id);
    if (c == camera_index_.end() || m == marker_index_.end()) continue;
    const double rms = ObservationRms(Obs{c->second, m->second, &o.corners}, pose);
    sum += rms * rms;
    ++n;
  }
  return n ? std::sqrt(sum / n) : -1.0;
}

// The corners of the active observations for core's rigid-pose solver (world = rig, body = object).
std::vector<PosePoint> PoseEstimator::Points(const std::vector<Obs>& obs,
                                             const std::vector<char>& active) const {
  std::vector<PosePoint> points;
  for (size_t i = 0; i < obs.size(); ++i) {
    if (!active[i]) continue;
    const Camera& cam = cameras_[obs[i].camera];
    const Marker& mk = markers_[obs[i].marker];
    const std::optional<CornerWeights> weights = options_.corner_weighting.For(*obs[i].pixels);
    for (int c = 0; c < 4; ++c) {
      points.push_back({&cam.model, obs[i].cam_from_rig, mk.corners_object[c], (*obs[i].pixels)[c]});
      if (weights) points.back().sqrt_information = (*weights)[c];
    }
  }
  return points;
}

// Levenberg-Marquardt on the active observations (core's RefineRigidPose: Huber, rotation about the
// object's origin).
void PoseEstimator::Optimise(const std::vector<Obs>& obs, const std::vector<char>& active, Rigid3* pose,
                             int* iterations) const {
  RigidPoseOptions options;
  options.max_iterations = options_.max_iterations;
  options.huber_px = options_.huber_px;
  const int it = RefineRigidPose(Points(obs, active), options, pose);
  if (iterations) *iterations += it;
}

PoseEstimator::Refined PoseEstimator::RefineFrom(const std::vector<Obs>& obs, const Rigid3& start) const {
  Refined out;
  out.pose = start;
  std::vector<char> active(obs.size(), 1);
  constexpr int kRounds = 4;
  for (int round = 0; round < kRounds; ++round) {
    Optimise(obs, active, &out.pose, &out.iterations);
    std::vector<char> next(obs.size(), 0);
    int n = 0;
    for (size_t i = 0; i < obs.size(); ++i) {
      next[i] = ObservationRms(obs[i], out.pose) <= options_.outlier_px;
      n += next[i];
    }
    if (n == 0) {
      out.valid = false;
      out.inlier = next;
      return out;
    }
    if (next == active) break;
    if (round + 1 == kRounds) {
      // Out of rounds: keep the set the pose was optimised on, minus what is now gross.
      for (size_t i = 0; i < obs.size(); ++i) active[i] = active[i] && next[i];
      if (std::find(active.begin(), active.end(), 1) == active.end()) active = next;
      Optimise(obs, active, &out.pose, &out.iterations);
      break;
    }
    active = next;
  }
  out.inlier = active;
  out.num_inliers = 0;
  out.cost = 0.0;
  for (size_t i = 0; i < obs.size(); ++i) {
    if (!active[i]) continue;
    const double e = ObservationRms(obs[i], out.pose);
    out.num_inliers++;
    out.cost += 4.0 * e * e;
  }
  out.valid = out.num_inliers > 0 && std::isfinite(out.cost);
  return out;
}

bool PoseEstimator::Better(const Refined& a, const Refined& b) {
  if (a.valid != b.valid) return a.valid;
  if (a.num_inliers != b.num_inliers) return a.num_inliers > b.num_inliers;
  return a.cost < b.cost;
}

std::vector<PoseEstimator::Obs> PoseEstimator::Mapped(const std::vector<MarkerObservation>& observations,
                                                      int* unmapped) const {
  std::vector<Obs> obs;
  obs.reserve(observations.size());
  for (const auto& o : observations) {
    Obs mapped;
    if (!ToObs(o, &mapped)) {
      ++*unmapped;
      continue;
    }
    obs.push_back(mapped);
  }
  return obs;
}

bool PoseEstimator::ToObs(const MarkerObservation& observation, Obs* obs) const {
  const auto c = camera_index_.find(observation.camera);
  const auto m = marker_index_.find(observation.id);
  bool finite = true;
  for (const auto& p : observation.corners) finite = finite && p.allFinite();
  if (c == camera_index_.end() || m == marker_index_.end() || !finite) return false;
  const Rigid3* cam_from_rig =
      observation.moved ? &observation.cam_from_rig : &cameras_[c->second].cam_from_rig;
  *obs = Obs{c->second, m->second, &observation.corners, cam_from_rig};
  return true;
}

void PoseEstimator::SeenAt(const Rigid3& rig_motion, MarkerObservation* observation) const {
  const auto c = camera_index_.find(observation->camera);
  if (c == camera_index_.end()) return;
  observation->cam_from_rig = cameras_[c->second].cam_from_rig * rig_motion;
  observation->moved = true;
}

std::vector<PosePoint> PoseEstimator::PosePoints(const MarkerObservation& observation) const {
  Obs obs;
  if (!ToObs(observation, &obs)) return {};
  return Points({obs}, {1});
}

std::vector<PoseEstimator::Hypothesis> PoseEstimator::SquareHypotheses(const std::vector<Obs>& obs) const {
  std::vector<int> order(obs.size());
  std::iota(order.begin(), order.end(), 0);
  std::vector<double> area(obs.size());
  for (size_t i = 0; i < obs.size(); ++i) {
    const auto& p = *obs[i].pixels;
    double a = 0.0;
    for (int k = 0; k < 4; ++k) {
      const auto& p0 = p[k];
      const auto& p1 = p[(k + 1) % 4];
      a += p0.x() * p1.y() - p1.x() * p0.y();
    }
    area[i] = std::abs(0.5 * a);
  }
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return area[a] > area[b]; });
  if (static_cast<int>(order.size()) > options_.max_start_markers) order.resize(options_.max_start_markers);
  std::vector<Hypothesis> hypotheses;
  const double score_px = 3.0 * options_.outlier_px;
  for (int i : order) {
    const Camera& cam = cameras_[obs[i].camera];
    const Marker& mk = markers_[obs[i].marker];
    const SquarePose sp = EstimateSquarePose(cam.model, *obs[i].pixels, mk.size);
    if (!sp.ok) continue;
    for (int h = 0; h < sp.num_hypotheses; ++h) {
      Hypothesis c;
      c.pose = Normalized(Inverse(*obs[i].cam_from_rig) * sp.hypotheses[h].cam_from_marker *
                          Inverse(mk.object_from_marker));
      c.ratio = sp.ratio;
      c.inliers = 0;
      c.cost = 0.0;
      for (const Obs& o : obs) {
        const double e = ObservationRms(o, c.pose);
        if (e <= score_px) c.inliers++;
        c.cost += std::min(e * e, score_px * score_px);
      }
      hypotheses.push_back(c);
    }
  }
  std::stable_sort(hypotheses.begin(), hypotheses.end(), [](const Hypothesis& a, const Hypothesis& b) {
    if (a.inliers != b.inliers) return a.inliers > b.inliers;
    if (a.cost != b.cost) return a.cost < b.cost;
    return a.ratio > b.ratio;
  });
  return hypotheses;
}

void PoseEstimator::RefineHypotheses(const std::vector<Obs>& obs, Refined* best, bool* from_prior,
                                     int* iterations) const {
  const std::vector<Hypothesis> hypotheses = SquareHypotheses(obs);
  const int n_obs = static_cast<int>(obs.size());
  constexpr int kMaxRefined = 3;
  for (int i = 0; i < static_cast<int>(hypotheses.size()) && i < kMaxRefined; ++i) {
    Refined r = RefineFrom(obs, hypotheses[i].pose);
    *iterations += r.iterations;
    // Against the prediction's result, a hypothesis must explain more observations, or as many clearly
    // better: with equal support (e.g. one true and one false marker, or a mirror solution) continuity
    // decides.
    const bool replace =
        *from_prior ? (r.valid && (r.num_inliers > best->num_inliers ||
                                   (r.num_inliers == best->num_inliers && r.cost < 0.5 * best->cost)))
                    : Better(r, *best);
    if (replace) {
      *best = r;
      *from_prior = false;
    }
    if (best->valid && best->num_inliers == n_obs) break;
  }
}

// The map's error as the pose solve sees it. The map's cameras and markers are the solve's fixed inputs
// m; to first order the pose's step (w, v) (rotation about the rig origin, then translation) moves by
//   dx = -H^-1 sum_i J_i^T J_i E_i dm_i,   H = sum_i J_i^T J_i,
// with J_i observation i's Jacobian (8 x 6) in that step and E_i dm_i the step that moves its corners as
// its camera's and marker's errors dm_i do (both are rigid motions of the corners):
//   camera, left perturbation (dr, dt) of cam_from_rig = (R_c, t_c): the corners move in the camera frame
//     by dr x (p_cam - t_c) + dt = R_c ((R_c^T dr) x p_rig + R_c^T dt), so E = diag(R_c^T, R_c^T);
//   marker, (dr, dt) of object_from_marker (origin t_m) with rig_from_object = (R, t): the corners move
//     in the rig frame by (R dr) x (p_rig - c) + R dt, c = R t_m + t the marker's origin in the rig,
//     so E = [R 0; [c]x R  R].
// So dx = -H^-1 G dm with G's 6 columns of an entry k = sum over its observations of J_i^T J_i E_i, and
// the pose's covariance gains H^-1 G Sigma_map G^T H^-1 (the frame's noise is independent of the map's
// error). A pose seen through one camera alone moves with it (dx = E dm: the camera's whole error); one
// seen by many gets the information-weighted mean of their errors, correlations included.
Matrix6d PoseEstimator::MapShare(const std::vector<Obs>& obs, const std::vector<char>& active,
                                 const Rigid3& pose, const std::vector<Matrix6d>& blocks,
                                 const Matrix6d& h_inverse) const {
  const int entries = static_cast<int>(map_covariance_->Entries());
  Eigen::Matrix<double, 6, Eigen::Dynamic> g = Eigen::Matrix<double, 6, Eigen::Dynamic>::Zero(6, 6 * entries);
  for (size_t i = 0; i < obs.size(); ++i) {
    const int camera = camera_entry_[obs[i].camera], marker = marker_entry_[obs[i].marker];
    if (!active[i] || (camera < 0 && marker < 0)) continue;
    const Matrix6d& w = blocks[i];
    if (camera >= 0) {
      const Eigen::Matrix3d rt = obs[i].cam_from_rig->linear().transpose();
      g.middleCols<3>(6 * camera) += w.leftCols<3>() * rt;
      g.middleCols<3>(6 * camera + 3) += w.rightCols<3>() * rt;
    }
    if (marker >= 0) {
      const Eigen::Matrix3d r = pose.linear();
      const Eigen::Vector3d c = pose * markers_[obs[i].marker].object_from_marker.translation();
      Matrix6d e = Matrix6d::Zero();
      e.topLeftCorner<3, 3>() = r;
      e.bottomLeftCorner<3, 3>() = Skew(c) * r;
      e.bottomRightCorner<3, 3>() = r;
      g.middleCols<6>(6 * marker) += w * e;
    }
  }
  const Eigen::Matrix<double, 6, Eigen::Dynamic> a = h_inverse * g;
  const Matrix6d share = a * map_covariance_->matrix * a.transpose();
  return 0.5 * (share + share.transpose());
}

void PoseEstimator::Describe(const std::vector<Obs>& obs, const Refined& best, PoseSolution* sol) const {
  const int n_obs = static_cast<int>(obs.size());
  // Final covariance at the solution: sigma^2 (J^T J)^-1 over the inliers.
  Matrix6d h;
  Vector6d g;
  double rss = 0.0;
  const std::vector<char>& active = best.inlier;
  // Unweighted J^T J and residual sum of squares; rotations about the rig origin, as the message documents.
  // With the map's covariance the same sums observation by observation, each one's J^T J kept for MapShare
  // (one pass instead of two: PoseEstimator::Solve on the demo log, callgrind, 46.7 M instructions for 300
  // frames without the map's share, 69.1 M with it computed in a second pass, 62.9 M so).
  const bool map_share = map_covariance_ && options_.map_uncertainty;
  std::vector<Matrix6d> blocks(map_share ? obs.size() : 0, Matrix6d::Zero());
  if (map_share) {
    h.setZero();
    g.setZero();
    for (size_t i = 0; i < obs.size(); ++i) {
      if (!active[i]) continue;
      Vector6d gi;
      double rss_i = 0.0;
      PoseNormalEquations(Points({obs[i]}, {1}), best.pose, Eigen::Vector3d::Zero(), 0.0, &blocks[i], &gi,
                          &rss_i);
      h += blocks[i];
      g += gi;
      rss += rss_i;
    }
  } else {
    PoseNormalEquations(Points(obs, active), best.pose, Eigen::Vector3d::Zero(), 0.0, &h, &g, &rss);
  }
  const int n_inliers = static_cast<int>(std::count(active.begin(), active.end(), 1));
  const int n_residuals = 8 * n_inliers;
  // sigma^2 pools the frame's residuals (N - 6 degrees of freedom) with nu0 = noise_prior_residuals
  // pseudo-residuals at the map's noise, sigma0^2 = the inlier cameras' mean rms_px^2 / 2 (rms_px is per
  // corner, two coordinates; cameras without one add nothing): sigma^2 = (RSS + nu0 sigma0^2) / (N - 6 +
  // nu0). A single square alone has N - 6 = 2: from its residuals alone sigma^2 is as often far too small as
  // the chi-square of 2 degrees of freedom allows, and so was the pose's covariance. The demo's log fed one
  // camera at a time (demoload): single-square poses with a rotation NEES above chi-square's 99.9 %
  // bound 10.1 % -> 1.5 % (nu0 = 8, computed offline), two-square poses 2.2 % -> 0.3 %; multi-camera poses
  // barely change.
  double prior = 0.0;
  int with_rms = 0;
  for (int i = 0; i < n_obs; ++i) {
    const double rms = map_.cameras[obs[i].camera].rms_px;
    if (!active[i] || !(rms > 0)) continue;
    prior += 0.5 * rms * rms;
    ++with_rms;
  }
  const double nu0 = with_rms > 0 ? options_.noise_prior_residuals : 0.0;
  const double dof = n_residuals - 6 + nu0;
  double sigma2 = dof > 0 ? (rss + (nu0 > 0 ? nu0 * prior / with_rms : 0.0)) / dof : rss;
  sigma2 = std::max(sigma2, options_.min_sigma_px * options_.min_sigma_px);
  Eigen::SelfAdjointEigenSolver<Matrix6d> eig(h);
  Matrix6d cov_params, noise_params;  // order (rx, ry, rz, tx, ty, tz); with the map's share, without
  if (eig.info() == Eigen::Success &&
      eig.eigenvalues().minCoeff() > 1e-12 * std::max(1.0, eig.eigenvalues().maxCoeff())) {
    cov_params = sigma2 * eig.eigenvectors() * eig.eigenvalues().cwiseInverse().asDiagonal() *
                 eig.eigenvectors().transpose();
    noise_params = cov_params;
    if (map_share)
      cov_params += MapShare(obs, active, best.pose, blocks,
                             eig.eigenvectors() * eig.eigenvalues().cwiseInverse().asDiagonal() *
                                 eig.eigenvectors().transpose());
  } else {
    cov_params = Matrix6d::Identity() * 1e6;  // unobservable: say so
    noise_params = cov_params;
  }
  Eigen::Matrix<int, 6, 1> perm;
  perm << 3, 4, 5, 0, 1, 2;  // message order: x y z (translation) then rotation
  for (int a = 0; a < 6; ++a)
    for (int b = 0; b < 6; ++b) {
      sol->covariance(a, b) = cov_params(perm[a], perm[b]);
      sol->noise_covariance(a, b) = noise_params(perm[a], perm[b]);
    }

  sol->rig_from_object = best.pose;
  sol->rms_px = std::sqrt(rss / (4.0 * n_inliers));
  sol->num_observations = n_inliers;
  sol->num_rejected = n_obs - n_inliers;
  std::set<std::string> cams;
  std::set<int> ids;
  const Obs* single = nullptr;
  for (size_t i = 0; i < obs.size(); ++i) {
    if (!active[i]) continue;
    cams.insert(cameras_[obs[i].camera].name);
    ids.insert(markers_[obs[i].marker].id);
    single = &obs[i];
  }
  sol->cameras.assign(cams.begin(), cams.end());
  sol->markers.assign(ids.begin(), ids.end());
  sol->status = PoseStatus::kTracking;
  if (n_inliers == 1) {
    const SquarePose sp =
        EstimateSquarePose(cameras_[single->camera].model, *single->pixels, markers_[single->marker].size);
    sol->ippe_ratio = sp.ok ? sp.ratio : 1.0;
    if (!sp.ok || (sp.num_hypotheses >= 2 && sp.ratio < options_.ambiguity_ratio))
      sol->status = PoseStatus::kAmbiguous;
    // A sure IPPE ratio (>= ambiguity_ratio) does not vouch for the pose published: from a prediction the
    // pose may stay on the mirror branch (continuity decides in RefineHypotheses, and with every observation
    // explained the hypotheses are not even tried; until core/src/ippe.cc's flip of 2026-12-07 the IPPE
    // solutions of squares facing the camera could themselves be up to 180 deg off on exact corners). So the
    // square's ambiguity is judged again on refined poses: from the published pose's mirror (the square's
    // normal n reflected about the line of sight v, n' = 2 (n.v) v - n, turned about the square's centre)
    // and from both IPPE solutions, each refined on this square; a refined pose more than 1 deg from the
    // published one with an RMS below ambiguity_ratio x the published RMS (the IPPE ratio's test,
    // e2 / e1 < tau_e, on refined poses) makes the pose ambiguous. The pose is unchanged.
    // Measured on the demo's idle log fed one camera at a time (1500 frames): 6 of 603 single-square poses
    // flagged tracking were 14-53 deg off (cam4 frames 13-22, on the mirror since the frontal frame 8).
    if (sol->status == PoseStatus::kTracking) {
      const std::vector<Obs> one{*single};
      const Rigid3& object_from_marker = markers_[single->marker].object_from_marker;
      const Rigid3 cam_from_marker = *single->cam_from_rig * best.pose * object_from_marker;
      const Eigen::Vector3d n = cam_from_marker.linear().col(2);
      const Eigen::Vector3d v = cam_from_marker.translation().normalized();
      const Eigen::Vector3d n_mirror = 2.0 * n.dot(v) * v - n;
      Rigid3 mirror = cam_from_marker;
      mirror.linear() = Eigen::Quaterniond::FromTwoVectors(n, n_mirror).toRotationMatrix() * mirror.linear();
      std::vector<Rigid3> starts{mirror};
      for (int h = 0; h < sp.num_hypotheses; ++h) starts.push_back(sp.hypotheses[h].cam_from_marker);
      const double e_pub = std::sqrt(best.cost / 4.0);
      for (const Rigid3& c : starts) {
        const Refined r =
            RefineFrom(one, Normalized(Inverse(*single->cam_from_rig) * c * Inverse(object_from_marker)));
        if (!r.valid || RotationAngle(r.pose, best.pose) < M_PI / 180.0) continue;
        if (std::sqrt(r.cost / 4.0) < options_.ambiguity_ratio * e_pub) sol->status = PoseStatus::kAmbiguous;
      }
    }
  }
}

PoseSolution PoseEstimator::Solve(const std::vector<MarkerObservation>& observations,
                                  const Rigid3* prior) const {
  PoseSolution sol;
  const std::vector<Obs> obs = Mapped(observations, &sol.num_unmapped);
  if (obs.empty()) return sol;

  Refined best;
  int iterations = 0;
  bool from_prior = false;
  if (prior) {
    best = RefineFrom(obs, *prior);
    iterations += best.iterations;
    from_prior = best.valid;
  }
  // Lost (or the prediction left observations out): start from single-square hypotheses.
  if (!best.valid || best.num_inliers < static_cast<int>(obs.size()))
    RefineHypotheses(obs, &best, &from_prior, &iterations);
  sol.iterations = iterations;
  if (!best.valid) {
    sol.num_rejected = static_cast<int>(obs.size());
    return sol;
  }
  Describe(obs, best, &sol);
  sol.from_prior = from_prior;
  return sol;
}

}  // namespace mcmt
