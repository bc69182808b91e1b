// Calibration diagnostics from a MapResult: residuals, verdicts, pose covariance (see diagnostics.h).
#include "mapper/diagnostics.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include "core/json.h"
#include "core/lcm_util.h"
#include "core/math.h"
#include "mapper/bodies.h"
#include "mapper/bundle.h"
#include "mapper/stages.h"

namespace mcmt {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The final estimates as a bundle problem, with one bundle observation per usable input observation.
struct Rebuilt {
  BundleProblem bp;
  std::vector<int> row_of_observation;  // bundle observation -> Diagnostics::observations index
  int reference_camera = -1, reference_marker = -1;
};

// Index of the trajectory row of the frame a detection at `utime` (on the reference camera's clock)
// belongs to, -1 if none: the nearest row within half the median frame interval (at least 2 ms, the
// default sync tolerance). Frames are stamped with their first message's time, so with synchronised
// clocks that is the latest row at or before it; with clocks corrected (time offsets) a message may come
// a little before its row.
class FrameLookup {
 public:
  explicit FrameLookup(const std::vector<TrajectoryRow>& rows) {
    for (size_t i = 0; i < rows.size(); ++i) order_.emplace_back(rows[i].utime, static_cast<int>(i));
    std::sort(order_.begin(), order_.end());
    std::vector<int64_t> gaps;
    for (size_t i = 1; i < order_.size(); ++i) gaps.push_back(order_[i].first - order_[i - 1].first);
    if (!gaps.empty()) {
      std::nth_element(gaps.begin(), gaps.begin() + gaps.size() / 2, gaps.end());
      tolerance_ = std::max<int64_t>(tolerance_, gaps[gaps.size() / 2] / 2);
    }
  }
  int Find(int64_t utime) const {
    auto after = std::upper_bound(order_.begin(), order_.end(), std::make_pair(utime, INT32_MAX));
    int64_t best = tolerance_ + 1;
    int row = -1;
    if (after != order_.begin() && utime - std::prev(after)->first < best)
      best = utime - std::prev(after)->first, row = std::prev(after)->second;
    if (after != order_.end() && after->first - utime < best) row = after->second;
    return row;
  }

 private:
  std::vector<std::pair<int64_t, int>> order_;
  int64_t tolerance_ = 2000;
};

// Reasons the mapper gave, by (camera, id), with the trajectory row of the frame they name.
using RejectionIndex = std::map<std::pair<std::string, int>, std::vector<std::pair<int, std::string>>>;

// The mapper names a rejected observation's frame by the frame's utime as assembled and its seq (Frame):
// the row of that frame (FrameMembership), else the row with that seq nearest that utime (with
// synchronised clocks the row's utime is the frame's).
RejectionIndex IndexRejections(const MapResult& result, const FrameLookup& frames) {
  const std::vector<int64_t>& frame_utimes = result.membership.frame_utime_of_row;
  const bool known = frame_utimes.size() == result.trajectory.size();
  std::map<std::pair<int64_t, int64_t>, int> row_of_frame;  // (utime, seq) -> row
  for (size_t row = 0; known && row < frame_utimes.size(); ++row)
    row_of_frame[{frame_utimes[row], result.trajectory[row].seq}] = static_cast<int>(row);
  RejectionIndex index;
  for (const RejectedObservation& o : result.report.rejected_observations) {
    int row = -1;
    if (known) {
      const auto it = row_of_frame.find({o.utime, o.seq});
      row = it != row_of_frame.end() ? it->second : -1;
    } else {
      row = frames.Find(o.utime);
      if (row >= 0 && result.trajectory[row].seq != o.seq) row = -1;
    }
    if (row >= 0) index[{o.camera, o.id}].emplace_back(row, o.reason);
  }
  return index;
}

std::string FindRejection(const RejectionIndex& index, const std::string& camera, int id, int row) {
  auto it = index.find({camera, id});
  if (it == index.end()) return "";
  for (const auto& [r, reason] : it->second)
    if (r == row) return reason;
  return "";
}

// The map's and trajectory's poses as the bundle problem's blocks; name / id -> block index.
void InitialBlocks(const MapResult& result, Rebuilt* rebuilt, std::map<std::string, int>* camera_index,
                   std::map<int, int>* marker_index) {
  const RigMap& map = result.map;
  Rebuilt& r = *rebuilt;
  for (size_t c = 0; c < map.cameras.size(); ++c) {
    (*camera_index)[map.cameras[c].name] = static_cast<int>(c);
    r.bp.cam_from_rig.push_back(BlockFromRigid(Inverse(map.cameras[c].rig_from_cam)));
    r.bp.models.push_back(&map.cameras[c].model);
    r.bp.camera_fixed.push_back(map.cameras[c].name == map.reference_camera);
    if (r.bp.camera_fixed.back()) r.reference_camera = static_cast<int>(c);
  }
  for (size_t m = 0; m < map.markers.size(); ++m) {
    (*marker_index)[map.markers[m].id] = static_cast<int>(m);
    r.bp.object_from_marker.push_back(BlockFromRigid(map.markers[m].object_from_marker));
    r.bp.marker_fixed.push_back(map.markers[m].id == map.reference_marker);
    if (r.bp.marker_fixed.back()) r.reference_marker = static_cast<int>(m);
  }
  for (const TrajectoryRow& t : result.trajectory)
    r.bp.rig_from_object.push_back(BlockFromRigid(t.rig_from_object));
  // Clocks that are not the reference camera's (mapper.time_offsets): each observation sees its frame's
  // pose moved along the frame's velocity to its capture time, as in the bundle (BundleProblem): the
  // bundle's velocities, kept with the rows (a trajectory without them: differences of its rows, Rebuild).
  if (map.HasClocks() && !result.trajectory.empty()) {
    r.bp.time_offset_s.assign(map.cameras.size(), 0.0);  // the observations' times are corrected already
    for (const TrajectoryRow& t : result.trajectory) {
      r.bp.frame_time_s.push_back(1e-6 * static_cast<double>(t.utime - result.trajectory.front().utime));
      if (t.velocity) r.bp.frame_velocity.push_back(*t.velocity);
    }
    if (r.bp.frame_velocity.size() != result.trajectory.size()) r.bp.frame_velocity.clear();
  }
}

// Observations of the input, classified, and the bundle problem of the usable ones.
Rebuilt Rebuild(const MapResult& result, std::vector<ObservationResidual>* rows) {
  const RigMap& map = result.map;
  Rebuilt r;
  std::map<std::string, int> camera_index;
  std::map<int, int> marker_index;
  InitialBlocks(result, &r, &camera_index, &marker_index);
  const FrameLookup frames(result.trajectory);
  const RejectionIndex rejections = IndexRejections(result, frames);
  std::map<int, std::string> rejected_markers;
  for (const RejectedMarker& m : result.report.rejected_markers) rejected_markers[m.id] = m.reason;
  // The rows the bundle gave the detections, when known (else by time: FrameLookup).
  const std::vector<int>& rows_given = result.membership.row_of_detection;
  const bool given = rows_given.size() == result.detections.size();
  for (size_t i = 0; i < result.detections.size(); ++i) {
    const detections_t& d = result.detections[i];
    std::map<int, int> count;
    for (const marker_t& mk : d.markers) ++count[mk.id];
    const auto cam = camera_index.find(d.camera);
    // On the reference camera's clock (the trajectory's).
    const int64_t utime = cam != camera_index.end() ? map.ReferenceUtime(d.camera, d.utime) : d.utime;
    const int frame = given ? rows_given[i] : frames.Find(utime);
    for (const marker_t& mk : d.markers) {
      ObservationResidual o;
      o.utime = d.utime;
      o.seq = d.seq;
      o.camera = d.camera;
      o.id = mk.id;
      o.observed = CornersOf(mk);
      o.residual.fill(Eigen::Vector2d(kNaN, kNaN));
      o.rms_px = kNaN;
      const auto marker = marker_index.find(mk.id);
      if (cam == camera_index.end())
        o.reason = "camera not in the map";
      else if (rejected_markers.count(mk.id))
        o.reason = "marker rejected: " + rejected_markers[mk.id];
      else if (marker == marker_index.end())
        o.reason = "marker not in the map";
      else if (count[mk.id] > 1)
        o.reason = "same id twice in one image (dropped)";
      else if (frame < 0)
        o.reason = "no object pose for its frame";
      if (o.reason.empty()) {
        o.reason = FindRejection(rejections, d.camera, mk.id, frame);
        BundleObservation b;
        b.camera = cam->second;
        b.marker = marker->second;
        b.frame = frame;
        b.corners = o.observed;
        b.side = map.markers[marker->second].size;
        // Relative to the row's pose on the reference clock, unrounded (the bundle's ObservationDt).
        b.time_s = 1e-6 * (static_cast<double>(d.utime - result.trajectory[frame].utime) -
                           map.cameras[cam->second].ClockUs(d.utime, map.time_reference_utime));
        r.bp.observations.push_back(b);
        r.bp.active.push_back(o.reason.empty());
        r.row_of_observation.push_back(static_cast<int>(rows->size()));
      }
      o.inlier = o.reason.empty();
      rows->push_back(o);
    }
  }
  if (r.bp.RefinesTime() && r.bp.frame_velocity.empty()) UpdateFrameVelocities(VelocityGapS(r.bp), &r.bp);
  return r;
}

// Corner residuals with the mapper's own cost function.
void FillResiduals(const Rebuilt& r, std::vector<ObservationResidual>* rows) {
  const std::vector<double> rms = ObservationRms(r.bp);
  for (size_t k = 0; k < r.bp.observations.size(); ++k) {
    const BundleObservation& b = r.bp.observations[k];
    ObservationResidual& o = (*rows)[r.row_of_observation[k]];
    ReprojectionCost cost(r.bp.models[b.camera], b.corners, b.side);
    // The frame's pose at the observation's capture time (with clocks; else the frame's own).
    const PoseBlock seen =
        r.bp.RefinesTime() ? BlockFromRigid(ObservedFramePose(r.bp, k)) : r.bp.rig_from_object[b.frame];
    const double* params[3] = {r.bp.cam_from_rig[b.camera].data(), r.bp.object_from_marker[b.marker].data(),
                               seen.data()};
    double res[8];
    if (!cost.Evaluate(params, res, nullptr)) {
      if (o.inlier) o.reason = "behind the camera";
      o.inlier = false;
      continue;
    }
    for (int c = 0; c < 4; ++c) o.residual[c] = Eigen::Vector2d(res[2 * c], res[2 * c + 1]);
    o.rms_px = rms[k];
  }
}

void Judge(const DiagnosticsOptions& o, CameraDiagnostics* c) {
  const double share = c->observations ? double(c->rejected) / c->observations : 0.0;
  const double ratio = c->predicted_rms_px > 0 ? c->rms_px / c->predicted_rms_px : 0.0;
  std::vector<std::string> poor, fair;
  const std::string rms_text = "rms " + Fixed(c->rms_px, 2) + " px is " + Fixed(ratio, 1) + "x the " +
                               Fixed(c->predicted_rms_px, 2) + " px its noise and marker sizes predict";
  if (ratio > o.poor_rms_ratio)
    poor.push_back(rms_text);
  else if (ratio > o.fair_rms_ratio)
    fair.push_back(rms_text);
  const std::string share_text = Fixed(100 * share, 1) + "% of its observations rejected";
  if (share > o.poor_rejected)
    poor.push_back(share_text);
  else if (share > o.fair_rejected)
    fair.push_back(share_text);
  const std::string cover_text = "markers seen in only " + Fixed(100 * c->coverage, 0) +
                                 "% of the image (move the object into the empty parts)";
  if (c->coverage < o.poor_coverage)
    poor.push_back(cover_text);
  else if (c->coverage < o.fair_coverage)
    fair.push_back(cover_text);
  const std::string obs_text = "only " + std::to_string(c->inliers) + " observations kept";
  if (c->inliers < o.poor_observations)
    poor.push_back(obs_text);
  else if (c->inliers < o.fair_observations)
    fair.push_back(obs_text);
  auto join = [](const std::vector<std::string>& v) {
    std::string s;
    for (const std::string& x : v) s += (s.empty() ? "" : "; ") + x;
    return s;
  };
  if (!poor.empty()) {
    c->verdict = "poor";
    c->reason = join(poor) + (fair.empty() ? "" : "; also " + join(fair));
  } else if (!fair.empty()) {
    c->verdict = "fair";
    c->reason = join(fair);
  } else {
    c->verdict = "good";
    c->reason = "rms " + Fixed(c->rms_px, 2) + " px within " + Fixed(o.fair_rms_ratio, 1) + "x of the " +
                Fixed(c->predicted_rms_px, 2) + " px predicted, " + Fixed(100 * c->coverage, 0) +
                "% of the image covered, " + std::to_string(c->inliers) + " observations, " +
                Fixed(100 * share, 1) + "% rejected";
  }
}

void CameraStatistics(const MapResult& result, const std::vector<ObservationResidual>& rows, Diagnostics* d) {
  const DiagnosticsOptions& o = d->options;
  for (const MapCamera& mc : result.map.cameras) {
    CameraDiagnostics c;
    c.name = mc.name;
    c.reference = mc.name == result.map.reference_camera;
    const int cells = std::max(1, o.coverage_cells);
    std::vector<char> covered(cells * cells, 0);
    std::vector<double> sides;
    double sq = 0;
    for (const ObservationResidual& r : rows) {
      if (r.camera != mc.name) continue;
      ++c.observations;
      if (!r.inlier) continue;
      ++c.inliers;
      sq += r.rms_px * r.rms_px;
      for (int k = 0; k < 4; ++k) {
        const int cx = std::clamp(int(r.observed[k].x() * cells / mc.model.width), 0, cells - 1);
        const int cy = std::clamp(int(r.observed[k].y() * cells / mc.model.height), 0, cells - 1);
        covered[cy * cells + cx] = 1;
      }
      sides.push_back(MeanSideLength(r.observed));
    }
    c.rejected = c.observations - c.inliers;
    c.rms_px = c.inliers ? std::sqrt(sq / c.inliers) : 0.0;
    c.median_side_px = Median(sides);
    const double print = o.print_tolerance * c.median_side_px / 2;
    c.predicted_rms_px = std::sqrt(2 * o.corner_noise_px * o.corner_noise_px + print * print);
    c.coverage = double(std::count(covered.begin(), covered.end(), 1)) / covered.size();
    Judge(o, &c);
    d->cameras.push_back(c);
  }
}

// Gauss-Newton information of the camera and marker poses with every frame pose eliminated (Schur
// complement: frames are independent given cameras and markers), from the inlier observations at the
// solution, without robust loss. Parameters are the 6-dof left perturbations of the mapper's blocks.
struct ReducedSystem {
  std::vector<int> camera_slot, marker_slot;  // -1: fixed or unobserved
  Eigen::MatrixXd information;                // 6 slots x 6 slots
  int residuals = 0, parameters = 0;
  double sum_sq = 0.0;
  std::vector<std::vector<size_t>> frames;  // per frame, its inlier observations
};

using Block6 = Eigen::Matrix<double, 6, 6>;
using Jacobian8x6 = Eigen::Matrix<double, 8, 6>;

// One inlier observation's residuals and Jacobians (camera, marker, frame) at the solution, in the
// left perturbations of their blocks; false when it cannot be evaluated (behind the camera).
struct ObservationTerms {
  Eigen::Matrix<double, 8, 1> res;
  Jacobian8x6 j[3];
};

bool EvaluateObservation(const BundleProblem& bp, size_t k, ObservationTerms* o) {
  const BundleObservation& b = bp.observations[k];
  ReprojectionCost cost(bp.models[b.camera], b.corners, b.side);
  const double* params[3] = {bp.cam_from_rig[b.camera].data(), bp.object_from_marker[b.marker].data(),
                             bp.rig_from_object[b.frame].data()};
  Eigen::Matrix<double, 8, 7, Eigen::RowMajor> jac[3];
  double* jacs[3] = {jac[0].data(), jac[1].data(), jac[2].data()};
  if (!cost.Evaluate(params, o->res.data(), jacs)) return false;
  for (int a = 0; a < 3; ++a) o->j[a] = jac[a].leftCols<6>();
  return true;
}

// One frame's share: its observations' Jacobians (slots of camera and marker, J_slot, J_frame).
struct FrameTerms {
  Block6 c = Block6::Zero();
  std::map<int, Block6> b;  // slot -> J_slot^T J_frame
};

void EliminateFrame(const FrameTerms& f, Eigen::MatrixXd* h) {
  const Eigen::LDLT<Block6> c(f.c);
  if (c.info() != Eigen::Success) return;
  for (const auto& [i, bi] : f.b) {
    const Block6 ki = c.solve(bi.transpose());
    for (const auto& [j, bj] : f.b) h->block<6, 6>(6 * j, 6 * i) -= bj * ki;  // S_ji -= B_j C^-1 B_i^T
  }
}

ReducedSystem BuildReducedSystem(const Rebuilt& r, const std::vector<ObservationResidual>& rows) {
  const BundleProblem& bp = r.bp;
  ReducedSystem sys;
  sys.camera_slot.assign(bp.cam_from_rig.size(), -1);
  sys.marker_slot.assign(bp.object_from_marker.size(), -1);
  std::vector<std::vector<size_t>>& by_frame = sys.frames;
  by_frame.resize(bp.rig_from_object.size());
  int slots = 0;
  for (size_t k = 0; k < bp.observations.size(); ++k) {
    if (!rows[r.row_of_observation[k]].inlier) continue;
    const BundleObservation& b = bp.observations[k];
    if (!bp.camera_fixed[b.camera] && sys.camera_slot[b.camera] < 0) sys.camera_slot[b.camera] = slots++;
    if (!bp.marker_fixed[b.marker] && sys.marker_slot[b.marker] < 0) sys.marker_slot[b.marker] = slots++;
    by_frame[b.frame].push_back(k);
  }
  sys.information = Eigen::MatrixXd::Zero(6 * slots, 6 * slots);
  for (const std::vector<size_t>& obs : by_frame) {
    if (obs.empty()) continue;
    FrameTerms f;
    for (size_t k : obs) {
      const BundleObservation& b = bp.observations[k];
      ObservationTerms o;
      if (!EvaluateObservation(bp, k, &o)) continue;
      f.c += o.j[2].transpose() * o.j[2];
      const int slot[2] = {sys.camera_slot[b.camera], sys.marker_slot[b.marker]};
      for (int a = 0; a < 2; ++a) {
        if (slot[a] < 0) continue;
        auto it = f.b.emplace(slot[a], Block6::Zero()).first;
        it->second += o.j[a].transpose() * o.j[2];
        for (int e = 0; e < 2; ++e)
          if (slot[e] >= 0)
            sys.information.block<6, 6>(6 * slot[a], 6 * slot[e]) += o.j[a].transpose() * o.j[e];
      }
      sys.residuals += 8;
      sys.sum_sq += o.res.squaredNorm();
    }
    sys.parameters += 6;
    EliminateFrame(f, &sys.information);
  }
  sys.parameters += 6 * slots;
  return sys;
}

// Camera centre c = -R^T t of cam_from_rig (R, t) under the left perturbation: dc = -R^T ([t]x dr + dt).
void FillPoseSigmas(const PoseBlock& cam_from_rig_block, CameraDiagnostics* cam) {
  const Rigid3 cam_from_rig = RigidFromBlock(cam_from_rig_block.data());
  const Eigen::Matrix3d rt = cam_from_rig.linear().transpose();
  const Eigen::Vector3d t = cam_from_rig.translation();
  Eigen::Matrix<double, 3, 6> j;
  j << -rt * Skew(t), -rt;
  const Eigen::Matrix3d cov_c = j * cam->covariance * j.transpose();
  cam->sigma_position_mm = 1000.0 * cov_c.diagonal().cwiseMax(0).cwiseSqrt();
  cam->sigma_rotation_deg =
      (180.0 / M_PI) * cam->covariance.topLeftCorner<3, 3>().diagonal().cwiseMax(0).cwiseSqrt();
  cam->has_covariance = true;
}

// The cameras and markers a covariance is written for (Diagnostics::map_covariance): every camera with a
// slot, then every marker with a slot when they are at most kMaxMapCovarianceEntries together. Their
// slots, in that order.
std::vector<int> OutputEntries(const RigMap& map, const ReducedSystem& sys, MapCovariance* out) {
  std::vector<int> slots;
  for (size_t c = 0; c < map.cameras.size(); ++c)
    if (sys.camera_slot[c] >= 0) {
      out->cameras.push_back(map.cameras[c].name);
      slots.push_back(sys.camera_slot[c]);
    }
  int markers = 0;
  for (size_t m = 0; m < map.markers.size(); ++m) markers += sys.marker_slot[m] >= 0;
  if (static_cast<int>(out->cameras.size()) + markers <= kMaxMapCovarianceEntries)
    for (size_t m = 0; m < map.markers.size(); ++m)
      if (sys.marker_slot[m] >= 0) {
        out->markers.push_back(map.markers[m].id);
        slots.push_back(sys.marker_slot[m]);
      }
  return slots;
}

// Correlated corner errors: a bias per track (one camera seeing one marker).
//
// The covariance s^2 S^-1 assumes every corner coordinate's error independent. On rendered images it is
// not: the detector's error of a marker's corner depends on how that camera sees that marker (its size,
// tilt and pixel phase, which change slowly along the session), so part of it stays the same in every
// frame of a track and does not average out over the frames. Measured on scripts/demo's session (true
// corner errors against ground truth, 2179 observations, 20 tracks): the tracks' mean errors hold 4.1 % of
// the error variance where independent errors would put 0.9 % there (4.5 times); the demo map's camera
// centres were 4.80 variances off per axis (1 for a right covariance), 0.76 with independent noise of
// the same size. The same errors shuffled within their tracks keep that bias and stay off (19.8), and
// removing each observation's common outward offset (the marker scale) does not help (7.5): the bias per
// track is what the covariance misses, not the frame-to-frame correlation nor the scale alone.
//
// Model (a one-way random effect, the estimate unchanged): the residual of coordinate i of observation k
// in track t is r_ki = b_ti + e_ki, b_ti ~ N(0, sb2) shared by the track's frames, e_ki ~ N(0, s2 - sb2)
// independent. The least-squares estimate ignores the correlation, so its covariance is the sandwich
//   cov = S^-1 (J~^T V J~) S^-1 = (s2 - sb2) S^-1 + sb2 S^-1 (sum_t G_t^T G_t) S^-1,
// S the reduced information (frames eliminated), J~_k = J_slots,k - J_frame,k C_f^-1 B_f^T observation
// k's Jacobian with its frame's pose re-solved (so sum_k J~_k^T J~_k = S), G_t = sum_{k in t} J~_k. Only the
// written entries are needed: W_t = G_t S^-1[:, out] (8 x 6 entries) per track, cov[out, out] = (s2 - sb2)
// S^-1[out, out] + sb2 sum_t W_t^T W_t. sb2 by the method of moments from the tracks' mean residuals
// (E[n_t rbar_ti^2] = n_t sb2 + sw2, sw2 the pooled within-track variance):
//   sb2 = max(0, sum_t (n_t |rbar_t|^2 - 8 sw2) / (8 N)).
// It sees only the part of the bias the map did not absorb (on the demo 0.019 px from the residuals,
// 0.024 px from the true errors), so it errs small. With sb2 = 0 the covariance is s2 S^-1: on independent
// noise the residuals' track means are mostly smaller than that expectation, and then the covariance is
// the one without this term, bit for bit.
// Measured: the demo's camera centres 4.80 -> 2.47 variances per axis, its poses beyond 3 sigma in the
// map's frames 78.7 -> 0.0 %; what is left is a bias all markers share (the map's scale, which the
// residuals cannot see: bench/results/2026-12-07-corrcov.md).
struct TrackBias {
  double sb2 = 0.0;
  Eigen::MatrixXd sum_wtw;  // sum_t W_t^T W_t over the output entries
};

TrackBias TrackBiasTerm(const Rebuilt& r, const ReducedSystem& sys, const Eigen::MatrixXd& cov,
                        const std::vector<int>& out) {
  const BundleProblem& bp = r.bp;
  const int n = 6 * static_cast<int>(out.size());
  Eigen::MatrixXd p(cov.rows(), n);  // S^-1[:, out]
  for (size_t e = 0; e < out.size(); ++e) p.middleCols<6>(6 * e) = cov.middleCols<6>(6 * out[e]);
  struct Track {
    int n = 0;
    Eigen::Matrix<double, 8, 1> sum = Eigen::Matrix<double, 8, 1>::Zero();
    Eigen::MatrixXd w;
  };
  std::map<std::pair<int, int>, Track> tracks;
  double sum_sq = 0.0;
  int observations = 0;
  for (const std::vector<size_t>& obs : sys.frames) {
    std::vector<ObservationTerms> terms(obs.size());
    std::vector<char> ok(obs.size(), 0);
    Block6 c = Block6::Zero();
    Eigen::MatrixXd bp_out = Eigen::MatrixXd::Zero(6, n);  // B_f^T S^-1[:, out]
    for (size_t i = 0; i < obs.size(); ++i) {
      const BundleObservation& b = bp.observations[obs[i]];
      if (!(ok[i] = EvaluateObservation(bp, obs[i], &terms[i]))) continue;
      c += terms[i].j[2].transpose() * terms[i].j[2];
      const int slot[2] = {sys.camera_slot[b.camera], sys.marker_slot[b.marker]};
      for (int a = 0; a < 2; ++a)
        if (slot[a] >= 0) bp_out += terms[i].j[2].transpose() * terms[i].j[a] * p.middleRows<6>(6 * slot[a]);
    }
    const Eigen::LDLT<Block6> ldlt(c);
    if (ldlt.info() != Eigen::Success) continue;
    const Eigen::MatrixXd f = ldlt.solve(bp_out);  // C_f^-1 B_f^T S^-1[:, out]
    for (size_t i = 0; i < obs.size(); ++i) {
      if (!ok[i]) continue;
      const BundleObservation& b = bp.observations[obs[i]];
      Track& t = tracks[{b.camera, b.marker}];
      if (t.w.size() == 0) t.w = Eigen::MatrixXd::Zero(8, n);
      t.w -= terms[i].j[2] * f;
      const int slot[2] = {sys.camera_slot[b.camera], sys.marker_slot[b.marker]};
      for (int a = 0; a < 2; ++a)
        if (slot[a] >= 0) t.w += terms[i].j[a] * p.middleRows<6>(6 * slot[a]);
      t.sum += terms[i].res;
      ++t.n;
      sum_sq += terms[i].res.squaredNorm();
      ++observations;
    }
  }
  TrackBias out_term;
  out_term.sum_wtw = Eigen::MatrixXd::Zero(n, n);
  double between = 0.0;  // sum_t n_t |rbar_t|^2
  for (const auto& [key, t] : tracks) {
    between += t.sum.squaredNorm() / t.n;
    out_term.sum_wtw.noalias() += t.w.transpose() * t.w;
  }
  const int dof = 8 * (observations - static_cast<int>(tracks.size()));
  if (dof <= 0) return out_term;
  const double sw2 = (sum_sq - between) / dof;
  out_term.sb2 = std::max(0.0, (between - 8 * sw2 * tracks.size()) / (8.0 * observations));
  return out_term;
}

// The printed marker size's error: a common scale (mapper.marker_size_sigma_percent).
//
// Every marker of a print shares its scale error (printers scale pages by 0.1-1 %, a ruler reads a 4 cm
// marker to a few 0.1 mm), and the detector's shared outward corner bias acts the same way (0.01-0.4 % on
// rendered images, BENCHMARKS.md). All marker sizes x k = 1 + e explain the same images with every
// distance in the map x k, so the map absorbs e whole and the residuals (and s2 S^-1, TrackBiasTerm)
// cannot see it. Only a stated prior holds it. Measured (mcmt-sim's rendered 1.3 m session, seed 7, whose
// map is 0.124 % small; camera centres' squared error per variance per axis, 1 for a right covariance, and
// tracked positions beyond 3 sigma in the map's frames; bench/results/2026-12-07-printscale.md): sigma 0
// 9.73 and 86.0 %, 0.05 % 3.98 and 0.0 %, 0.1 % 1.50 and 0.0 %, 0.15 % 0.74; scripts/demo's (-0.023 %)
// 2.47 / 0.88 / 0.33 at 0 / 0.05 / 0.1 %.
//
// The reference camera and the reference marker are held fixed (their poses define the rig and object
// frames), so the similarity acts about their origins: a camera centre c = -R^T t of cam_from_rig (R, t)
// goes to c_ref + k (c - c_ref), c_ref the reference camera's centre (0 unless the rig frame is a static
// body's, rig_frame), rotations unchanged; t = -R c gives dt = -R e (c - c_ref) = e (t + R c_ref). A marker
// of object_from_marker (R_m, t_m) goes to t_ref + k (t_m - t_ref) with its corners' k-times size, so dt_m =
// e (t_m - t_ref), t_ref the reference marker's. dr = 0 everywhere. With e ~ N(0, sigma^2) the written
// entries' covariance gains sigma^2 v v^T, v the stacked (dr, dt) / e of this function, correlated across
// every camera and marker; a camera centre's covariance gains sigma^2 (c - c_ref)(c - c_ref)^T (its sigma
// along c - c_ref grows to sqrt(sigma_before^2 + sigma^2 |c - c_ref|^2), across unchanged), the reference's
// nothing. The estimate is not changed.
Eigen::VectorXd MarkerSizeScaleDirection(const RigMap& map, const Rebuilt& r, const ReducedSystem& sys,
                                         bool with_markers) {
  const BundleProblem& bp = r.bp;
  Eigen::Vector3d c_ref = Eigen::Vector3d::Zero(), t_ref = Eigen::Vector3d::Zero();
  if (r.reference_camera >= 0) {
    const Rigid3 ref = RigidFromBlock(bp.cam_from_rig[r.reference_camera].data());
    c_ref = -ref.linear().transpose() * ref.translation();
  }
  if (r.reference_marker >= 0)
    t_ref = RigidFromBlock(bp.object_from_marker[r.reference_marker].data()).translation();
  std::vector<Eigen::Vector3d> dt;
  for (size_t c = 0; c < map.cameras.size(); ++c)
    if (sys.camera_slot[c] >= 0) {
      const Rigid3 cam_from_rig = RigidFromBlock(bp.cam_from_rig[c].data());
      dt.push_back(cam_from_rig.translation() + cam_from_rig.linear() * c_ref);
    }
  for (size_t m = 0; with_markers && m < map.markers.size(); ++m)
    if (sys.marker_slot[m] >= 0)
      dt.push_back(RigidFromBlock(bp.object_from_marker[m].data()).translation() - t_ref);
  Eigen::VectorXd v = Eigen::VectorXd::Zero(6 * dt.size());
  for (size_t e = 0; e < dt.size(); ++e) v.segment<3>(6 * e + 3) = dt[e];
  return v;
}

// Marginal covariance of every non-reference camera pose and the joint covariance of the cameras and
// markers: s2 S^-1 with the tracks' bias (TrackBiasTerm) and the marker size's scale
// (MarkerSizeScaleDirection) added.
void PoseCovariance(const RigMap& map, const Rebuilt& r, Diagnostics* d) {
  const ReducedSystem sys = BuildReducedSystem(r, d->observations);
  d->residual_sigma_px =
      sys.residuals > sys.parameters ? std::sqrt(sys.sum_sq / (sys.residuals - sys.parameters)) : 0.0;
  const Eigen::LDLT<Eigen::MatrixXd> h(sys.information);
  const bool ok = sys.information.size() > 0 && h.info() == Eigen::Success && h.isPositive() &&
                  h.vectorD().minCoeff() > 1e-12 * h.vectorD().maxCoeff();
  MapCovariance joint;
  const std::vector<int> out = OutputEntries(map, sys, &joint);
  if (ok) {
    const Eigen::MatrixXd cov =
        h.solve(Eigen::MatrixXd::Identity(sys.information.rows(), sys.information.cols()));
    const TrackBias bias = TrackBiasTerm(r, sys, cov, out);
    const double s2 = d->residual_sigma_px * d->residual_sigma_px;
    d->track_bias_sigma_px = std::sqrt(bias.sb2);
    const double se2 = std::max(0.0, s2 - bias.sb2);
    joint.matrix.resize(6 * out.size(), 6 * out.size());
    for (size_t a = 0; a < out.size(); ++a)
      for (size_t b = 0; b < out.size(); ++b)
        joint.matrix.block<6, 6>(6 * a, 6 * b) = se2 * cov.block<6, 6>(6 * out[a], 6 * out[b]);
    if (bias.sb2 > 0) joint.matrix += bias.sb2 * bias.sum_wtw;
    const double k2 = d->options.marker_size_sigma * d->options.marker_size_sigma;
    if (k2 > 0) {
      const Eigen::VectorXd v = MarkerSizeScaleDirection(map, r, sys, !joint.markers.empty());
      joint.matrix.noalias() += k2 * v * v.transpose();
    }
    joint.matrix = 0.5 * (joint.matrix + joint.matrix.transpose()).eval();
  }
  for (size_t c = 0; c < d->cameras.size(); ++c) {
    CameraDiagnostics& cam = d->cameras[c];
    const int slot = sys.camera_slot[c];
    if (cam.reference) {
      cam.covariance_note = "reference camera (defines the rig frame)";
    } else if (slot < 0) {
      cam.covariance_note = "no inlier observation";
    } else if (!ok) {
      cam.covariance_note = "the poses are not determined by the observations (rank-deficient)";
    } else {
      const int e = joint.CameraEntry(cam.name);
      cam.covariance = joint.matrix.block<6, 6>(6 * e, 6 * e);
      FillPoseSigmas(r.bp.cam_from_rig[c], &cam);
    }
  }
  if (ok) d->map_covariance = std::move(joint);
}

}  // namespace

Diagnostics ComputeDiagnostics(const MapResult& result, const DiagnosticsOptions& options) {
  Diagnostics d;
  d.options = options;
  Rebuilt r = Rebuild(result, &d.observations);
  FillResiduals(r, &d.observations);
  CameraStatistics(result, d.observations, &d);
  if (options.covariance) PoseCovariance(result.map, r, &d);
  return d;
}

Diagnostics ComputeObjectDiagnostics(const MapResult& result, const DiagnosticsOptions& options) {
  return result.map.objects.empty() ? ComputeDiagnostics(result, options)
                                    : ComputeDiagnostics(DiagnosticsView(result), options);
}

std::string UnsupportedMapText(const Diagnostics& d, double rms_ratio, double side_fraction) {
  if (rms_ratio <= 0) return "";
  std::string cameras;
  for (const CameraDiagnostics& c : d.cameras) {
    if (c.inliers < d.options.poor_observations) continue;
    if (!(c.rms_px > rms_ratio * c.predicted_rms_px && c.rms_px > side_fraction * c.median_side_px))
      return "";  // this camera supports the map
    cameras += (cameras.empty() ? "" : ", ") + c.name + " " + Fixed(c.rms_px, 2) + " px (predicted " +
               Fixed(c.predicted_rms_px, 2) + " px, markers " + Fixed(c.median_side_px, 0) + " px)";
  }
  if (cameras.empty()) return "";
  return "no camera supports the map: every camera's reprojection RMS is over " + Fixed(rms_ratio, 1) +
         "x the RMS its corner noise predicts and over " + Fixed(100 * side_fraction, 1) +
         "% of its markers' median side: " + cameras;
}

const char kResidualsHeader[] = "utime,seq,camera,id,corner,x,y,dx,dy,status,reason";

std::string ResidualsCsv(const Diagnostics& d) {
  std::ostringstream o;
  o << kResidualsHeader << "\n" << std::setprecision(10);
  for (const ObservationResidual& r : d.observations) {
    std::string reason = r.reason;
    std::replace(reason.begin(), reason.end(), ',', ';');
    for (int k = 0; k < 4; ++k) {
      o << r.utime << ',' << r.seq << ',' << r.camera << ',' << r.id << ',' << k << ',' << r.observed[k].x()
        << ',' << r.observed[k].y() << ',';
      if (std::isfinite(r.residual[k].x()))
        o << r.residual[k].x() << ',' << r.residual[k].y();
      else
        o << ',';
      o << ',' << (r.inlier ? "inlier" : "rejected") << ',' << reason << "\n";
    }
  }
  return o.str();
}

std::string DiagnosticsJson(const Diagnostics& d) {
  const DiagnosticsOptions& o = d.options;
  std::ostringstream j;
  j << "{\n    \"corner_noise_px\": " << JsonNumber(d.options.corner_noise_px)
    << ",\n    \"print_tolerance\": " << JsonNumber(d.options.print_tolerance)
    << ",\n    \"residual_sigma_px\": " << JsonNumber(d.residual_sigma_px)
    << ",\n    \"track_bias_sigma_px\": " << JsonNumber(d.track_bias_sigma_px)
    << ",\n    \"marker_size_sigma_percent\": " << JsonNumber(100.0 * d.options.marker_size_sigma)
    << ",\n    \"rules\": {\"fair_rms_ratio\": " << JsonNumber(o.fair_rms_ratio)
    << ", \"poor_rms_ratio\": " << JsonNumber(o.poor_rms_ratio)
    << ", \"fair_rejected\": " << JsonNumber(o.fair_rejected)
    << ", \"poor_rejected\": " << JsonNumber(o.poor_rejected)
    << ", \"fair_coverage\": " << JsonNumber(o.fair_coverage)
    << ", \"poor_coverage\": " << JsonNumber(o.poor_coverage)
    << ", \"fair_observations\": " << o.fair_observations
    << ", \"poor_observations\": " << o.poor_observations << ", \"coverage_cells\": " << o.coverage_cells
    << "},\n    \"cameras\": [\n";
  for (size_t i = 0; i < d.cameras.size(); ++i) {
    const CameraDiagnostics& c = d.cameras[i];
    j << "      {\"name\": " << JsonString(c.name) << ", \"verdict\": " << JsonString(c.verdict)
      << ", \"reason\": " << JsonString(c.reason) << ", \"observations\": " << c.observations
      << ", \"inliers\": " << c.inliers << ", \"rejected\": " << c.rejected
      << ", \"rms_px\": " << JsonNumber(c.rms_px)
      << ", \"predicted_rms_px\": " << JsonNumber(c.predicted_rms_px)
      << ", \"median_side_px\": " << JsonNumber(c.median_side_px)
      << ", \"coverage\": " << JsonNumber(c.coverage)
      << ", \"reference\": " << (c.reference ? "true" : "false");
    if (c.has_covariance) {
      j << ", \"sigma_position_mm\": [" << JsonNumber(c.sigma_position_mm.x()) << ", "
        << JsonNumber(c.sigma_position_mm.y()) << ", " << JsonNumber(c.sigma_position_mm.z())
        << "], \"sigma_rotation_deg\": [" << JsonNumber(c.sigma_rotation_deg.x()) << ", "
        << JsonNumber(c.sigma_rotation_deg.y()) << ", " << JsonNumber(c.sigma_rotation_deg.z())
        << "], \"covariance\": [";
      for (int k = 0; k < 36; ++k) j << (k ? ", " : "") << JsonNumber(c.covariance(k / 6, k % 6));
      j << "]";
    } else {
      j << ", \"covariance_note\": " << JsonString(c.covariance_note);
    }
    j << "}" << (i + 1 < d.cameras.size() ? "," : "") << "\n";
  }
  j << "    ]\n  }";
  return j.str();
}

std::string VerdictLines(const Diagnostics& d) {
  std::ostringstream o;
  for (const CameraDiagnostics& c : d.cameras) {
    o << "camera " << c.name << ": " << c.verdict << " (" << c.reason << ")";
    if (c.has_covariance)
      o << "; pose 1-sigma " << Fixed(c.sigma_position_mm.norm(), 2) << " mm, "
        << Fixed(c.sigma_rotation_deg.norm(), 3) << " deg";
    o << "\n";
  }
  return o.str();
}

std::string WithDiagnostics(const std::string& report_json, const Diagnostics& d) {
  const size_t end = report_json.find_last_of('}');
  if (end == std::string::npos) return report_json;
  size_t body_end = report_json.find_last_not_of(" \n", end - 1);
  return report_json.substr(0, body_end + 1) + ",\n  \"diagnostics\": " + DiagnosticsJson(d) + "\n}\n";
}

}  // namespace mcmt
