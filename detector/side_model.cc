#include "detector/side_model.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>
#ifdef __SSE2__
#include <emmintrin.h>
#endif
// The AVX2 code (side_model_lanes.inc): GCC on x86-64, its functions compiled for AVX2 by #pragma GCC target
// and run only where the CPU has it (no -mavx2: the binaries run on any x86-64).
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define MCMT_SIDE_HAS_AVX2 1
#include <immintrin.h>
#else
#define MCMT_SIDE_HAS_AVX2 0
#endif

#include "detector/cpu.h"

namespace mcmt {

void SideProfiles::Reset(double u0_, double du_, int bins_, double cell_) {
  u0 = u0_, du = du_, bins = bins_, cell = cell_;
  fit_gamma = false;
  gamma_hint = 1.0;
  hold_gamma = false;
  polarity = 0;
  edge_only = false;
  paper = 0;
  patterns.clear();
  sum.reserve(static_cast<size_t>(16) * bins);
  count.reserve(static_cast<size_t>(16) * bins);
  sum.clear();
  count.clear();
  depth_sum.clear();
  other_sum.clear();
  rays.clear();
  row_steps.clear();
  first_step.clear();
  steps.clear();
}

int SideProfiles::AddRay(const std::array<uint8_t, kRows>& pattern, const std::array<double, kRows>& depths,
                         const std::array<double, kRows>& other, const RowStep* ray_steps,
                         int ray_step_count) {
  size_t g = 0;
  // A ray with steps is a group of its own; the others group by pattern among the groups without steps.
  // (The patterns compared element by element: std::array's != called memcmp for its two bytes.)
  auto same_pattern = [&](const std::array<uint8_t, kRows>& p) {
    for (int r = 0; r < kRows; ++r)
      if (p[r] != pattern[r]) return false;
    return true;
  };
  if (ray_step_count == 0)
    while (g < patterns.size() && (!same_pattern(patterns[g]) || steps[g] > 0)) ++g;
  else
    g = patterns.size();
  if (g == patterns.size()) {
    patterns.push_back(pattern);
    sum.resize(sum.size() + bins, 0.0);
    count.resize(count.size() + bins, 0.0);
    depth_sum.push_back({});
    other_sum.push_back({});
    rays.push_back(0);
    first_step.push_back(static_cast<int>(row_steps.size()));
    steps.push_back(ray_step_count);
    row_steps.insert(row_steps.end(), ray_steps, ray_steps + ray_step_count);
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
// A margin narrower than half a cell whose excess over the surround, times its width, is below this
// fraction of a cell times the code-to-surround contrast is no print's margin either: a faint strip at the
// width's bound (0.2 cell) that pairs with a per-side gamma off the image's (0.8-0.9 on linear renders) and
// moves the edge outward on markers without a margin (FitSideModels). The narrowest margin a print has is
// paper over the surround (excess 1) about 0.3 cell wide (the reference renderer's "hard"), 0.3 of a cell;
// the fitted products of real margins under blur, shading and sharpening stay above 0.1 but for a few
// sides of "hard" (5 of 2871 two-level fits of its map). On the no-margin map 0.04 left 166 strips at the
// width's bound with products 0.04-0.1 (+0.10..0.15 px outward each, a fifth of the map's -0.215 %):
// bench/results/2026-12-06-nomargin.md.
constexpr double kMinMarginExcess = 0.1;
// The fitted levels' bounds: the 8-bit range with some room for noise (FitOnce).
constexpr double kLevelMin = -20.0, kLevelMax = 275.0;
// A fitted level within half a grey level of its bound is at the bound: the fit ran into it (a valley, not a
// measured level).
bool LevelInsideBounds(double level) { return level > kLevelMin + 0.5 && level < kLevelMax - 0.5; }
bool LevelsInsideBounds(const double* p) {  // L0, L1, S1 and S2 of a fit's parameters
  for (int k : {kL0, kL1, kS1, kS2})
    if (!LevelInsideBounds(p[k])) return false;
  return true;
}
// A margin fitted narrower than this (cells; its bound is 0.2) is at its narrowest (FitSideModels).
constexpr double kHaloMaxCells = 0.25;
// A paper margin's far side counts as beyond the profiles' outer end (FitSideModels' `unseen`) only where
// it lies this many fitted blurs beyond it: closer, its step still darkens the last bins by Phi(-z) of its
// contrast (16 % at z = 1, 2.3 % at z = 2), which one surround level cannot follow.
constexpr double kUnseenSigmas = 2.0;
// ... where the margin is paper: its level within this fraction of the border-to-code contrast of the
// code's other colour (a normal print's paper). With 0.6 the probe's webcam marker (seed 31, image 5, id
// 129) was refined 2.07 px apart from two starts (main 0.44; bench/results/2026-12-07-widemargin.md).
constexpr double kPaperMarginContrast = 0.25;
// ... and only on cells at least this deep (px along the side's normal): on cells about a pixel deep the
// profiles fix a margin's area but not its width and level apart (SideProfiles::paper), and the two-level
// fit of a 0.3-cell margin over a light surface (the reference renderer's "hard", seed 51 image 4 id 96,
// side cell 1.29 px) slid to a 2.7-cell "paper" margin whose far step 0.4 px beyond the end took any level
// (S2 36-90): the marker was refined 0.105 px apart from two starts (bound 0.1; main 0.0003).
constexpr double kPaperReachMinCell = 1.5;

using Normal = Eigen::Matrix<double, kParams, kParams>;
using Vector = Eigen::Matrix<double, kParams, 1>;

static_assert(kParams == 8, "CholeskyLower factorises 8 x 8 normal matrices");
static_assert(kQ == 6, "SideFit::margin_width() reads params[kQ] as params[6]");

}  // namespace

// Eigen::LLT's factorisation (its unblocked algorithm, Eigen 3.4) by its operations in their
// order, without its calls per column (a dynamic-size matrix-vector product each) and its L1 norm: the
// same L in the lower triangle, to the bit (SideModel.CholeskyIsEigens). False where LLT reports a
// numerical issue (a pivot not above 0). For each column k:
//   L_kk = sqrt(A_kk - sum_j<k L_kj^2),   L_ik = (A_ik - sum_j<k L_ij L_kj) / L_kk  (i > k),
// each sum from j = 0 up (Eigen: the squared norm's sum from the first term, the product's from 0).
// In bench_detector's 10 accurate frames LLT took 5.45 M instructions (3.11 M of them in those products);
// FitOnce with this 100.31 -> 96.08 M (refcost).
// With SSE2 the column's rows i > k two at a time (Eigen's storage is column-major: rows i and i + 1 of
// a column are adjacent), each lane by the operations of one row: the same values. bench_detector's 10
// accurate frames: CholeskyLower 3.08 -> 1.23 M instructions (with the outer loop unrolled; fitcost).
bool CholeskyLower(Eigen::Matrix<double, 8, 8>* a) {
  Eigen::Matrix<double, 8, 8>& m = *a;
  static_assert(!Eigen::Matrix<double, 8, 8>::IsRowMajor, "columns are contiguous");
#ifdef __SSE2__
  double* const data = m.data();  // (i, j) at data[i + 8 j]
#endif
#pragma GCC unroll 8
  for (int k = 0; k < 8; ++k) {
    double x = m(k, k);
    if (k > 0) {
      double norm = m(k, 0) * m(k, 0);
      for (int j = 1; j < k; ++j) norm += m(k, j) * m(k, j);
      x -= norm;
    }
    if (x <= 0.0) return false;
    m(k, k) = x = std::sqrt(x);
    int i = k + 1;
#ifdef __SSE2__
    for (; i + 1 < 8; i += 2) {
      __m128d column = _mm_loadu_pd(data + i + 8 * k);
      if (k > 0) {
        __m128d dot = _mm_setzero_pd();
        for (int j = 0; j < k; ++j)
          dot = _mm_add_pd(dot, _mm_mul_pd(_mm_loadu_pd(data + i + 8 * j), _mm_set1_pd(data[k + 8 * j])));
        column = _mm_sub_pd(column, dot);
      }
      _mm_storeu_pd(data + i + 8 * k, _mm_div_pd(column, _mm_set1_pd(x)));
    }
#endif
    for (; i < 8; ++i) {
      if (k > 0) {
        double dot = 0.0;
        for (int j = 0; j < k; ++j) dot += m(i, j) * m(k, j);
        m(i, k) -= dot;
      }
      m(i, k) /= x;
    }
  }
  return true;
}

namespace {

// ExpInline and LogInline: detector/exp_log.h.

// Whether group g has a step (SideProfiles::RowStep) in code row `row`.
bool HasRowStep(const SideProfiles& s, int g, int row) {
  for (int k = s.first_step[g]; k < s.first_step[g] + s.steps[g]; ++k)
    if (s.row_steps[k].row == row) return true;
  return false;
}

// The margin's width's lower bound in cells (FitOnce).
constexpr double kMinMarginCells = 0.2;

// The margin's penalty (SideProfiles::paper) counts as this many observations of the paper's level per
// ray.
constexpr double kPaperWeightPerRay = 1.0;

// The paper's level P (SideProfiles::paper) in the model's linear units at gamma p[kGamma]:
// P_lin = 255 (P / 255)^gamma where the profiles are encoded.
double LinearPaper(const SideProfiles& s, const double* p) {
  return s.fit_gamma ? 255.0 * PowInline(s.paper / 255.0, p[kGamma]) : s.paper;
}

// The two-level model's margin tied to the paper (SideProfiles::paper): a soft penalty on a margin level
// off the paper's instead of a fixed level, so that no fit switches between models (a switch taken in one
// pass and not in another left fast mode's corners 0.09 px from the accurate mode's). The residual
//   h = W (S1 - P_lin(gamma)),   W = sqrt(kPaperWeightPerRay * rays) G,
// (d h / d S1 = W, d h / d gamma = -W P_lin ln(P / 255)), G the weight of the fit's start (MarginWeight):
// held through the fit, so that the fit cannot escape the penalty by shrinking the margin (a gate on the
// fitted margin's area let it do so: the stronger the penalty, the smaller the black tool's gain).
// Two-sided: the profiles fix a narrow bright margin's centre and area q (S1 - S2), and its level and
// width trade along a valley (a margin fitted too bright is too narrow, its near edge e outward by about
// half the width's error). A penalty on S1 below the paper only (h = W min(0, S1 - P_lin)) clipped the
// lower half of S1's scatter and kept the upper: S1 median +0.043 of the contrast above the paper, 15 %
// of the sides at the level's bound, margins 0.47 cell for 0.5, the sides +0.030 px outward and the
// clean markers +0.27 % too large on a half-cell margin over dark grey (bench/results/2026-12-06-darkmap.md).
// Returns h; its gradient in the parameters into `grad`.
double MarginPenalty(const SideProfiles& s, const double* p, bool single, double weight, double* grad) {
  std::fill(grad, grad + kParams, 0.0);
  if (single || !(weight > 0)) return 0.0;
  const double paper = LinearPaper(s, p);
  grad[kS1] = weight;
  if (s.fit_gamma) grad[kGamma] = -weight * paper * LogInline(s.paper / 255.0);
  return weight * (p[kS1] - paper);
}

// A margin wider than this (cells) whose level is paper already is tied to the paper whatever its excess
// over the surround and whatever lies beyond it (MarginWeight's `wide_tie`; issue 15, twocell / twocell2:
// bench/results/2026-12-07-twocell2.md). A wide margin over a light surround (the reference renderer's
// white 2-cell margin, surround 0.8 of the paper) has a small excess over the surround, so the area gate
// below left its level free, and its far step lies near the profiles' end (1.6 cells + 1 px): its level and
// width traded (brighter and narrower or dimmer and wider) and the edge with them. Tied: the reference
// 2-cell maps 1.0 / 1.3 m -0.077 / -0.120 -> -0.062 / -0.067 %, mcmt-sim's 2-cell paper margin 1.0 / 1.3 m
// -0.023 / -0.074 -> +0.014 / -0.019 %. Only where the start's margin level is within kPaperMarginContrast
// of the code's other colour: without that condition a spurious wide margin of a marker without one (no
// margin on grey, seed 1 image 6 id 201 of the accuracy bench) was tied and its corners moved 0.6-0.9 px.
constexpr double kWideTieCells = 1.5;

// MarginPenalty's W for a fit starting from p (the last factor 1 with SideProfiles::tie_paper):
//   G = SmoothStep(a, 0.1, 0.2) (1 - SmoothStep(q / c, 2.5, 3.5)) (1 - SmoothStep(b, 0.1, 0.2)),
//   a = q (S1 - S2) / (c (P_lin - L0)),   b = (S2 - L0) / (P_lin - L0),
// by the margin's area a (width times excess over the surround, as a part of a cell times the paper's
// contrast to the border: what the profiles fix even on cells a pixel deep, 0.5 for a half-cell margin,
// near 0 on markers without one, whose fits must not get a paper strip), by its width (a "margin" wider
// than 2.5 cells is the surface's far edge or texture, and its level is seen, not slid) and by the level
// b of the surround beyond it (the penalty only where the surface is near the border's black: with a
// grey surface the free fit's margin level is the paper's on the median, and a one-sided penalty clipped
// the lower half of its scatter and moved mcmt-sim's 1-cell margins' edges outward; gate,
// bench/results/2026-12-06-gate.md). 0 on other prints or without the paper's level.
// With `wide_tie` a paper margin wider than kWideTieCells gets the larger of G and (1 - SmoothStep(q /
// c, 2.5, 3.5)) (`*wide_tied` true where the latter is larger).
double MarginWeight(const SideProfiles& s, const double* p, bool wide_tie, bool* wide_tied) {
  *wide_tied = false;
  if (s.polarity <= 0 || !(s.paper > 0)) return 0.0;
  const double contrast = LinearPaper(s, p) - p[kL0];
  if (!(contrast > 0)) return 0.0;
  double rays = 0;
  for (int n : s.rays) rays += n;
  const double c = s.cell, a = p[kQ] * (p[kS1] - p[kS2]) / (c * contrast);
  const double b = (p[kS2] - p[kL0]) / contrast;
  const double width_gate = 1.0 - SmoothStep(p[kQ] / c, 2.5, 3.5);
  const double gate = SmoothStep(a, 0.1, 0.2) * width_gate;
  // With SideProfiles::tie_paper the margin is paper whatever lies beyond it.
  const double surround_gate = s.tie_paper ? 1.0 : 1.0 - SmoothStep(b, 0.1, 0.2);
  if (wide_tie && p[kQ] > kWideTieCells * c &&
      std::abs(p[kS1] - p[kL1]) < kPaperMarginContrast * std::abs(p[kL1] - p[kL0]) &&
      width_gate > gate * surround_gate) {
    *wide_tied = true;
    return std::sqrt(kPaperWeightPerRay * rays) * width_gate;
  }
  return std::sqrt(kPaperWeightPerRay * rays) * gate * surround_gate;
}

// Group g's region levels: S2, S1, then the border L0 and rows 1..kRows, each L0 + (L1 - L0) * other,
// `other` the share of the row's cells of the other colour than the border's along the group's rays.
void RegionLevels(const SideProfiles& s, const double* p, bool single, int g, double* other, double* level) {
  other[0] = other[1] = other[2] = 0;
  for (int r = 0; r < SideProfiles::kRows; ++r) other[3 + r] = s.other_sum[g][r] / s.rays[g];
  level[0] = single ? p[kS1] : p[kS2], level[1] = p[kS1];
  for (int k = 2; k < kRegions; ++k) level[k] = p[kL0] + (p[kL1] - p[kL0]) * other[k];
}

// The margin's penalty h (MarginPenalty) added to the normal equations: J^T J += g g^T, J^T r += h g.
void AddPenalty(double penalty, const double* penalty_grad, Normal* jtj, Vector* jtr) {
  if (penalty_grad[kS1] == 0) return;  // no penalty on this fit (MarginPenalty)
  const Vector g = Eigen::Map<const Vector>(penalty_grad);
  *jtj += g * g.transpose(), *jtr += penalty * g;
}

// The side model's evaluation (side_model_lanes.inc) as SSE2 code, and on x86-64 with GCC also as AVX2
// code chosen at run time (DetectorUsesAvx2): the same values to the bit.
#define MCMT_SIDE_AVX2 0
namespace sse2 {
#include "detector/side_model_lanes.inc"
}  // namespace sse2
#undef MCMT_SIDE_AVX2
#if MCMT_SIDE_HAS_AVX2
#pragma GCC push_options
#pragma GCC target("avx2")
#define MCMT_SIDE_AVX2 1
namespace avx2 {
#include "detector/side_model_lanes.inc"
}  // namespace avx2
#undef MCMT_SIDE_AVX2
#pragma GCC pop_options
#endif

// `reject_from`: an LM trial's cost to beat (NaN: none). Once the cost reaches it, Evaluate returns that
// partial cost (not below reject_from) without the later groups and the normal equations; jtj and jtr are
// then left as they were. A trial's cost is otherwise the same to the bit.
double Evaluate(const SideProfiles& s, const double* p, bool single, double margin_weight, Normal* jtj,
                Vector* jtr, double reject_from = NAN) {
#if MCMT_SIDE_HAS_AVX2
  if (DetectorUsesAvx2()) return avx2::Evaluate(s, p, single, margin_weight, jtj, jtr, reject_from);
#endif
  return sse2::Evaluate(s, p, single, margin_weight, jtj, jtr, reject_from);
}

}  // namespace

double EvaluateSideModel(const SideProfiles& s, const std::array<double, 8>& p, bool single,
                         double margin_weight, Eigen::Matrix<double, 8, 8>* jtj,
                         Eigen::Matrix<double, 8, 1>* jtr) {
  return Evaluate(s, p.data(), single, margin_weight, jtj, jtr);
}

void FillBoundary(const SideProfiles& s, double bound, double inv_sigma, double step_ratio, double* zs,
                  double* big_phi, double* small_phi) {
#if MCMT_SIDE_HAS_AVX2
  if (DetectorUsesAvx2())
    return avx2::FillBoundaryLanes(s, bound, inv_sigma, step_ratio, zs, big_phi, small_phi);
#endif
  sse2::FillBoundaryLanes(s, bound, inv_sigma, step_ratio, zs, big_phi, small_phi);
}

namespace {

// The samples of bin j over the groups whose row `row` (0: the border; 1..kRows: code rows; -1: any) has
// colour `colour`: their sum and their count.
void BinSamples(const SideProfiles& s, int j, double* sum, double* count, int row = -1, int colour = 0) {
  assert(row <= SideProfiles::kRows);  // the patterns hold rows 1..kRows
  *sum = 0, *count = 0;
  for (size_t g = 0; g < s.patterns.size(); ++g) {
    if (row >= 1 && s.patterns[g][row - 1] != colour) continue;
    *sum += s.sum[g * s.bins + j];
    *count += s.count[g * s.bins + j];
  }
}

// Mean of the groups' profiles at the bin nearest u, over the groups whose row `row` (0: the border;
// 1..kRows: code rows; -1: any) has colour `colour`.
double LevelNear(const SideProfiles& s, double u, int row, int colour) {
  const int j = std::clamp(static_cast<int>(std::lround((u - s.u0) / s.du)), 0, s.bins - 1);
  double sum, count;
  BinSamples(s, j, &sum, &count, row, colour);
  return count > 0 ? sum / count : NAN;
}

// The solution of L L^T x = rhs for CholeskyLower's L (its lower triangle), as Eigen::LLT::solve.
Vector SolveCholesky(const Normal& l, const Vector& rhs) {
  Vector x = rhs;
  l.triangularView<Eigen::Lower>().solveInPlace(x);
  l.adjoint().triangularView<Eigen::Upper>().solveInPlace(x);
  return x;
}

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
    // The damped normal matrix is positive definite: Cholesky (LDLT where it is not, numerically).
    Normal l = m;
    step = CholeskyLower(&l) ? SolveCholesky(l, rhs) : Vector(m.ldlt().solve(rhs));
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

// One fit; `hold_gamma`: gamma held at the profiles' gamma_hint where the side shows no code contrast;
// `wide_tie`, `*wide_tied`: MarginWeight's.
bool FitOnce(const SideProfiles& s, bool hold_gamma, bool single, bool wide_tie, SideFit* fit,
             bool* code_contrast_out, bool* wide_tied) {
  *wide_tied = false;
  if (s.bins < 6 || s.patterns.empty() || !(s.cell > 0)) return false;
  const double c = s.cell;
  double p[kParams];
  p[kE] = 0.0;
  p[kSigma] = fit->sigma > 0.15 ? fit->sigma : 0.7;
  p[kL0] = LevelNear(s, -0.5 * c, -1, 0);
  p[kL1] = LevelNear(s, -1.5 * c, 1, 1);
  if (!std::isfinite(p[kL1])) p[kL1] = LevelNear(s, -2.5 * c, 2, 1);
  p[kS1] = LevelNear(s, std::min(0.5 * c, 1.0), -1, 0);
  p[kS2] = LevelNear(s, s.OuterU(), -1, 0);
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
  for (int k : {kL0, kL1, kS1, kS2}) lo[k] = kLevelMin, hi[k] = kLevelMax;
  // Margins from a fifth of a cell (0.4 before: a 0.3-cell margin could not be modelled, its corners
  // sat 0.03 px further inward on the reference renderer's "hard" condition).
  lo[kQ] = kMinMarginCells * c, hi[kQ] = 4.0 * c;
  // Gamma is free only where the side shows the code's level next to the border's (SideProfiles::gamma_hint).
  // A row's boundary with the border counts where the profiles reach it (within 2 px of their inner end).
  bool code_contrast = false;
  for (size_t g = 0; g < s.patterns.size(); ++g)
    for (int r = 0; r < SideProfiles::kRows; ++r)
      code_contrast = code_contrast || ((r + 1) * c < 2.0 - s.u0 &&
                                        (s.patterns[g][r] != 0 || s.other_sum[g][r] > 0.05 * s.rays[g] ||
                                         HasRowStep(s, static_cast<int>(g), r + 1)));
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
  const double margin_weight = MarginWeight(s, p, wide_tie, wide_tied);
  double cost = Evaluate(s, p, single, margin_weight, &jtj, &jtr);
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
      // The trial's normal equations come with its cost: kept when it is accepted (a trial whose cost
      // reaches the current one stops there: rejected, no normal equations).
      Normal trial_jtj;
      Vector trial_jtr;
      const double trial = Evaluate(s, q, single, margin_weight, &trial_jtj, &trial_jtr, cost);
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
// side is fitted again with the hint. `wide_tie`, `*wide_tied`: MarginWeight's (of the last fit).
bool FitSurround(const SideProfiles& s, bool single, bool wide_tie, SideFit* fit, bool* code_contrast,
                 bool* wide_tied) {
  const SideFit start = *fit;
  const bool ok = FitOnce(s, false, single, wide_tie, fit, code_contrast, wide_tied);
  if (*code_contrast || !s.fit_gamma || (ok && fit->gamma > 0.41 && fit->gamma < 3.49)) return ok;
  *fit = start;
  return FitOnce(s, true, single, wide_tie, fit, code_contrast, wide_tied);
}

// The two-step surround model, refitted with one surround level where its margin has the border's level.
// `code_contrast`: the side shows the code's level next to the border's. `wide_tie`: MarginWeight's.
bool FitSideModels(const SideProfiles& s, bool wide_tie, SideFit* fit, bool* code_contrast_out) {
  const SideFit start = *fit;
  // A side fitted with one surround level in the previous pass stays so (warm-started).
  bool& code_contrast = *code_contrast_out;
  code_contrast = true;
  bool wide_tied = false;
  if (start.warm && start.single_surround)
    return FitSurround(s, true, wide_tie, fit, &code_contrast, &wide_tied);
  bool ok = FitSurround(s, false, wide_tie, fit, &code_contrast, &wide_tied);
  fit->single_surround = false;
  if (!ok) return false;
  // A margin of nearly the border's level is no margin that could be printed (it would be border):
  // the fit has moved the edge inward into the border and let the "margin" make up the step, a valley
  // where the marker has no margin. The side is fitted again with one surround level.
  // Only where the side shows the code's level next to the border's (without, L1 is free).
  // Nor is a faint strip beyond the edge (kMinMarginExcess); that side is fitted with one level in this
  // pass only, and the next pass fits both models again (kept warm, the choice depended on the start: fast
  // mode's corners left the accurate mode's by 0.47 px on a marker without a margin).
  // Nor is a margin whose far side (e + q) lies beyond the profiles' outer end: S2 has no bin there, and
  // where the margin has the surround's level (no margin) q and S2 wander between valleys (no margin on
  // grey, 25.6 px at 71 deg: q 1.9 or 7.5 px, S2 88 or -20 by the start; with blurside3's row-3 terms fast
  // mode's corners were 0.21 px from the accurate mode's, bench/results/2026-12-05-blurside3.md). On main
  // it took the reference renderer's "hard" map from +0.96 to +0.68 % (BENCHMARKS.md, 2026-12-05 evening).
  const double* p = fit->params.data();
  const bool faint = p[kQ] < 0.5 * s.cell && p[kQ] * std::abs(p[kS1] - p[kS2]) <
                                                 kMinMarginExcess * s.cell * std::abs(p[kL1] - p[kS2]);
  // A paper margin (kPaperMarginContrast) on cells of kPaperReachMinCell px or more whose levels all lie
  // within their bounds counts only kUnseenSigmas blurs beyond the end: its far side just past the end still
  // darkens the last bins, and the one-level refit of such wide paper margins (sticky for the later passes)
  // lowered its level and moved the edge outward (3-cell margins: 87 % of sides single; reference renderer,
  // blur 1.2, 15-22 px, 3-cell margin +0.042 -> +0.024 px, WidePaperMarginsDoNotMoveCornersOutward; its
  // map with margin_cells=3 -0.138 -> -0.040 %). A level at its bound is a valley (as for `halo`): without
  // that condition "hard"'s id 96 (above) moved 0.064 px with its start; without the cell's depth 0.108 px.
  // The cell's depth costs the plain 3-cell map its gain (-0.060 %, -0.007 without it): its sides lie on
  // cells under 1.5 px (bench/results/2026-12-07-margin2.md).
  const bool levels_inside = LevelsInsideBounds(p);
  const bool paper_reach = s.cell >= kPaperReachMinCell && levels_inside &&
                           std::abs(p[kS1] - p[kL1]) < kPaperMarginContrast * std::abs(p[kL1] - p[kL0]);
  const bool unseen = p[kE] + p[kQ] > s.OuterU() + (paper_reach ? kUnseenSigmas * p[kSigma] : 0.0);
  // Nor is a strip at the margin's narrowest (kHaloMaxCells) whose level lies beyond the border's, away
  // from the code's, at the level's bound (darker than black for a normal print): a print's margin is
  // paper, or surround of any level but then not a strip of a fifth of a cell. It is the edge's own
  // undershoot (sharpening, a gamma off the side's), and its valley lies half a cell inside the edge of
  // the one-level fit: the model-only rounds' cold fits (RefineMarkerCorners) alternated between the two
  // for ever, 1.25 px apart, and the corners depended on the start by 1.42 px (hard,
  // bench/results/2026-12-06-onevalley.md; without the level's bound the rule moved the no-margin map
  // -0.205 -> -0.222 %).
  const bool halo = p[kQ] < kHaloMaxCells * s.cell && (p[kS1] - p[kL0]) * (p[kL1] - p[kL0]) < 0 &&
                    !LevelInsideBounds(p[kS1]);
  if (!code_contrast || (!faint && !unseen && !halo &&
                         std::abs(p[kS1] - p[kL0]) >= kMinMarginContrast * std::abs(p[kL1] - p[kL0])))
    return true;
  // A wide margin tied to the paper (kWideTieCells) whose far side the tie took beyond the reach is fitted
  // again from the same start without that tie, and that fit's own checks decide. On mcmt-sim's 3-cell paper
  // margin under blur 1.2 px (cells 1.6-2 px, blur 0.7 cell) the paper read on the code cells lies about 3 %
  // of the contrast below the margin's level; tied to it, the margin's far step (3 cells out, beyond the
  // reach) left its tail in the last bins to a margin ever wider (q at its bound of 4 cells, S2 below its
  // bound), and a third of the tied fits became `unseen`: their one-level refit lay 0.11 px outward of the
  // tied fit and stayed for the later passes (that map -0.342 -> -0.419 %; with this refit -0.287 %).
  if (wide_tied && unseen) {
    *fit = start;
    return FitSideModels(s, false, fit, code_contrast_out);
  }
  *fit = start;
  fit->warm = false;
  ok = FitSurround(s, true, wide_tie, fit, &code_contrast, &wide_tied);
  fit->single_surround = ok && !faint;
  return ok;
}

}  // namespace

bool EdgeHasStep(const SideProfiles& s, const SideFit& fit) {
  const double c = s.cell;
  const double border = LevelNear(s, fit.e - 0.5 * c, -1, 0), beyond = LevelNear(s, fit.e + 0.25 * c, -1, 0);
  double code = LevelNear(s, fit.e - 1.5 * c, 1, 1);
  if (!std::isfinite(code)) code = LevelNear(s, fit.e - 2.5 * c, 2, 1);
  if (s.polarity == 0 || !std::isfinite(border) || !std::isfinite(beyond) || !std::isfinite(code))
    return true;
  return (beyond - border) * s.polarity >= kMinEdgeStep * std::abs(code - border);
}

double MarginExcessOverPaper(const SideProfiles& s, const SideFit& fit) {
  if (!(s.paper > 0)) return NAN;
  const double* p = fit.params.data();
  const double paper = LinearPaper(s, p), contrast = paper - p[kL0];
  return contrast > 0 ? (p[kS1] - paper) / contrast : NAN;
}

double SecondStepBeyondMargin(const SideProfiles& s, const SideFit& fit) {
  if (fit.single_surround || s.polarity <= 0 || s.bins < 2 || !(s.cell < kSecondStepMaxCell)) return NAN;
  const double* p = fit.params.data();
  // A margin at its width's bound (within a thousandth of a cell) and not far brighter than the paper.
  if (p[kQ] < (kMinMarginCells + 0.001) * s.cell &&
      !(MarginExcessOverPaper(s, fit) >= kSecondStepCollapsedExcess))
    return NAN;
  const double sign = p[kS1] > p[kS2] ? 1.0 : -1.0;  // towards the margin's level
  auto bin_of = [&](double u) {
    return std::clamp(static_cast<int>(std::ceil((u - s.u0) / s.du)), 0, s.bins - 1);
  };
  // sign times the profiles' mean over groups at bin j (NaN without samples there).
  auto level = [&](int j) {
    double sum, count;
    BinSamples(s, j, &sum, &count);
    return count > 0 ? sign * sum / count : NAN;
  };
  double peak = -HUGE_VAL;
  for (int j = bin_of(fit.e); j <= bin_of(fit.e + p[kQ]); ++j) peak = std::max(peak, level(j));
  int dip = -1;
  double dip_level = HUGE_VAL, back = -HUGE_VAL;
  for (int j = bin_of(fit.e + p[kQ] + p[kSigma]); j < s.bins; ++j) {
    const double v = level(j);
    if (!std::isfinite(v)) continue;
    if (v < dip_level) dip = j, dip_level = v, back = -HUGE_VAL;
    back = std::max(back, v);
  }
  const double dip_u = s.u0 + dip * s.du - fit.e;
  if (dip < 0 || dip_u > kSecondStepMaxDip * s.cell || !(peak > dip_level) ||
      !(back - dip_level >= kSecondStepRise * (peak - dip_level)))
    return NAN;
  return dip_u;
}

// DetrendSurround: the fit's surround part at u, in the profiles' units,
//   f(u) = enc(S2 + (S1 - S2) Phi((e + q - u) / sigma) + (L0 - S1) Phi((e - u) / sigma)),
// enc the fitted gamma's encoding (none unless fit_gamma): the blurred margin's and the edge's tails over the
// far level S2. The plateau is the bins j with u_j >= a = e + q + kDetrendStartSigmas sigma; each bin's
// residual r_j = (sum over groups of the bin's samples) / (their count) - f(u_j), its weight w_j that count.
// The weighted least-squares line r = m + b (u - a) gives
//   b = sum w (x - x_mean)(r - r_mean) / sum w (x - x_mean)^2,  x = u - a,
// and every group's bin j of the plateau loses b (u_j - a) per sample (sum -= count b (u_j - a)): the
// plateau's level at a is kept, its slope taken off. No significance test: a third level's tail over the
// last 3-4 bins is not significant on one side, but it is systematic over many (shade3's variants C, D).
bool DetrendSurround(SideProfiles* s, SideFit* fit) {
  // The slope taken off fades from cells of kDetrendFullCellPx to kDetrendMaxCellPx, so that a marker whose
  // cells lie near the limit does not have the rule switch on and off between passes as its quad moves.
  const double weight = 1.0 - SmoothStep(s->cell, kDetrendFullCellPx, kDetrendMaxCellPx);
  if (s->edge_only || !(weight > 0) || fit->single_surround || s->bins < 6) return false;
  const double* p = fit->params.data();
  if (!LevelsInsideBounds(p)) return false;
  const double start = p[kE] + p[kQ] + kDetrendStartSigmas * p[kSigma];
  const int first = std::max(0, static_cast<int>(std::ceil((start - s->u0) / s->du)));
  const int n = s->bins - first;
  if (n < kDetrendMinBins) return false;
  const double inv_sigma = 1.0 / p[kSigma];
  double sw = 0, swx = 0, swr = 0, swxx = 0, swxr = 0;
  int used = 0;  // bins with samples
  for (int j = first; j < s->bins; ++j) {
    double sum, count;
    BinSamples(*s, j, &sum, &count);
    if (!(count > 0)) continue;
    const double u = s->u0 + j * s->du, x = u - start;
    double far_side, edge, density;
    PhiAndDensity((p[kE] + p[kQ] - u) * inv_sigma, &far_side, &density);
    PhiAndDensity((p[kE] - u) * inv_sigma, &edge, &density);
    double f = p[kS2] + (p[kS1] - p[kS2]) * far_side + (p[kL0] - p[kS1]) * edge;
    if (s->fit_gamma) f = 255.0 * PowInline(std::max(f, 0.5) / 255.0, 1.0 / p[kGamma]);
    const double r = sum / count - f;
    sw += count, swx += count * x, swr += count * r, swxx += count * x * x, swxr += count * x * r;
    ++used;
  }
  if (used < kDetrendMinBins) return false;
  const double sxx = swxx - swx * swx / sw, sxr = swxr - swx * swr / sw;
  if (!(sxx > 0)) return false;
  const double slope = weight * sxr / sxx;
  // The plateau's sums as they were, for a refit that fails: the profiles must stay those *fit was fitted
  // to (SecondStepBeyondMargin and the next passes read them against it).
  thread_local std::vector<double> kept;
  kept.clear();
  for (size_t g = 0; g < s->patterns.size(); ++g)
    for (int j = first; j < s->bins; ++j) {
      const size_t k = g * s->bins + j;
      kept.push_back(s->sum[k]);
      s->sum[k] -= s->count[k] * slope * (s->u0 + j * s->du - start);
    }
  SideFit again = *fit;
  again.warm = true;
  if (!FitSideProfiles(*s, &again)) {
    size_t i = 0;
    for (size_t g = 0; g < s->patterns.size(); ++g)
      for (int j = first; j < s->bins; ++j) s->sum[g * s->bins + j] = kept[i++];
    return false;
  }
  *fit = again;
  return true;
}

bool FitSideProfiles(const SideProfiles& s, SideFit* fit) {
  fit->wrong_polarity = fit->beyond = false;
  bool code_contrast = true;
  bool wide_tied = false;
  if (s.edge_only)
    return fit->warm && FitOnce(s, true, fit->single_surround, true, fit, &code_contrast, &wide_tied);
  const bool ok = FitSideModels(s, true, fit, &code_contrast);
  // Without code contrast in the modelled rows the code's level L1 is free: no polarity to check.
  if (!ok || s.polarity == 0 || !code_contrast) return ok;
  // The border's level on the wrong side of the code's (the border darker than the other colour for
  // polarity +1): the fit took the first code row for the border.
  const double* p = fit->params.data();
  fit->wrong_polarity = (p[kL1] - p[kL0]) * s.polarity < 0;
  return !fit->wrong_polarity;
}

}  // namespace mcmt
