#include "detector/side_model.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

namespace mcmt {

void SideProfiles::Reset(double u0_, double du_, int bins_, double cell_) {
  u0 = u0_, du = du_, bins = bins_, cell = cell_;
  fit_gamma = false;
  gamma_hint = 1.0;
  hold_gamma = false;
  polarity = 0;
  edge_only = false;
  patterns.clear();
  sum.reserve(static_cast<size_t>(16) * bins);
  count.reserve(static_cast<size_t>(16) * bins);
  sum.clear();
  count.clear();
  depth_sum.clear();
  other_sum.clear();
  rays.clear();
}

int SideProfiles::AddRay(const std::array<uint8_t, kRows>& pattern, const std::array<double, kRows>& depths,
                         const std::array<double, kRows>& other) {
  size_t g = 0;
  while (g < patterns.size() && patterns[g] != pattern) ++g;
  if (g == patterns.size()) {
    patterns.push_back(pattern);
    sum.resize(sum.size() + bins, 0.0);
    count.resize(count.size() + bins, 0.0);
    depth_sum.push_back({});
    other_sum.push_back({});
    rays.push_back(0);
  }
  for (int r = 0; r < kRows; ++r) depth_sum[g][r] += depths[r], other_sum[g][r] += other[r];
  ++rays[g];
  return static_cast<int>(g);
}

namespace {

// A further step beyond the margin's far side, the margin's far side, the outer edge, kRows inner.
constexpr int kBoundaries = SideProfiles::kRows + 3;
constexpr int kRegions = kBoundaries + 1;
// S3, Q2: the level beyond a further step of the surround and the step's distance beyond the margin's
// far side (a narrow face beyond the margin, then the object's edge: FitSideModels).
enum Param { kE, kSigma, kL0, kL1, kS1, kS2, kQ, kGamma, kS3, kQ2, kParams };
static_assert(kParams == std::tuple_size<decltype(SideFit::params)>::value, "SideFit::params");
// A margin differs from the border's level by at least this fraction of the border-to-code contrast
// (a print's margin is paper or ink of the other colour; FitSideProfiles).
constexpr double kMinMarginContrast = 0.4;
// A further surround step beyond the margin (FitFurtherStep) is tried where the margin differs from the
// surround by kMinFurtherMarginContrast of the code's contrast and the margin fit's mean residual beyond
// it reaches kFurtherStepResidual of that contrast at some bin; it is kept where the step is at least
// kMinFurtherStepContrast and the residual sum falls below kFurtherStepGain of the margin fit's.
constexpr double kMinFurtherMarginContrast = 0.25, kFurtherStepResidual = 0.01;
constexpr double kMinFurtherStepContrast = 0.1, kFurtherStepGain = 0.8;
// Nor on margins narrower than kMinFurtherMargin cells: beyond a sharpened 0.3-cell margin the halo was
// fitted as a step, and whether it was depended on the refinement's start (fast mode's corners 0.09 px
// from the accurate mode's on the reference renderer's "hard" condition).
constexpr double kMinFurtherMargin = 0.4;

// The number of parameters a model with `levels` surround levels fits (Evaluate): S3 and Q2 are last.
constexpr int ParamsOf(int levels) { return levels == 3 ? kParams : kS3; }
template <int N>
using Normal = Eigen::Matrix<double, N, N>;
template <int N>
using Vector = Eigen::Matrix<double, N, 1>;

// Model values, and with `jtj` / `jtr` the normal equations of its N = ParamsOf(levels) parameters, for
// parameters p with `levels` surround levels (1: S1 only, no margin; 2: margin S1 and surround S2; 3:
// and S3 beyond a further step). Returns the weighted squared residual sum; `bin_residual` (optional):
// per bin the weighted sum of the residuals and of the weights.
template <int N>
double Evaluate(const SideProfiles& s, const double* p, int levels, Normal<N>* jtj, Vector<N>* jtr,
                std::vector<double>* bin_residual = nullptr) {
  if (bin_residual) bin_residual->assign(2 * s.bins, 0.0);
  const int n = s.bins;
  const int groups = static_cast<int>(s.patterns.size());
  // Phi and phi of every boundary at every bin: the margin's far side and the outer edge are shared
  // by all groups, the inner boundaries are per group (their depths differ under perspective).
  const int rows_per_group = kBoundaries + (groups - 1) * SideProfiles::kRows;
  thread_local std::vector<double> big_phi, small_phi, zs;
  big_phi.resize(static_cast<size_t>(rows_per_group) * n);
  small_phi.resize(big_phi.size());
  zs.resize(big_phi.size());
  const double inv_sigma = 1.0 / p[kSigma], inv_gamma = 1.0 / p[kGamma];
  auto fill = [&](int row, double bound) {
    for (int j = 0; j < n; ++j) {
      const double z = (bound - (s.u0 + j * s.du)) * inv_sigma;
      const size_t i = static_cast<size_t>(row) * n + j;
      zs[i] = z;
      // Beyond 7 sigmas Phi is 0 or 1 within 1.3e-12 and phi below 1e-10: no exponential.
      if (std::abs(z) > 7.0)
        big_phi[i] = z > 0 ? 1.0 : 0.0, small_phi[i] = 0.0;
      else
        PhiAndDensity(z, &big_phi[i], &small_phi[i]);
    }
  };
  if (levels == 3) {
    fill(0, p[kE] + p[kQ] + p[kQ2]);
  } else {  // no further step: its boundary beyond every bin (its levels are equal)
    std::fill_n(big_phi.begin(), n, 1.0), std::fill_n(small_phi.begin(), n, 0.0);
    std::fill_n(zs.begin(), n, 0.0);
  }
  fill(1, p[kE] + p[kQ]);
  fill(2, p[kE]);
  for (int g = 0; g < groups; ++g)
    for (int r = 0; r < SideProfiles::kRows; ++r)
      fill(3 + g * SideProfiles::kRows + r, p[kE] - s.depth_sum[g][r] / s.rays[g]);
  if (jtj) jtj->setZero(), jtr->setZero();
  double cost = 0;
  for (int g = 0; g < groups; ++g) {
    int row_of[kBoundaries] = {0, 1, 2};  // boundary b's row of big_phi
    for (int r = 0; r < SideProfiles::kRows; ++r) row_of[3 + r] = 3 + g * SideProfiles::kRows + r;
    // Region levels: S3, S2, S1, then the border L0 and rows 1..kRows, each L0 + (L1 - L0) * other.
    double other[kRegions] = {0, 0, 0, 0};
    for (int r = 0; r < SideProfiles::kRows; ++r) other[4 + r] = s.other_sum[g][r] / s.rays[g];
    double level[kRegions];
    level[1] = levels == 1 ? p[kS1] : p[kS2], level[2] = p[kS1];
    level[0] = levels == 3 ? p[kS3] : level[1];
    for (int k = 3; k < kRegions; ++k) level[k] = p[kL0] + (p[kL1] - p[kL0]) * other[k];
    for (int j = 0; j < n; ++j) {
      const double w = s.count[g * n + j];
      if (w <= 0) continue;
      double f = 0, indicator[kRegions] = {}, gamma_grad = 0;
      const int first = levels == 3 ? 0 : 1;  // region 0 is empty without a further step
      for (int k = first; k < kRegions; ++k) {
        const double upper = k == first ? 1.0 : big_phi[static_cast<size_t>(row_of[k - 1]) * n + j];
        const double lower = k == kRegions - 1 ? 0.0 : big_phi[static_cast<size_t>(row_of[k]) * n + j];
        indicator[k] = upper - lower;
        f += level[k] * indicator[k];
      }
      double scale = 1.0;  // d encoded / d linear
      if (s.fit_gamma) {   // encoded: 255 exp(log(f / 255) / gamma), one log and one exp
        // Below 0.5 (no log of 0) the curve continues along its tangent there: a clip would hold the
        // model at 0.5 where an image's black is 0, push the dark level below 0 and with it the edge
        // towards the dark side (0.09 px on a sharp printed sheet).
        const double at = std::max(f, 0.5), log_lin = std::log(at * (1.0 / 255.0));
        const double enc = 255.0 * std::exp(log_lin * inv_gamma);
        scale = enc * inv_gamma / at;
        gamma_grad = -enc * log_lin * inv_gamma * inv_gamma;
        if (f < at) {
          gamma_grad += (gamma_grad * inv_gamma / at - scale * inv_gamma) * (f - at);
          f = enc + scale * (f - at);
        } else {
          f = enc;
        }
      }
      const double r = f - s.sum[g * n + j] / w;
      cost += w * r * r;
      if (bin_residual) (*bin_residual)[2 * j] += w * r, (*bin_residual)[2 * j + 1] += w;
      if (!jtj) continue;
      Vector<N> grad = Vector<N>::Zero();
      double grad_q2 = 0, grad_s3 = 0;
      for (int b = levels == 3 ? 0 : 1; b < kBoundaries; ++b) {
        const size_t i = static_cast<size_t>(row_of[b]) * n + j;
        const double d = (level[b + 1] - level[b]) * small_phi[i] * inv_sigma;  // d f / d bound_b
        grad[kE] += d;
        grad[kSigma] -= d * zs[i];
        if (b <= 1) grad[kQ] += d;
        if (b == 0) grad_q2 += d;
      }
      (levels == 3 ? grad_s3 : grad[levels == 2 ? kS2 : kS1]) += indicator[0];
      grad[levels == 1 ? kS1 : kS2] += indicator[1], grad[kS1] += indicator[2];
      for (int k = 3; k < kRegions; ++k)
        grad[kL0] += (1.0 - other[k]) * indicator[k], grad[kL1] += other[k] * indicator[k];
      if constexpr (N > kQ2) grad[kS3] = grad_s3, grad[kQ2] = grad_q2;
      grad *= scale;
      grad[kGamma] = gamma_grad;
      *jtj += w * grad * grad.transpose();
      *jtr += w * r * grad;
    }
  }
  return cost;
}

// Mean of the groups' profiles at the bin nearest u, over the groups whose row `row` (0: the border;
// 1..: code rows; -1: any) has colour `colour`.
double LevelNear(const SideProfiles& s, double u, int row, int colour) {
  const int j = std::clamp(static_cast<int>(std::lround((u - s.u0) / s.du)), 0, s.bins - 1);
  double sum = 0, count = 0;
  for (size_t g = 0; g < s.patterns.size(); ++g) {
    if (row >= 1 && s.patterns[g][row - 1] != colour) continue;
    sum += s.sum[g * s.bins + j];
    count += s.count[g * s.bins + j];
  }
  return count > 0 ? sum / count : NAN;
}

// The damped Gauss-Newton step from p that stays within [lo, hi]: a parameter whose step would cross
// its bound is held at the bound and the others are solved again (a plain clamp after the solve would
// leave the free parameters compensating for a move that did not happen, and the fit crawls along the
// bound for many iterations).
template <int N>
Vector<N> BoundedStep(const Normal<N>& a, const Vector<N>& jtr, const double* p, const double* lo,
                      const double* hi) {
  bool fixed[N] = {};
  Vector<N> held = Vector<N>::Zero(), step;
  for (int round = 0; round < 4; ++round) {
    Normal<N> m = a;
    Vector<N> rhs = -jtr;
    for (int k = 0; k < N; ++k) {
      if (!fixed[k]) continue;
      rhs -= a.col(k) * held[k];
      m.row(k).setZero(), m.col(k).setZero(), m(k, k) = 1.0, rhs[k] = held[k];
    }
    step = m.ldlt().solve(rhs);
    bool changed = false;
    for (int k = 0; k < N; ++k) {
      if (fixed[k] || (p[k] + step[k] <= hi[k] && p[k] + step[k] >= lo[k])) continue;
      fixed[k] = changed = true;
      held[k] = std::clamp(p[k] + step[k], lo[k], hi[k]) - p[k];
    }
    if (!changed) break;
  }
  for (int k = 0; k < N; ++k) step[k] = std::clamp(p[k] + step[k], lo[k], hi[k]) - p[k];
  return step;
}

// Levenberg-Marquardt from p (within [lo, hi]) over the first N parameters of the model with `levels`
// surround levels (N = ParamsOf(levels)); p ends at the minimum found. Returns its cost.
template <int N>
double Minimize(const SideProfiles& s, int levels, double* p, const double* lo, const double* hi) {
  Normal<N> jtj;
  Vector<N> jtr;
  double cost = Evaluate<N>(s, p, levels, &jtj, &jtr);
  double lambda = 1e-3;
  // Converged when the next step would move the edge less than 5e-4 px and the blur less than 5e-3 px:
  // that step is taken without evaluating it (near the minimum the damped Gauss-Newton step does not
  // overshoot).
  bool done = false;
  for (int iter = 0; iter < 12 && !done; ++iter) {
    bool improved = false;
    for (int attempt = 0; attempt < 6 && !improved && !done; ++attempt) {
      Normal<N> a = jtj;
      for (int k = 0; k < N; ++k) a(k, k) += lambda * jtj(k, k) + 1e-9;
      const Vector<N> step = BoundedStep<N>(a, jtr, p, lo, hi);
      double q[kParams];
      std::copy(p, p + kParams, q);
      for (int k = 0; k < N; ++k) q[k] = p[k] + step(k);
      if (attempt == 0 && std::abs(step[kE]) < 5e-4 && std::abs(step[kSigma]) < 5e-3) {
        std::copy(q, q + N, p);
        done = true;
        break;
      }
      // The trial's normal equations come with its cost: kept when it is accepted.
      Normal<N> trial_jtj;
      Vector<N> trial_jtr;
      const double trial = Evaluate<N>(s, q, levels, &trial_jtj, &trial_jtr);
      if (trial < cost) {
        std::copy(q, q + N, p);
        cost = trial;
        jtj = trial_jtj, jtr = trial_jtr;
        lambda = std::max(1e-7, lambda * 0.3);
        improved = true;
      } else {
        lambda *= 10;
      }
    }
    if (!improved) break;
  }
  return cost;
}

// One fit; `hold_gamma`: gamma held at the profiles' gamma_hint where the side shows no code contrast.
bool FitOnce(const SideProfiles& s, bool hold_gamma, int levels, SideFit* fit, bool* code_contrast_out) {
  if (s.bins < 6 || s.patterns.empty() || !(s.cell > 0)) return false;
  const double c = s.cell;
  double p[kParams];
  p[kE] = 0.0;
  p[kSigma] = fit->sigma > 0.15 ? fit->sigma : 0.7;
  p[kL0] = LevelNear(s, -0.5 * c, -1, 0);
  p[kL1] = LevelNear(s, -1.5 * c, 1, 1);
  if (!std::isfinite(p[kL1])) p[kL1] = LevelNear(s, -2.5 * c, 2, 1);
  if (!std::isfinite(p[kL1])) p[kL1] = LevelNear(s, -3.5 * c, 3, 1);
  p[kS1] = LevelNear(s, std::min(0.5 * c, 1.0), -1, 0);
  p[kS2] = LevelNear(s, s.u0 + (s.bins - 1) * s.du, -1, 0);
  p[kQ] = c;
  p[kGamma] = 1.0;
  p[kS3] = p[kS2], p[kQ2] = 2.0 * c;
  if (!std::isfinite(p[kL0]) || !std::isfinite(p[kS1]) || !std::isfinite(p[kS2])) return false;
  if (!std::isfinite(p[kL1])) p[kL1] = p[kS1];  // no code cell of the other colour here
  if (fit->warm) {
    std::copy(fit->params.begin(), fit->params.end(), p);
    p[kE] = fit->e;
    if (!s.fit_gamma) p[kGamma] = 1.0;
  }
  // Bounds: blur and margin width within what the profiles can show, levels within the 8-bit range
  // (with some room for noise: a level far outside it is a valley of the fit, e.g. a code level and
  // the gamma traded for each other on small cells, not a solution).
  double lo[kParams], hi[kParams];
  lo[kE] = -c, hi[kE] = c;
  lo[kSigma] = 0.15, hi[kSigma] = 4.0;
  for (int k : {kL0, kL1, kS1, kS2}) lo[k] = -20.0, hi[k] = 275.0;
  // Margins from a fifth of a cell (0.4 before: a 0.3-cell margin could not be modelled, its corners
  // sat 0.03 px further inward on the reference renderer's "hard" condition).
  lo[kQ] = 0.2 * c, hi[kQ] = 4.0 * c;
  lo[kS3] = -20.0, hi[kS3] = 275.0;
  // A further step at least half a cell beyond the margin (nearer, the two are one blurred step).
  lo[kQ2] = 0.5 * c, hi[kQ2] = 6.0 * c;
  // Gamma is free only where the side shows the code's level next to the border's (SideProfiles::gamma_hint).
  // A row's boundary with the border counts where the profiles reach it (within 2 px of their inner end).
  bool code_contrast = false;
  for (size_t g = 0; g < s.patterns.size(); ++g)
    for (int r = 0; r < SideProfiles::kRows; ++r)
      code_contrast = code_contrast || ((r + 1) * c < 2.0 - s.u0 &&
                                        (s.patterns[g][r] != 0 || s.other_sum[g][r] > 0.05 * s.rays[g]));
  *code_contrast_out = code_contrast;
  const bool free_gamma = s.fit_gamma && !s.hold_gamma && (code_contrast || !hold_gamma);
  const double held_gamma = s.fit_gamma ? std::clamp(s.gamma_hint, 0.4, 3.5) : 1.0;
  lo[kGamma] = free_gamma ? 0.4 : held_gamma, hi[kGamma] = free_gamma ? 3.5 : held_gamma;
  if (s.edge_only && fit->warm)
    for (int k = 0; k < kParams; ++k)
      if (k != kE) lo[k] = hi[k] = p[k];
  for (int k = 0; k < kParams; ++k) p[k] = std::clamp(p[k], lo[k], hi[k]);
  // Parameters not in the model are held.
  if (levels < 3) lo[kS3] = hi[kS3] = p[kS3], lo[kQ2] = hi[kQ2] = p[kQ2];
  if (levels < 2) lo[kS2] = hi[kS2] = p[kS2], lo[kQ] = hi[kQ] = p[kQ];
  const double cost =
      levels == 3 ? Minimize<ParamsOf(3)>(s, levels, p, lo, hi) : Minimize<ParamsOf(2)>(s, levels, p, lo, hi);
  const double contrast = std::abs(p[kL1] - p[kL0]);
  if (!std::isfinite(p[kE]) || contrast < 5.0) return false;
  if (std::abs(p[kE]) > 0.75 * c) {
    fit->beyond = true, fit->beyond_e = p[kE];
    return false;
  }
  fit->e = p[kE];
  fit->sigma = p[kSigma];
  fit->contrast = contrast;
  fit->gamma = p[kGamma];
  fit->gamma_fitted = free_gamma;
  fit->cost = cost;
  std::copy(p, p + kParams, fit->params.begin());
  return true;
}

// One surround model (`levels` beyond the edge, Evaluate) with gamma fitted freely; on a side without
// code contrast a gamma at its bound is the valley of a single step (SideProfiles::gamma_hint), and the
// side is fitted again with the hint.
bool FitSurround(const SideProfiles& s, int levels, SideFit* fit, bool* code_contrast) {
  const SideFit start = *fit;
  const bool ok = FitOnce(s, false, levels, fit, code_contrast);
  if (*code_contrast || !s.fit_gamma || (ok && fit->gamma > 0.41 && fit->gamma < 3.49)) return ok;
  *fit = start;
  return FitOnce(s, true, levels, fit, code_contrast);
}

// A margin fit (`fit`, two surround levels) fitted again with a further surround step beyond the
// margin (a narrow face beyond the print's margin, then the object's edge, within the blur's reach of
// the profiles: the margin fit trades the margin's level and width, and with them the edge, against it).
// Tried only where the margin fit shows a margin and leaves a residual beyond the margin's far side;
// kept (fit->further_step) where it lowers the residual clearly.
void FitFurtherStep(const SideProfiles& s, SideFit* fit, bool* code_contrast) {
  const double* q = fit->params.data();
  const double end = s.u0 + (s.bins - 1) * s.du;
  if (std::abs(q[kS2] - q[kS1]) < kMinFurtherMarginContrast * fit->contrast ||
      q[kQ] < kMinFurtherMargin * s.cell || q[kE] + q[kQ] + q[kSigma] > end)
    return;
  thread_local std::vector<double> residual;
  Evaluate<ParamsOf(2)>(s, q, 2, nullptr, nullptr, &residual);
  double outer = 0;  // the largest mean residual beyond the margin's far side
  for (int j = 0; j < s.bins; ++j)
    if (s.u0 + j * s.du > q[kE] + q[kQ] && residual[2 * j + 1] > 0)
      outer = std::max(outer, std::abs(residual[2 * j] / residual[2 * j + 1]));
  if (outer < kFurtherStepResidual * fit->contrast) return;
  SideFit further = *fit;
  double* p = further.params.data();
  // The step started at the profiles' outer end, its level from the last bin (half way between S2 and S3).
  p[kQ2] = std::max(0.5 * s.cell, end - p[kE] - p[kQ]);
  const double last = LevelNear(s, end, -1, 0);
  p[kS3] = std::isfinite(last) ? 2.0 * last - p[kS2] : p[kS2];
  further.warm = true;
  if (!FitSurround(s, 3, &further, code_contrast) ||
      std::abs(p[kS3] - p[kS2]) < kMinFurtherStepContrast * further.contrast ||
      !(further.cost < kFurtherStepGain * fit->cost))
    return;
  *fit = further;
  fit->further_step = true;
}

// The two-step surround model, refitted with one surround level where its margin has the border's level.
// `code_contrast`: the side shows the code's level next to the border's.
bool FitSideModels(const SideProfiles& s, SideFit* fit, bool* code_contrast_out) {
  const SideFit start = *fit;
  // A side fitted with one surround level, or with a further step, in the previous pass stays so
  // (warm-started). A cold fit with a margin tries the further step (FitFurtherStep).
  bool& code_contrast = *code_contrast_out;
  code_contrast = true;
  if (start.warm && start.single_surround) return FitSurround(s, 1, fit, &code_contrast);
  if (start.warm && start.further_step) return FitSurround(s, 3, fit, &code_contrast);
  bool ok = FitSurround(s, 2, fit, &code_contrast);
  fit->single_surround = fit->further_step = false;
  if (!ok) return false;
  // A margin of nearly the border's level is no margin that could be printed (it would be border):
  // the fit has moved the edge inward into the border and let the "margin" make up the step, a valley
  // where the marker has no margin. The side is fitted again with one surround level.
  // Only where the side shows the code's level next to the border's (without, L1 is free).
  const double* p = fit->params.data();
  if (!code_contrast || std::abs(p[kS1] - p[kL0]) >= kMinMarginContrast * std::abs(p[kL1] - p[kL0]))
    return start.warm || (FitFurtherStep(s, fit, &code_contrast), true);
  *fit = start;
  fit->warm = false;
  ok = FitSurround(s, 1, fit, &code_contrast);
  fit->single_surround = ok;
  return ok;
}

}  // namespace

bool FitSideProfiles(const SideProfiles& s, SideFit* fit) {
  fit->wrong_polarity = fit->beyond = false;
  bool code_contrast = true;
  if (s.edge_only)
    return fit->warm && FitOnce(s, true,
                                fit->single_surround ? 1
                                : fit->further_step  ? 3
                                                     : 2,
                                fit, &code_contrast);
  const bool ok = FitSideModels(s, fit, &code_contrast);
  // Without code contrast in the modelled rows the code's level L1 is free: no polarity to check.
  if (!ok || s.polarity == 0 || !code_contrast) return ok;
  // The border's level on the wrong side of the code's (the border darker than the other colour for
  // polarity +1): the fit took the first code row for the border.
  const double* p = fit->params.data();
  fit->wrong_polarity = (p[kL1] - p[kL0]) * s.polarity < 0;
  return !fit->wrong_polarity;
}

}  // namespace mcmt
