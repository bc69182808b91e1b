// Stages: the bundle problem from the initial poses, refinement with outlier rejection and re-solves
// (the paper's step 5), cameras that do not fit, and the map at the bundle's parameters.
#include <array>
#include <cmath>
#include <iomanip>
#include <limits>
#include <numeric>
#include <set>
#include <sstream>

#include "core/math.h"
#include "mapper/intrinsics.h"
#include "mapper/stages.h"

namespace mcmt {

void RejectObservation(const MapperBundle& bundle, const Observations& observations,
                       const ObservationNames& names, size_t k, double rms_px, const std::string& reason,
                       BundleProblem* problem, MapReport* report) {
  problem->active[k] = 0;
  const Observation& ob = observations.obs[bundle.observation[k]];
  RejectedObservation r;
  r.utime = (*names.frames)[ob.frame].utime;
  r.seq = (*names.frames)[ob.frame].seq;
  r.camera = (*names.camera_names)[ob.camera];
  r.id = (*names.marker_ids)[ob.marker];
  r.rms_px = rms_px;
  r.reason = reason;
  report->rejected_observations.push_back(r);
}

MapperBundle MakeBundleProblem(const Observations& observations, const ObservationNames& names,
                               const MarkerLayout& layout, const CameraPlacement& cameras,
                               const ObjectPoses& poses, const std::vector<CameraModel>& models,
                               MapReport* report) {
  const int num_cameras = static_cast<int>(cameras.rig_from_cam.size());
  const int num_markers = static_cast<int>(layout.object_from_marker.size());
  const int num_frames = static_cast<int>(poses.rig_from_object.size());
  MapperBundle bundle;
  BundleProblem& bp = bundle.problem;
  bp.models.resize(num_cameras);
  for (int c = 0; c < num_cameras; ++c) {
    bp.cam_from_rig.push_back(BlockFromRigid(Inverse(cameras.rig_from_cam[c])));
    bp.models[c] = &models[c];
  }
  bp.camera_fixed.assign(num_cameras, 0);
  bp.camera_fixed[cameras.reference] = 1;
  for (int m = 0; m < num_markers; ++m)
    bp.object_from_marker.push_back(BlockFromRigid(layout.object_from_marker[m]));
  bp.marker_fixed.assign(num_markers, 0);
  bp.marker_fixed[layout.reference] = 1;
  const std::vector<Frame>& frames = *names.frames;
  for (int f = 0; f < num_frames; ++f) {
    bp.rig_from_object.push_back(BlockFromRigid(poses.rig_from_object[f]));
    bp.frame_time_s.push_back(1e-6 * static_cast<double>(frames[f].utime - frames[0].utime));
  }
  // Clock drifts are reckoned from the session's middle (the offsets hold there: the least correlated).
  if (!frames.empty())
    bp.time_reference_utime = frames.front().utime + (frames.back().utime - frames.front().utime) / 2;
  const std::vector<Observation>& obs = observations.obs;
  // Reserved at their final size: grown by doubling, the vectors kept up to 2x their 116 bytes per
  // observation through the bundle adjustment, the mapper's peak (8-camera board, 3000 frames: 14.7 MB
  // for 92800 observations instead of 10.4).
  size_t num_usable = 0;
  for (size_t i = 0; i < obs.size(); ++i) num_usable += poses.usable[i] && poses.has_pose[obs[i].frame];
  bp.observations.reserve(num_usable);
  bundle.observation.reserve(num_usable);
  for (size_t i = 0; i < obs.size(); ++i) {
    if (!poses.usable[i] || !poses.has_pose[obs[i].frame]) continue;
    const double time_s = 1e-6 * static_cast<double>(obs[i].utime - frames[obs[i].frame].utime);
    const double clock_s = 1e-6 * static_cast<double>(obs[i].utime - bp.time_reference_utime);
    bp.observations.push_back(
        {obs[i].camera, obs[i].marker, obs[i].frame, obs[i].corners, obs[i].side, time_s, clock_s});
    bundle.observation.push_back(static_cast<int>(i));
  }
  bp.active.assign(bp.observations.size(), 1);
  const std::vector<double> rms = ObservationRms(bp);
  for (size_t k = 0; k < rms.size(); ++k)
    if (!std::isfinite(rms[k]))
      RejectObservation(bundle, observations, names, k, rms[k], "behind the camera at initialisation", &bp,
                        report);
  bundle.marker_rejected.assign(num_markers, 0);
  for (const RejectedMarker& r : report->rejected_markers)
    bundle.marker_rejected[observations.marker_index.at(r.id)] = 1;
  return bundle;
}

BundleSettings BundleSettingsFor(const MapperOptions& o, int threads) {
  BundleSettings settings;
  settings.huber_px = o.huber_px;
  settings.view_weight_power = o.view_weight_power;
  settings.corner_weighting = o.corner_weighting;
  settings.max_iterations = o.max_iterations;
  settings.paper_stop = o.paper_stop;
  settings.paper_stop_px = o.paper_stop_px;
  settings.threads = threads;
  settings.linear_solver = o.linear_solver;
  return settings;
}

namespace {

// RMS corner error over the active observations.
double CurrentRms(const BundleProblem& bp) {
  const std::vector<double> rms = ObservationRms(bp);
  double sum = 0;
  int n = 0;
  for (size_t k = 0; k < rms.size(); ++k)
    if (bp.active[k] && std::isfinite(rms[k])) {
      sum += rms[k] * rms[k];
      ++n;
    }
  return n ? std::sqrt(sum / n) : 0.0;
}

// A re-solve whose updated velocities move the poses the observations are seen at by less than this
// (metres, at the object's points) is not made: it would start where the last solve stopped.
// 10 um: 0.01 px seen by a camera with a 1000 px focal length 1 m away, a twentieth of the sim sessions'
// corner noise (bench_selfcal's everything row: 2.8 um after the agreement test's re-solve; the re-solve,
// 1 iteration, changed the RMS by 2e-8 px and cost a tenth of the second pass).
constexpr double kNegligibleVelocityShiftM = 1e-5;

// How far updated velocities (bp.frame_velocity against `before`) move the pose each active observation
// is seen at: the largest |dt| x (|dv| + |dw| x scale_m) over them, metres.
double VelocityShiftM(const std::vector<std::array<double, 6>>& before, double scale_m,
                      const BundleProblem& bp) {
  if (before.size() != bp.frame_velocity.size()) return std::numeric_limits<double>::infinity();
  double worst = 0.0;
  for (size_t k = 0; k < bp.observations.size(); ++k) {
    if (!bp.active[k]) continue;
    const std::array<double, 6>& a = before[bp.observations[k].frame];
    const std::array<double, 6>& b = bp.frame_velocity[bp.observations[k].frame];
    const double dw = std::hypot(b[0] - a[0], b[1] - a[1], b[2] - a[2]);
    const double dv = std::hypot(b[3] - a[3], b[4] - a[4], b[5] - a[5]);
    worst = std::max(worst, std::abs(bp.ObservationDt(k)) * (dv + dw * scale_m));
  }
  return worst;
}

BundleSummary Solve(const BundleSettings& settings, MapperBundle* bundle, MapReport* report) {
  const BundleSummary summary = SolveBundle(&bundle->problem, settings);
  ++report->solves;
  report->iterations += summary.iterations;
  report->termination = summary.termination;
  return summary;
}

// One rejection round at the current parameters; returns true when an observation was rejected.
bool RejectGrossResiduals(const Observations& observations, const ObservationNames& names,
                          const MarkerLayout& layout, const MapperOptions& o, MapperBundle* bundle,
                          MapReport* report) {
  BundleProblem& bp = bundle->problem;
  const int num_markers = static_cast<int>(bundle->marker_rejected.size());
  const std::vector<double> rms = ObservationRms(bp);
  bool changed = false;
  std::vector<int> active_n(num_markers, 0), rejected_n(num_markers, 0);
  for (size_t k = 0; k < rms.size(); ++k) {
    if (!bp.active[k]) continue;
    ++active_n[bp.observations[k].marker];
    if (!(rms[k] <= o.outlier_px)) {
      std::ostringstream why;
      why << "gross residual (rms " << rms[k] << " px > outlier_px " << o.outlier_px << ")";
      RejectObservation(*bundle, observations, names, k, rms[k], why.str(), &bp, report);
      ++rejected_n[bp.observations[k].marker];
      changed = true;
    }
  }
  for (int m = 0; m < num_markers; ++m) {
    if (m == layout.reference || active_n[m] == 0) continue;
    if (!(rejected_n[m] > o.marker_reject_fraction * active_n[m])) continue;
    bundle->marker_rejected[m] = 1;
    std::ostringstream why;
    why << "not rigidly attached: " << rejected_n[m] << " of " << active_n[m]
        << " observations have gross residuals after refinement";
    report->rejected_markers.push_back({(*names.marker_ids)[m], layout.observations[m], why.str()});
    for (size_t k = 0; k < bp.observations.size(); ++k)
      if (bp.active[k] && bp.observations[k].marker == m)
        RejectObservation(*bundle, observations, names, k, rms[k], "marker dropped", &bp, report);
  }
  return changed;
}

}  // namespace

void RefineWithRejection(const Observations& observations, const ObservationNames& names,
                         const MarkerLayout& layout, const MapperOptions& o, const BundleSettings& settings,
                         MapperBundle* bundle, MapReport* report, int velocity_passes) {
  double sigma_px = 0.0;
  BundleSettings solve_settings = settings;
  BundleProblem& bp = bundle->problem;
  const bool intrinsics = o.intrinsics.refine != IntrinsicsRefinement::kNone;
  if (intrinsics || o.estimate_time_offsets) {
    if (intrinsics) {
      // Poses first at the given intrinsics (no rejection yet: rough intrinsics leave large residuals
      // that are not outliers), then the intrinsics the data can constrain join the unknowns. (The clocks
      // alone join at once: the poses-first solve took a fifth of the time-offset mapping and changed
      // the offsets by 1 us.)
      // Its result only scales the intrinsics' prior and information and starts the solve with them:
      // it stops at 10 times the paper's threshold (bench_selfcal's everything row: 2 iterations of 3, the
      // RMS the same to 1e-6 px).
      BundleSettings poses_first = settings;
      poses_first.paper_stop_px = kRoughStopFactor * settings.paper_stop_px;
      const BundleSummary first = Solve(poses_first, bundle, report);
      if (!first.usable) throw MapperError("refinement failed: " + first.termination);
      // Corner noise per coordinate: the observations' RMS corner distance / sqrt(2).
      sigma_px = std::max(0.05, CurrentRms(bundle->problem) / std::sqrt(2.0));
      report->intrinsics = PlanIntrinsicsRefinement(o.intrinsics, *names.camera_names, sigma_px, &bp);
      // An intrinsic trades with the camera's pose and barely moves the RMS per iteration: the paper's
      // stopping rule would end the solve long before the intrinsics arrive (cx 8 px off stayed 7.4
      // off): it stops at a 100 times smaller RMS improvement.
      solve_settings.paper_stop_px = 0.01 * settings.paper_stop_px;
    }
    if (o.estimate_time_offsets) {
      bp.time_offset_s.assign(bp.cam_from_rig.size(), 0.0);
      bp.time_offset_fixed = bp.camera_fixed;  // the reference camera's clock is the rig's
      if (o.estimate_clock_drift) bp.time_drift.assign(bp.cam_from_rig.size(), 0.0);
    }
  }
  for (int round = 0;; ++round) {
    if (bp.RefinesTime()) UpdateFrameVelocities(VelocityGapS(bp), &bp);
    const BundleSummary summary = Solve(solve_settings, bundle, report);
    report->linear_solver = summary.linear_solver;
    if (!summary.usable) throw MapperError("refinement failed: " + summary.termination);
    if (round >= o.max_rejection_rounds) break;
    if (!RejectGrossResiduals(observations, names, layout, o, bundle, report)) break;
  }
  // The agreement test's information, for the posterior covariances at the end (held entries dropped):
  // the agreement re-solve only brings back the poses the held entries had traded with (bench_selfcal's
  // everything row: the largest focal sigma the same to 3 digits; computing it again was a fourteenth of the
  // second pass). After a velocity re-solve it is computed again.
  IntrinsicsInformation information;
  bool information_current = !report->intrinsics.empty();
  if (!report->intrinsics.empty() &&
      KeepAgreeingIntrinsics(sigma_px, &report->intrinsics, &bp, &information)) {
    BundleSettings full = solve_settings;
    full.paper_stop = false;
    if (!Solve(full, bundle, report).usable) throw MapperError("refinement failed (intrinsics)");
  }
  // The velocities the offsets move poses along come from the poses: re-solve with them updated, until
  // they move nothing (kNegligibleVelocityShiftM).
  for (int pass = 0; bp.RefinesTime() && pass < velocity_passes; ++pass) {
    const std::vector<std::array<double, 6>> before = bp.frame_velocity;
    UpdateFrameVelocities(VelocityGapS(bp), &bp);
    const double shift_m = VelocityShiftM(before, layout.ObjectScale(), bp);
    if (shift_m < kNegligibleVelocityShiftM) break;
    if (!Solve(solve_settings, bundle, report).usable) throw MapperError("refinement failed (time offsets)");
    information_current = false;
  }
  if (!report->intrinsics.empty())
    FinishIntrinsicsReports(&bundle->problem, sigma_px, &report->intrinsics,
                            information_current ? &information : nullptr);
}

namespace {

std::string UnreliableCameraMessage(int c, int total, int active, const CameraPlacement& cameras,
                                    const std::vector<std::string>& names, const MapperOptions& o) {
  std::ostringstream msg;
  msg << "camera '" << names[c] << "'" << (c == cameras.reference ? " (the reference camera)" : "")
      << " cannot be placed reliably: " << total - active << " of its " << total
      << " marker observations (in " << cameras.views[c]
      << " frames) do not fit the map after refinement (rms > outlier_px " << o.outlier_px
      << " px); record more frames where '" << names[c]
      << "' sees the object closer to face-on at the same time as another camera";
  std::vector<double> others;
  for (size_t k = 0; k < names.size(); ++k)
    if (static_cast<int>(k) != c && cameras.fit_rms[k] >= 0) others.push_back(cameras.fit_rms[k]);
  const double fit = cameras.fit_rms[c];
  if (fit >= 0 && !others.empty() && fit > 3.0 * Median(others) && fit > 2.0)
    msg << ". Its frames with several markers do not fit the marker layout (median rms "
        << std::setprecision(3) << fit << " px; other cameras " << Median(others)
        << " px): check its intrinsics and the orientation of "
        << "its images";
  return msg.str();
}

// Makes camera `reference` the rig frame: every cam_from_rig, rig_from_object and frame velocity
// re-expressed in it.
void ReanchorOn(int reference, CameraPlacement* cameras, BundleProblem* bp) {
  const Rigid3 rig_from_new = Inverse(RigidFromBlock(bp->cam_from_rig[reference].data()));
  const Rigid3 new_from_rig = Inverse(rig_from_new);
  for (PoseBlock& b : bp->cam_from_rig)
    b = BlockFromRigid(Normalized(RigidFromBlock(b.data()) * rig_from_new));
  for (PoseBlock& b : bp->rig_from_object)
    b = BlockFromRigid(Normalized(new_from_rig * RigidFromBlock(b.data())));
  for (std::array<double, 6>& twist : bp->frame_velocity) twist = TwistIn(new_from_rig, twist);
  bp->cam_from_rig[reference] = BlockFromRigid(Rigid3::Identity());
  bp->camera_fixed.assign(bp->camera_fixed.size(), 0);
  bp->camera_fixed[reference] = 1;
  cameras->reference = reference;
}

// With --allow-partial a reference that does not fit is replaced by the best-connected camera that does;
// a reference the user named, or none left, is an error naming it.
void ReplaceReference(const std::vector<int>& bad, const std::string& problem, const MapperOptions& o,
                      const std::vector<std::string>& names, CameraPlacement* cameras, BundleProblem* bp,
                      MapReport* report) {
  const int n = static_cast<int>(names.size());
  if (!o.reference_camera.empty())
    throw MapperError(problem + "; it is the reference camera: name another one " +
                      "(--reference-camera or mapper.reference_camera) to map without it");
  std::vector<bool> eligible(cameras->placed.begin(), cameras->placed.end());
  for (int c : bad) eligible[c] = false;
  const int next = BestConnectedNode(n, cameras->edges, eligible);
  if (next < 0) throw MapperError(problem + "; it is the reference camera and no other camera fits the map");
  report->warnings.push_back("reference camera '" + names[cameras->reference] + "' left out: '" +
                             names[next] + "' is the reference camera instead");
  ReanchorOn(next, cameras, bp);
}

}  // namespace

void DropUnreliableCameras(const Observations& observations, const ObservationNames& names,
                           const MapperOptions& o, const BundleSettings& settings, CameraPlacement* cameras,
                           MapperBundle* bundle, MapReport* report) {
  BundleProblem& bp = bundle->problem;
  const std::vector<std::string>& camera_names = *names.camera_names;
  const int n = static_cast<int>(camera_names.size());
  std::vector<int> total(n, 0), active(n, 0);
  for (size_t k = 0; k < bp.observations.size(); ++k) {
    ++total[bp.observations[k].camera];
    active[bp.observations[k].camera] += bp.active[k];
  }
  std::vector<std::string> problems;
  std::vector<int> bad;
  for (int c = 0; c < n; ++c) {
    // The reference camera too: a badly placed reference makes every other pose meaningless.
    if (!cameras->placed[c] || total[c] == 0 || active[c] >= 0.5 * total[c]) continue;
    problems.push_back(UnreliableCameraMessage(c, total[c], active[c], *cameras, camera_names, o));
    bad.push_back(c);
  }
  if (problems.empty()) return;
  if (!o.allow_partial) {
    std::string all = problems[0];
    if (problems.size() > 1) all += " (and " + std::to_string(problems.size() - 1) + " more cameras)";
    throw MapperError(all + "; use --allow-partial to map without it");
  }
  for (size_t i = 0; i < bad.size(); ++i)
    if (bad[i] == cameras->reference)
      ReplaceReference(bad, problems[i], o, camera_names, cameras, &bp, report);
  for (int c : bad) {
    cameras->placed[c] = false;
    report->dropped_cameras.push_back(camera_names[c]);
    for (size_t k = 0; k < bp.observations.size(); ++k)
      if (bp.active[k] && bp.observations[k].camera == c)
        RejectObservation(*bundle, observations, names, k, 0.0, "camera left out (--allow-partial)", &bp,
                          report);
  }
  for (const std::string& p : problems) report->warnings.push_back(p + ": left out (--allow-partial)");
  Solve(settings, bundle, report);
}

namespace {

// Sums of squared observation RMS (and largest corner errors) per camera, marker and frame.
struct ResidualStats {
  std::vector<double> cam_sq, cam_max, mk_sq, mk_max, fr_sq;
  std::vector<int> cam_n, mk_n, fr_n;
  std::vector<std::set<int>> fr_cams, fr_markers;
  double total_sq = 0;
  int total_n = 0;
  std::vector<double> fr_dt;  // sum of the observations' capture times relative to the frame's pose, s
};

ResidualStats StatsOf(const BundleProblem& bp) {
  const size_t nc = bp.cam_from_rig.size(), nm = bp.object_from_marker.size(), nf = bp.rig_from_object.size();
  ResidualStats s{std::vector<double>(nc, 0),
                  std::vector<double>(nc, 0),
                  std::vector<double>(nm, 0),
                  std::vector<double>(nm, 0),
                  std::vector<double>(nf, 0),
                  std::vector<int>(nc, 0),
                  std::vector<int>(nm, 0),
                  std::vector<int>(nf, 0),
                  std::vector<std::set<int>>(nf),
                  std::vector<std::set<int>>(nf),
                  0.0,
                  0,
                  std::vector<double>(nf, 0.0)};
  std::vector<double> max_corner;
  const std::vector<double> rms = ObservationRms(bp, &max_corner);
  for (size_t k = 0; k < bp.observations.size(); ++k) {
    if (!bp.active[k] || !std::isfinite(rms[k])) continue;
    const BundleObservation& b = bp.observations[k];
    const double sq = rms[k] * rms[k];
    s.cam_sq[b.camera] += sq;
    s.cam_max[b.camera] = std::max(s.cam_max[b.camera], max_corner[k]);
    ++s.cam_n[b.camera];
    s.mk_sq[b.marker] += sq;
    s.mk_max[b.marker] = std::max(s.mk_max[b.marker], max_corner[k]);
    ++s.mk_n[b.marker];
    s.fr_sq[b.frame] += sq;
    s.fr_dt[b.frame] += bp.ObservationDt(k);
    ++s.fr_n[b.frame];
    s.fr_cams[b.frame].insert(b.camera);
    s.fr_markers[b.frame].insert(b.marker);
    s.total_sq += sq;
    ++s.total_n;
  }
  return s;
}

}  // namespace

FrameMembership MembershipOf(const std::vector<Frame>& frames, const std::vector<int>& row_frames,
                             size_t num_messages) {
  FrameMembership m;
  m.row_of_detection.assign(num_messages, -1);
  for (size_t row = 0; row < row_frames.size(); ++row) {
    const Frame& f = frames[row_frames[row]];
    m.frame_utime_of_row.push_back(f.utime);
    for (int i : f.messages) m.row_of_detection[i] = static_cast<int>(row);
  }
  return m;
}

void FillMap(const MapperBundle& bundle, const Observations& observations, const ObservationNames& names,
             const MarkerLayout& layout, const CameraPlacement& cameras, const MapperOptions& o, RigMap* map,
             std::vector<TrajectoryRow>* trajectory, std::vector<int>* row_frames) {
  const BundleProblem& bp = bundle.problem;
  const ResidualStats s = StatsOf(bp);
  const std::vector<int>& ids = observations.marker_ids;
  map->dictionary = o.dictionary;
  map->reference_camera = (*names.camera_names)[cameras.reference];
  map->reference_marker = ids[layout.reference];
  map->cameras.clear();
  map->markers.clear();
  for (size_t c = 0; c < bp.cam_from_rig.size(); ++c) {
    if (!cameras.placed[c]) continue;
    const double rms = s.cam_n[c] ? std::sqrt(s.cam_sq[c] / s.cam_n[c]) : 0.0;
    map->cameras.push_back({(*names.camera_names)[c], bp.Model(static_cast<int>(c)),
                            Normalized(Inverse(RigidFromBlock(bp.cam_from_rig[c].data()))), s.cam_n[c], rms,
                            s.cam_max[c], bp.RefinesTime() ? 1e6 * bp.time_offset_s[c] : 0.0,
                            bp.RefinesDrift() ? 1e6 * bp.time_drift[c] : 0.0});
  }
  map->time_reference_utime = bp.RefinesDrift() ? bp.time_reference_utime : 0;
  std::vector<int> order(ids.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int x, int y) { return ids[x] < ids[y]; });
  for (int m : order) {
    if (!layout.placed[m] || bundle.marker_rejected[m]) continue;
    const double rms = s.mk_n[m] ? std::sqrt(s.mk_sq[m] / s.mk_n[m]) : 0.0;
    map->markers.push_back({ids[m], o.sizes.Get(ids[m]),
                            Normalized(RigidFromBlock(bp.object_from_marker[m].data())), s.mk_n[m], rms,
                            s.mk_max[m]});
  }
  map->rms_px = s.total_n ? std::sqrt(s.total_sq / s.total_n) : 0.0;
  map->num_observations = s.total_n;
  trajectory->clear();
  if (row_frames) row_frames->clear();
  for (size_t f = 0; f < bp.rig_from_object.size(); ++f) {
    if (s.fr_n[f] == 0) continue;
    TrajectoryRow row;
    // With clocks, the row is at its observations' mean capture time on the reference clock (the frame's
    // pose is at its first message's utime, on that camera's clock as the frames were assembled: with
    // the time offsets' second pass, the first pass's clock error of that camera; at 0.5 m/s 1 ms is
    // 0.5 mm of the object's trajectory). The pose is at the row's utime exactly (the mean rounded to the
    // microsecond), and the row keeps the bundle's velocity: moved along it, it is the pose each
    // observation saw (the diagnostics').
    const int64_t dt_us = bp.RefinesTime() ? std::llround(1e6 * s.fr_dt[f] / s.fr_n[f]) : 0;
    row.utime = (*names.frames)[f].utime + dt_us;
    row.seq = (*names.frames)[f].seq;
    row.rig_from_object = Normalized(FramePoseAt(bp, static_cast<int>(f), 1e-6 * static_cast<double>(dt_us)));
    if (bp.RefinesTime()) row.velocity = bp.frame_velocity[f];
    row.rms_px = std::sqrt(s.fr_sq[f] / s.fr_n[f]);
    row.cameras = static_cast<int>(s.fr_cams[f].size());
    row.markers = static_cast<int>(s.fr_markers[f].size());
    trajectory->push_back(row);
    if (row_frames) row_frames->push_back(static_cast<int>(f));
  }
  map->num_frames = static_cast<int>(trajectory->size());
}

}  // namespace mcmt
