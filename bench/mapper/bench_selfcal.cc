// Self-calibration (issue 18): each perturbation of what the mapper is told (intrinsics, clock offsets
// and drifts, both), the errors before and after refinement, the recovered values against the truth, and
// the mapping time against the same session mapped with the defaults (synchronised, exact intrinsics).
//
//   bench_selfcal [--frames 300] [--long 1200] [--seeds N] [--ablate N] [--only TEXT] [--threads N]
//                 [--verbose]
//
// Sessions: tests/mapper/selfcal_sim.h (the paper's rig, 5 cameras at 30 fps, box object, 0.2 px corner
// noise; the simulator's detections, as mcmt-sim --detections-only --intrinsics-error / --clock
// / --max-speed-m-s). --long: the quick-calibration rows again with that many frames (how the camera error
// falls with more observations; 0: skipped). --seeds N: instead, the quick calibration over N sessions, why
// the refined cameras' positions are worse (SeedRows). --ablate N: which entry's error makes it
// (AblationRows). --only TEXT: only the rows whose perturbation or settings contain TEXT are mapped (besides
// their baselines), e.g. `--only clock_drift`. --threads N: the mappings' threads (0: the mapper's default;
// 1 gives callgrind one call tree). Prints a markdown table.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <map>
#include <string>
#include <vector>

#include "tests/mapper/selfcal_sim.h"

namespace mcmt {
namespace {

using testing::SelfCalRun;
using testing::SelfCalSession;

bool verbose = false;
std::string only;  // --only
int threads = 0;   // --threads

struct Row {
  std::string perturbation, settings;
  double camera_mm = 0, object_mm = 0, seconds = 0, baseline_s = 0;
  double cpu_s = 0, baseline_cpu_s = 0;  // processor time of the mapping (all threads)
  std::string recovered;
  bool skipped = false;  // --only
};

// Largest error of the refined focal lengths (%), principal points (px) and k1 over the cameras.
std::string IntrinsicsRecovered(const sim::GroundTruth& truth, const MapResult& r) {
  double focal = 0, centre = 0, k1 = 0, sigma_focal = 0;
  for (const MapCamera& c : r.map.cameras) {
    const CameraModel& t = truth.FindCamera(c.name)->model;
    const CameraModel& m = c.model;
    focal = std::max({focal, std::abs(m.fx / t.fx - 1), std::abs(m.fy / t.fy - 1)});
    centre = std::max({centre, std::abs(m.cx - t.cx), std::abs(m.cy - t.cy)});
    if (!t.distortion.empty()) k1 = std::max(k1, std::abs(m.distortion[0] - t.distortion[0]));
  }
  for (const IntrinsicsReport& ir : r.report.intrinsics)
    if (ir.is_refined[0]) sigma_focal = std::max(sigma_focal, ir.posterior_sigma[0] / ir.refined[0]);
  char text[256];
  std::snprintf(text, sizeof(text), "focal %.3f %% (posterior sigma <= %.3f %%), centre %.2f px, k1 %.4f",
                100 * focal, 100 * sigma_focal, centre, k1);
  return text;
}

// Largest error of the cameras' clocks (offset + drift) over the session (us) and of the drifts (ppm),
// against the reference camera's clock.
std::string ClocksRecovered(const SelfCalRun& run, const MapResult& r, bool drift) {
  auto reading = [&](const std::string& name, int64_t utime) {
    const auto it = run.truth.clocks.find(name);
    return it == run.truth.clocks.end() ? 0.0
                                        : static_cast<double>(sim::ClockUtime(it->second, utime) - utime);
  };
  auto drift_of = [&](const std::string& name) {
    const auto it = run.truth.clocks.find(name);
    return it == run.truth.clocks.end() ? 0.0 : it->second.drift_ppm;
  };
  double worst_us = 0, worst_ppm = 0;
  for (const MapCamera& c : r.map.cameras) {
    for (const sim::SimFrame& f : run.truth.frames) {
      const double truth = reading(c.name, f.utime) - reading(r.map.reference_camera, f.utime);
      worst_us = std::max(worst_us, std::abs(c.ClockUs(f.utime, r.map.time_reference_utime) - truth));
    }
    worst_ppm = std::max(worst_ppm,
                         std::abs(c.time_drift_ppm - (drift_of(c.name) - drift_of(r.map.reference_camera))));
  }
  char text[160];
  if (drift)
    std::snprintf(text, sizeof(text), "clocks within %.0f us over the session, drifts within %.1f ppm",
                  worst_us, worst_ppm);
  else
    std::snprintf(text, sizeof(text), "clocks within %.0f us over the session", worst_us);
  return text;
}

// Processor time of this process (all its threads), seconds: on the shared machine the wall time of a
// mapping varies by 2x with the other processes' load, its processor time by a few per cent.
double CpuSeconds() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

MapResult Map(const SelfCalRun& run, const MapperOptions& options, const std::string& what,
              double* cpu_s = nullptr) {
  MapperOptions o = options;
  if (threads > 0) o.threads = threads;
  const double cpu_start = CpuSeconds();
  const MapResult r = testing::MapDetections(run.detections, o);
  if (cpu_s) *cpu_s = CpuSeconds() - cpu_start;
  if (verbose) {
    std::fprintf(stderr, "%s: %.2f s, %d solves, %d iterations\n", what.c_str(), r.report.total_seconds,
                 r.report.solves, r.report.iterations);
    for (const auto& [stage, seconds] : r.report.stage_seconds)
      std::fprintf(stderr, "  %-32s %.3f s\n", stage.c_str(), seconds);
  }
  return r;
}

Row Measure(const SelfCalRun& run, const MapperOptions& options, const Row* baseline,
            const std::string& perturbation, const std::string& settings, const std::string& recovered_kind) {
  if (baseline && !only.empty() && (perturbation + " " + settings).find(only) == std::string::npos) {
    Row skipped;
    skipped.skipped = true;
    return skipped;
  }
  double cpu_s = 0;
  const MapResult r = Map(run, options, perturbation + " / " + settings, &cpu_s);
  const sim::EvalResult e = sim::Evaluate(run.truth, &r.map, &r.trajectory);
  Row row;
  row.perturbation = perturbation;
  row.settings = settings;
  row.camera_mm = e.camera_position_mm.mean;
  row.object_mm = e.object_translation_mm.mean;
  row.seconds = r.report.total_seconds;
  row.cpu_s = cpu_s;
  row.baseline_s = baseline ? baseline->seconds : row.seconds;
  row.baseline_cpu_s = baseline ? baseline->cpu_s : row.cpu_s;
  if (recovered_kind == "intrinsics") row.recovered = IntrinsicsRecovered(run.truth, r);
  if (recovered_kind == "clocks") row.recovered = ClocksRecovered(run, r, false);
  if (recovered_kind == "drift") row.recovered = ClocksRecovered(run, r, true);
  if (recovered_kind == "both")
    row.recovered = IntrinsicsRecovered(run.truth, r) + "; " + ClocksRecovered(run, r, true);
  if (recovered_kind.empty()) row.recovered = "-";
  return row;
}

// The quick calibration of the issue: cam1 and cam3 focal +-3 %, principal point 8 px, k1 +-0.03.
void QuickCalibration(SelfCalRun* run) {
  testing::PerturbIntrinsics("cam1", {0.03, 8.0, -6.0, 0.03}, run);
  testing::PerturbIntrinsics("cam3", {-0.03, -8.0, 8.0, -0.03}, run);
}

const std::map<std::string, sim::CameraClock> kOffsets = {
    {"cam1", {-20.0, 0.0}}, {"cam2", {12.0, 0.0}}, {"cam4", {20.0, 0.0}}};
const std::map<std::string, sim::CameraClock> kDrifts = {
    {"cam1", {-20.0, 400.0}}, {"cam2", {12.0, -300.0}}, {"cam4", {20.0, 0.0}}};

void QuickCalibrationRows(int frames, std::vector<Row>* rows) {
  SelfCalSession session;
  session.frames = frames;
  const SelfCalRun exact = testing::SimulateSelfCal(session);
  SelfCalRun wrong = exact;
  QuickCalibration(&wrong);
  MapperOptions defaults = testing::SelfCalOptions(exact.truth);
  MapperOptions all = defaults;
  all.intrinsics.refine = IntrinsicsRefinement::kAll;
  const std::string n = " (" + std::to_string(frames) + " frames)";
  const Row base = Measure(exact, defaults, nullptr, "none" + n, "defaults", "");
  rows->push_back(base);
  rows->push_back(Measure(exact, all, &base, "none" + n, "`refine_intrinsics: all`", "intrinsics"));
  rows->push_back(Measure(wrong, defaults, &base, "cam1, cam3: focal +-3 %, centre 8 px, k1 +-0.03" + n,
                          "defaults", "intrinsics"));
  rows->push_back(Measure(wrong, all, &base, "same" + n, "`refine_intrinsics: all`", "intrinsics"));
}

// Why the refined cameras' positions are worse than with exact intrinsics (--seeds N): the quick
// calibration over N sessions (seeds 11, 12, ...). Per refined camera: its focal length's error against its
// posterior sigma (z: an unbiased estimate has |z| ~ 0.8 on average), its position error split along its
// optical axis and across it (+: towards the scene), and the axial error the focal error alone predicts
// (-distance to the object x relative focal error: with its focal length short by x % the camera, to see
// the object as large as it is seen, is placed x % closer).
void SeedRows(int num_seeds, int frames) {
  std::printf(
      "| seed | camera error, exact intrinsics | refined | ratio | camera | fx error (posterior sigma, z) | "
      "position error along / across the axis (exact intrinsics) | -distance x fx error |\n");
  std::printf("|---:|---:|---:|---:|---|---|---|---:|\n");
  double sum_abs_z = 0, sum_exact = 0, sum_refined = 0;
  int n_z = 0;
  for (int k = 0; k < num_seeds; ++k) {
    SelfCalSession session;
    session.frames = frames;
    session.seed = 11 + k;
    const SelfCalRun exact = testing::SimulateSelfCal(session);
    SelfCalRun wrong = exact;
    QuickCalibration(&wrong);
    MapperOptions defaults = testing::SelfCalOptions(exact.truth);
    MapperOptions all = defaults;
    all.intrinsics.refine = IntrinsicsRefinement::kAll;
    const MapResult r_exact = testing::MapDetections(exact.detections, defaults);
    const MapResult r_refined = testing::MapDetections(wrong.detections, all);
    const sim::EvalResult e_exact = sim::Evaluate(exact.truth, &r_exact.map, &r_exact.trajectory);
    const sim::EvalResult e_refined = sim::Evaluate(exact.truth, &r_refined.map, &r_refined.trajectory);
    sum_exact += e_exact.camera_position_mm.mean;
    sum_refined += e_refined.camera_position_mm.mean;
    Eigen::Vector3d object_mean = Eigen::Vector3d::Zero();
    for (const sim::SimFrame& f : exact.truth.frames) object_mean += f.rig_from_object.translation();
    object_mean /= static_cast<double>(exact.truth.frames.size());
    // Position error of a camera split along its (true) optical axis and across it, mm.
    auto split = [&](const sim::EvalResult& e, const MapResult& r, const std::string& name) {
      const sim::SimCamera& t = *exact.truth.FindCamera(name);
      const Eigen::Vector3d error =
          e.gt_rig_from_est_rig * r.map.FindCamera(name)->rig_from_cam.translation() -
          t.rig_from_cam.translation();
      const Eigen::Vector3d axis = t.rig_from_cam.linear().col(2);
      return std::make_pair(1000 * error.dot(axis), 1000 * (error - error.dot(axis) * axis).norm());
    };
    for (const IntrinsicsReport& ir : r_refined.report.intrinsics) {
      if (!ir.is_refined[0]) continue;
      const sim::SimCamera& t = *exact.truth.FindCamera(ir.camera);
      const double fx_error = ir.refined[0] / t.model.fx - 1, sigma = ir.posterior_sigma[0] / ir.refined[0];
      const double z = fx_error / sigma;
      sum_abs_z += std::abs(z);
      ++n_z;
      const auto refined = split(e_refined, r_refined, ir.camera);
      const auto base = split(e_exact, r_exact, ir.camera);
      const double distance_mm = 1000 * (t.rig_from_cam.translation() - object_mean).norm();
      std::printf(
          "| %llu | %.3f mm | %.3f mm | %.1fx | %s | %+.3f %% (%.3f %%, z %+.2f) | %+.3f / %.3f mm (%+.3f / "
          "%.3f) "
          "| %+.3f mm |\n",
          static_cast<unsigned long long>(session.seed), e_exact.camera_position_mm.mean,
          e_refined.camera_position_mm.mean,
          e_refined.camera_position_mm.mean / e_exact.camera_position_mm.mean, ir.camera.c_str(),
          100 * fx_error, 100 * sigma, z, refined.first, refined.second, base.first, base.second,
          -distance_mm * fx_error);
    }
  }
  std::printf(
      "\nmean over %d sessions: exact intrinsics %.3f mm, refined %.3f mm (%.1fx); mean |z| of fx %.2f\n",
      num_seeds, sum_exact / num_seeds, sum_refined / num_seeds, sum_refined / sum_exact,
      n_z ? sum_abs_z / n_z : 0.0);
}

// What makes the refined cameras' positions worse (--ablate N): the quick calibration over N sessions
// (seeds 11, 12, ...) refined with `all` as is and with one kind of entry given exactly and held there
// (its error left out of the quick calibration and a prior sigma of 1e-6 (focal: relative; centre 1e-4 px),
// so the observability test holds it at the given value, the truth; radial holds k1, k2 and k3), with a 10x
// wider prior, and run to convergence (no paper stop). Per variant, over the two perturbed cameras and the
// seeds: the errors of fx and of the principal point (cx and cy) against their posterior sigmas (mean z,
// signed towards the quick calibration's error: a pull towards the given values; RMS z: 1 when the posterior
// is calibrated and the estimate efficient), the camera position error along the optical axis against what
// the posterior focal sigma predicts (distance x sigma), and the mean camera error against the same
// session mapped with exact intrinsics and the defaults. (n): how many entries were refined (not held).
// --only TEXT: the variants whose name contains it.
struct Variant {
  std::string name;
  sim::IntrinsicsError cam1{0.03, 8.0, -6.0, 0.03}, cam3{-0.03, -8.0, 8.0, -0.03};
  IntrinsicsSigma sigma;
  bool paper_stop = true;
  bool exact = false;  // the exact session refined
};

struct VariantSums {
  int n = 0, seeds = 0;
  double camera_mm = 0, exact_mm = 0;
  double z_fx = 0, z_fx_sq = 0, fx_err_sq = 0, sigma_fx_sq = 0;
  double z_cx = 0, z_cx_sq = 0, cx_err = 0, cx_err_abs = 0, sigma_cx = 0;
  double axial_sq = 0, predicted_axial_sq = 0;
  int n_cx = 0, n_fx = 0;
};

void AblationRows(int num_seeds, int frames) {
  std::vector<Variant> variants(7);
  variants[0].name = "`all` (the quick calibration's row)";
  variants[1].name = "focal given exactly and held";
  variants[1].cam1.focal_rel = variants[1].cam3.focal_rel = 0;
  variants[1].sigma.focal_rel = 1e-6;
  variants[2].name = "principal point given exactly and held";
  variants[2].cam1.cx_px = variants[2].cam1.cy_px = variants[2].cam3.cx_px = variants[2].cam3.cy_px = 0;
  variants[2].sigma.center_px = 1e-4;
  variants[3].name = "k1 given exactly, k1 k2 k3 held";
  variants[3].cam1.k1 = variants[3].cam3.k1 = 0;
  variants[3].sigma.radial = 1e-6;
  variants[4].name = "prior 10x wider";
  variants[4].sigma.focal_rel *= 10;
  variants[4].sigma.center_px *= 10;
  variants[4].sigma.radial *= 10;
  variants[4].sigma.tangential *= 10;
  variants[5].name = "no paper stop (to Ceres' convergence)";
  variants[5].paper_stop = false;
  variants[6].name = "exact intrinsics refined";
  variants[6].exact = true;
  std::vector<VariantSums> sums(variants.size());
  for (int k = 0; k < num_seeds; ++k) {
    SelfCalSession session;
    session.frames = frames;
    session.seed = 11 + k;
    const SelfCalRun exact = testing::SimulateSelfCal(session);
    const MapperOptions defaults = testing::SelfCalOptions(exact.truth);
    const MapResult r_exact = testing::MapDetections(exact.detections, defaults);
    const sim::EvalResult e_exact = sim::Evaluate(exact.truth, &r_exact.map, &r_exact.trajectory);
    Eigen::Vector3d object_mean = Eigen::Vector3d::Zero();
    for (const sim::SimFrame& f : exact.truth.frames) object_mean += f.rig_from_object.translation();
    object_mean /= static_cast<double>(exact.truth.frames.size());
    for (size_t v = 0; v < variants.size(); ++v) {
      const Variant& variant = variants[v];
      if (!only.empty() && variant.name.find(only) == std::string::npos) continue;
      SelfCalRun run = exact;
      if (!variant.exact) {
        testing::PerturbIntrinsics("cam1", variant.cam1, &run);
        testing::PerturbIntrinsics("cam3", variant.cam3, &run);
      }
      MapperOptions o = defaults;
      o.intrinsics.refine = IntrinsicsRefinement::kAll;
      o.intrinsics.sigma = variant.sigma;
      o.paper_stop = variant.paper_stop;
      const MapResult r = testing::MapDetections(run.detections, o);
      const sim::EvalResult e = sim::Evaluate(exact.truth, &r.map, &r.trajectory);
      VariantSums& s = sums[v];
      ++s.seeds;
      s.camera_mm += e.camera_position_mm.mean;
      s.exact_mm += e_exact.camera_position_mm.mean;
      for (const IntrinsicsReport& ir : r.report.intrinsics) {
        if (ir.camera != "cam1" && ir.camera != "cam3") continue;
        const sim::SimCamera& t = *exact.truth.FindCamera(ir.camera);
        const Eigen::Vector3d error =
            e.gt_rig_from_est_rig * r.map.FindCamera(ir.camera)->rig_from_cam.translation() -
            t.rig_from_cam.translation();
        const double axial_mm = 1000 * error.dot(t.rig_from_cam.linear().col(2));
        const double distance_mm = 1000 * (t.rig_from_cam.translation() - object_mean).norm();
        // +1 where the quick calibration's error of fx, cx, cy is positive: signed errors towards it.
        const double sign = ir.camera == "cam1" ? 1.0 : -1.0;
        const double toward[3] = {sign, sign, -sign};
        ++s.n;
        s.axial_sq += axial_mm * axial_mm;
        if (ir.is_refined[0] && ir.posterior_sigma[0] > 0) {
          const double err = ir.refined[0] / t.model.fx - 1, sigma = ir.posterior_sigma[0] / ir.refined[0];
          s.z_fx += toward[0] * err / sigma;
          s.z_fx_sq += err * err / (sigma * sigma);
          s.fx_err_sq += err * err;
          s.sigma_fx_sq += sigma * sigma;
          s.predicted_axial_sq += distance_mm * distance_mm * sigma * sigma;
          ++s.n_fx;
        }
        if (verbose)
          for (const std::string& why : ir.held)
            std::fprintf(stderr, "seed %d %s %s held: %s\n", 11 + k, variant.name.c_str(), ir.camera.c_str(),
                         why.c_str());
        for (int e = 2; e <= 3; ++e) {
          if (!ir.is_refined[e] || ir.posterior_sigma[e] <= 0) continue;
          const double err = ir.refined[e] - (e == 2 ? t.model.cx : t.model.cy),
                       sigma = ir.posterior_sigma[e];
          s.z_cx += toward[e - 1] * err / sigma;
          s.z_cx_sq += err * err / (sigma * sigma);
          s.cx_err += toward[e - 1] * err;
          s.cx_err_abs += std::abs(err);
          s.sigma_cx += sigma;
          ++s.n_cx;
        }
      }
      if (verbose)
        std::fprintf(stderr, "seed %d %s: %.3f mm (exact %.3f)\n", 11 + k, variant.name.c_str(),
                     e.camera_position_mm.mean, e_exact.camera_position_mm.mean);
    }
  }
  std::printf(
      "| variant (%d sessions, %d frames) | camera error | exact, defaults | ratio | fx error RMS | fx "
      "posterior "
      "sigma RMS | fx z mean / RMS | axial error RMS (cam1, cam3) | distance x fx sigma RMS | centre error "
      "mean "
      "/ mean abs | centre posterior sigma mean | centre z mean / RMS |\n",
      num_seeds, frames);
  std::printf("|---|---:|---:|---:|---:|---:|---|---:|---:|---|---:|---|\n");
  for (size_t v = 0; v < variants.size(); ++v) {
    const VariantSums& s = sums[v];
    if (s.seeds == 0) continue;  // --only
    const double nf = std::max(1, s.n_fx), nc = std::max(1, s.n_cx), n = std::max(1, s.n);
    char fx[160] = "-", cx[200] = "-";
    if (s.n_fx)
      std::snprintf(fx, sizeof(fx), "%.3f %% | %.3f %% | %+.2f / %.2f (%d)",
                    100 * std::sqrt(s.fx_err_sq / nf), 100 * std::sqrt(s.sigma_fx_sq / nf), s.z_fx / nf,
                    std::sqrt(s.z_fx_sq / nf), s.n_fx);
    else
      std::snprintf(fx, sizeof(fx), "- | - | -");
    if (s.n_cx)
      std::snprintf(cx, sizeof(cx), "%+.2f / %.2f px | %.2f px | %+.2f / %.2f (%d)", s.cx_err / nc,
                    s.cx_err_abs / nc, s.sigma_cx / nc, s.z_cx / nc, std::sqrt(s.z_cx_sq / nc), s.n_cx);
    else
      std::snprintf(cx, sizeof(cx), "- | - | -");
    std::printf("| %s | %.3f mm | %.3f mm | %.2fx | %s | %.3f mm | %.3f mm | %s |\n",
                variants[v].name.c_str(), s.camera_mm / s.seeds, s.exact_mm / s.seeds,
                s.camera_mm / s.exact_mm, fx, std::sqrt(s.axial_sq / n),
                s.n_fx ? std::sqrt(s.predicted_axial_sq / nf) : 0.0, cx);
  }
}

void Print(const std::vector<Row>& rows) {
  std::printf(
      "| perturbation | mapper settings | camera position error | object error | recovered vs truth (worst "
      "camera) | map time | vs defaults | processor time | vs defaults |\n");
  std::printf("|---|---|---:|---:|---|---:|---:|---:|---:|\n");
  for (const Row& r : rows)
    if (!r.skipped)
      std::printf("| %s | %s | %.3f mm | %.3f mm | %s | %.2f s | %.1fx | %.2f s | %.1fx |\n",
                  r.perturbation.c_str(), r.settings.c_str(), r.camera_mm, r.object_mm, r.recovered.c_str(),
                  r.seconds, r.baseline_s > 0 ? r.seconds / r.baseline_s : 1.0, r.cpu_s,
                  r.baseline_cpu_s > 0 ? r.cpu_s / r.baseline_cpu_s : 1.0);
}

int Main(int argc, char** argv) {
  int frames = 300, long_frames = 1200, seeds = 0, ablate = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--frames" && i + 1 < argc) {
      frames = std::atoi(argv[++i]);
    } else if (a == "--long" && i + 1 < argc) {
      long_frames = std::atoi(argv[++i]);
    } else if (a == "--seeds" && i + 1 < argc) {
      seeds = std::atoi(argv[++i]);
    } else if (a == "--ablate" && i + 1 < argc) {
      ablate = std::atoi(argv[++i]);
    } else if (a == "--only" && i + 1 < argc) {
      only = argv[++i];
    } else if (a == "--threads" && i + 1 < argc) {
      threads = std::atoi(argv[++i]);
    } else if (a == "--verbose") {
      verbose = true;
    } else {
      std::fprintf(stderr,
                   "usage: bench_selfcal [--frames 300] [--long 1200] [--seeds N] [--ablate N] [--only TEXT] "
                   "[--threads N] [--verbose]\n");
      return 2;
    }
  }
  if (ablate > 0) {
    AblationRows(ablate, frames);
    return 0;
  }
  if (seeds > 0) {
    SeedRows(seeds, frames);
    return 0;
  }
  std::vector<Row> rows;
  QuickCalibrationRows(frames, &rows);
  const Row base_row = rows.front();
  {
    SelfCalSession session;
    session.frames = frames;
    SelfCalRun rough = testing::SimulateSelfCal(session);
    testing::PerturbIntrinsics("cam2", {0.15, 0, 0, 0}, &rough);
    testing::PerturbIntrinsics("cam4", {-0.15, 0, 0, 0}, &rough);
    MapperOptions o = testing::SelfCalOptions(rough.truth);
    o.intrinsics.refine = IntrinsicsRefinement::kFocal;
    o.intrinsics.sigma.focal_rel = 0.2;
    rows.push_back(Measure(rough, o, &base_row, "cam2, cam4: focal +-15 %",
                           "`focal`, `intrinsics_sigma.focal_rel: 0.2`", "intrinsics"));
    // Only a field of view: focal lengths +15.8 % / -14.4 %, the principal point at the image centre.
    session.distortion = DistortionModel::kNone;
    SelfCalRun fov = testing::SimulateSelfCal(session);
    for (const auto& [name, deg] : std::map<std::string, double>{{"cam2", 53.0}, {"cam4", 68.0}}) {
      CameraModel m = fov.truth.FindCamera(name)->model;
      m.fx = m.fy = 0.5 * m.width / std::tan(0.5 * deg * M_PI / 180);
      m.cx = 0.5 * (m.width - 1);
      m.cy = 0.5 * (m.height - 1);
      testing::GiveIntrinsics(name, m, &fov);
    }
    MapperOptions f = testing::SelfCalOptions(fov.truth);
    Row fov_base;
    fov_base.seconds = Map(fov, f, "hfov baseline", &fov_base.cpu_s).report.total_seconds;
    f.intrinsics.refine = IntrinsicsRefinement::kFocalCenter;
    f.intrinsics.sigma.focal_rel = 0.2;
    rows.push_back(Measure(fov, f, &fov_base, "cam2, cam4: only hfov_deg 53 / 68 (no distortion)",
                           "`focal_center`, `intrinsics_sigma.focal_rel: 0.2`", "intrinsics"));
  }
  {
    // Clocks: the object up to ~0.95 m/s (time scale 6).
    SelfCalSession session;
    session.frames = frames;
    session.speed = 6.0;
    const SelfCalRun synced = testing::SimulateSelfCal(session);
    const SelfCalRun late = testing::SimulateSelfCal(session, kOffsets);
    const SelfCalRun drifting = testing::SimulateSelfCal(session, kDrifts);
    SelfCalRun both = drifting;
    QuickCalibration(&both);
    const MapperOptions defaults = testing::SelfCalOptions(synced.truth);
    char speed[96];
    std::snprintf(speed, sizeof(speed), "object up to %.2f m/s", synced.max_speed_m_s);
    const Row base =
        Measure(synced, defaults, nullptr, std::string("synchronised, ") + speed, "defaults", "");
    rows.push_back(base);
    MapperOptions wide = defaults;
    wide.sync_tolerance_ms = 25;
    rows.push_back(Measure(late, wide, &base, "cam1, cam2, cam4 clocks -20, +12, +20 ms",
                           "`sync.tolerance_ms: 25`, offsets ignored", ""));
    MapperOptions offsets = defaults;
    offsets.estimate_time_offsets = true;
    rows.push_back(Measure(late, offsets, &base, "same", "`time_offsets: true`", "clocks"));
    rows.push_back(Measure(drifting, offsets, &base, "same, drifting +400, -300, 0 ppm",
                           "`time_offsets: true`", "drift"));
    MapperOptions drift = offsets;
    drift.estimate_clock_drift = true;
    rows.push_back(Measure(drifting, drift, &base, "same", "`time_offsets`, `clock_drift: true`", "drift"));
    rows.push_back(Measure(both, wide, &base, "quick calibration (cam1, cam3) and drifting clocks",
                           "`sync.tolerance_ms: 25`", ""));
    MapperOptions everything = drift;
    everything.intrinsics.refine = IntrinsicsRefinement::kAll;
    rows.push_back(Measure(both, everything, &base, "same",
                           "`refine_intrinsics: all`, `time_offsets`, `clock_drift`", "both"));
  }
  if (long_frames > 0) QuickCalibrationRows(long_frames, &rows);
  Print(rows);
  return 0;
}

}  // namespace
}  // namespace mcmt

int main(int argc, char** argv) { return mcmt::Main(argc, argv); }
