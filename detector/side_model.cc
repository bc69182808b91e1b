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

constexpr int kBoundaries = SideProfiles::kRows + 2;  // margin's far side, outer edge, kRows inner
constexpr int kRegions = kBoundaries + 1;
enum Param { kE, kSigma, kL0, kL1, kS1, kS2, kQ, kGamma, kParams };
// A margin differs from the border's level by at least this fraction of the border-to-code contrast
// (a print's margin is paper or ink of the other colour; FitSideProfiles).
constexpr double kMinMarginContrast = 0.4;

// Model values, and with `jtj` / `jtr` the normal equations, for parameters p. Returns the weighted
// squared residual sum.
double Evaluate(const SideProfiles& s, const double* p, bool single,
                Eigen::Matrix<double, kParams, kParams>* jtj, Eigen::Matrix<double, kParams, 1>* jtr) {
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
  fill(0, p[kE] + p[kQ]);
  fill(1, p[kE]);
  for (int g = 0; g < groups; ++g)
    for (int r = 0; r < SideProfiles::kRows; ++r)
      fill(2 + g * SideProfiles::kRows + r, p[kE] - s.depth_sum[g][r] / s.rays[g]);
  if (jtj) jtj->setZero(), jtr->setZero();
  double cost = 0;
  for (int g = 0; g < groups; ++g) {
    int row_of[kBoundaries] = {0, 1};  // boundary b's row of big_phi
    for (int r = 0; r < SideProfiles::kRows; ++r) row_of[2 + r] = 2 + g * SideProfiles::kRows + r;
    // Region levels: S2, S1, then the border L0 and rows 1..kRows, each L0 + (L1 - L0) * other.
    double other[kRegions] = {0, 0, 0};
    for (int r = 0; r < SideProfiles::kRows; ++r) other[3 + r] = s.other_sum[g][r] / s.rays[g];
    double level[kRegions];
    level[0] = single ? p[kS1] : p[kS2], level[1] = p[kS1];
    for (int k = 2; k < kRegions; ++k) level[k] = p[kL0] + (p[kL1] - p[kL0]) * other[k];
    for (int j = 0; j < n; ++j) {
      const double w = s.count[g * n + j];
      if (w <= 0) continue;
      double f = 0, indicator[kRegions], gamma_grad = 0;
      for (int k = 0; k < kRegions; ++k) {
        const double upper = k == 0 ? 1.0 : big_phi[static_cast<size_t>(row_of[k - 1]) * n + j];
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
      if (!jtj) continue;
      Eigen::Matrix<double, kParams, 1> grad = Eigen::Matrix<double, kParams, 1>::Zero();
      for (int b = 0; b < kBoundaries; ++b) {
        const size_t i = static_cast<size_t>(row_of[b]) * n + j;
        const double d = (level[b + 1] - level[b]) * small_phi[i] * inv_sigma;  // d f / d bound_b
        grad[kE] += d;
        grad[kSigma] -= d * zs[i];
        if (b == 0) grad[kQ] += d;
      }
      grad[single ? kS1 : kS2] += indicator[0], grad[kS1] += indicator[1];
      for (int k = 2; k < kRegions; ++k)
        grad[kL0] += (1.0 - other[k]) * indicator[k], grad[kL1] += other[k] * indicator[k];
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

using Normal = Eigen::Matrix<double, kParams, kParams>;
using Vector = Eigen::Matrix<double, kParams, 1>;

// The damped Gauss-Newton step from p that stays within [lo, hi]: a parameter whose step would cross
// its bound is held at the bound and the others are solved again (a plain clamp after the solve would
// leave the free parameters compensating for a move that did not happen, and the fit crawls along the
// bound for many iterations).
Vector BoundedStep(const Normal& a, const Vector& jtr, const double* p, const double* lo, const double* hi) {
  bool fixed[kParams] = {};
  Vector held = Vector::Zero(), step;
  for (int round = 0; round < 4; ++round) {
    Normal m = a;
    Vector rhs = -jtr;
    for (int k = 0; k < kParams; ++k) {
      if (!fixed[k]) continue;
      rhs -= a.col(k) * held[k];
      m.row(k).setZero(), m.col(k).setZero(), m(k, k) = 1.0, rhs[k] = held[k];
    }
    step = m.ldlt().solve(rhs);
    bool changed = false;
    for (int k = 0; k < kParams; ++k) {
      if (fixed[k] || (p[k] + step[k] <= hi[k] && p[k] + step[k] >= lo[k])) continue;
      fixed[k] = changed = true;
      held[k] = std::clamp(p[k] + step[k], lo[k], hi[k]) - p[k];
    }
    if (!changed) break;
  }
  for (int k = 0; k < kParams; ++k) step[k] = std::clamp(p[k] + step[k], lo[k], hi[k]) - p[k];
  return step;
}

// One fit; `hold_gamma`: gamma held at the profiles' gamma_hint where the side shows no code contrast.
bool FitOnce(const SideProfiles& s, bool hold_gamma, bool single, SideFit* fit, bool* code_contrast_out) {
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
  if (single) lo[kS2] = hi[kS2] = p[kS2], lo[kQ] = hi[kQ] = p[kQ];  // not in the model: held
  Normal jtj;
  Vector jtr;
  double cost = Evaluate(s, p, single, &jtj, &jtr);
  double lambda = 1e-3;
  // Converged when the next step would move the edge less than 5e-4 px and the blur less than 5e-3 px:
  // that step is taken without evaluating it (near the minimum the damped Gauss-Newton step does not
  // overshoot).
  bool done = false;
  for (int iter = 0; iter < 12 && !done; ++iter) {
    bool improved = false;
    for (int attempt = 0; attempt < 6 && !improved && !done; ++attempt) {
      Normal a = jtj;
      for (int k = 0; k < kParams; ++k) a(k, k) += lambda * jtj(k, k) + 1e-9;
      const Vector step = BoundedStep(a, jtr, p, lo, hi);
      double q[kParams];
      for (int k = 0; k < kParams; ++k) q[k] = p[k] + step(k);
      if (attempt == 0 && std::abs(step[kE]) < 5e-4 && std::abs(step[kSigma]) < 5e-3) {
        std::copy(q, q + kParams, p);
        done = true;
        break;
      }
      // The trial's normal equations come with its cost: kept when it is accepted.
      Normal trial_jtj;
      Vector trial_jtr;
      const double trial = Evaluate(s, q, single, &trial_jtj, &trial_jtr);
      if (trial < cost) {
        std::copy(q, q + kParams, p);
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
  std::copy(p, p + kParams, fit->params.begin());
  return true;
}

// One surround model (`single`: one level beyond the edge) with gamma fitted freely; on a side without
// code contrast a gamma at its bound is the valley of a single step (SideProfiles::gamma_hint), and the
// side is fitted again with the hint.
bool FitSurround(const SideProfiles& s, bool single, SideFit* fit, bool* code_contrast) {
  const SideFit start = *fit;
  const bool ok = FitOnce(s, false, single, fit, code_contrast);
  if (*code_contrast || !s.fit_gamma || (ok && fit->gamma > 0.41 && fit->gamma < 3.49)) return ok;
  *fit = start;
  return FitOnce(s, true, single, fit, code_contrast);
}

// The two-step surround model, refitted with one surround level where its margin has the border's level.
// `code_contrast`: the side shows the code's level next to the border's.
bool FitSideModels(const SideProfiles& s, SideFit* fit, bool* code_contrast_out) {
  const SideFit start = *fit;
  // A side fitted with one surround level in the previous pass stays so (warm-started).
  bool& code_contrast = *code_contrast_out;
  code_contrast = true;
  if (start.warm && start.single_surround) return FitSurround(s, true, fit, &code_contrast);
  bool ok = FitSurround(s, false, fit, &code_contrast);
  fit->single_surround = false;
  if (!ok) return false;
  // A margin of nearly the border's level is no margin that could be printed (it would be border):
  // the fit has moved the edge inward into the border and let the "margin" make up the step, a valley
  // where the marker has no margin. The side is fitted again with one surround level.
  // Only where the side shows the code's level next to the border's (without, L1 is free).
  const double* p = fit->params.data();
  if (!code_contrast || std::abs(p[kS1] - p[kL0]) >= kMinMarginContrast * std::abs(p[kL1] - p[kL0]))
    return true;
  *fit = start;
  fit->warm = false;
  ok = FitSurround(s, true, fit, &code_contrast);
  fit->single_surround = ok;
  return ok;
}

}  // namespace

bool FitSideProfiles(const SideProfiles& s, SideFit* fit) {
  fit->wrong_polarity = fit->beyond = false;
  bool code_contrast = true;
  if (s.edge_only) return fit->warm && FitOnce(s, true, fit->single_surround, fit, &code_contrast);
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
