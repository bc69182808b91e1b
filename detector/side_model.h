// The profile model of one side of a decoded marker, fitted to locate its outer edge without assuming
// anything about what surrounds the marker.
//
// Once a marker is decoded every cell of it is known. Across one side (u: signed distance from the
// current line estimate, outward), the image is, in linear light, a sum of blurred steps:
//   f(u) = sum over regions k of level_k * [Phi((B_{k-1} - u) / sigma) - Phi((B_k - u) / sigma)]
// with the region boundaries, from outside in,
//   B_0 = e + q   (far side of the margin: level S2 beyond, S1 between; both free, q free),
//   B_1 = e       (the outer edge: the unknown we want),
//   B_{1+r} = e - r c  (r = 1..kRows: the boundaries between the border (row 0) and the code rows
//                       1..kRows, c = the depth of one cell here, known from the marker's geometry).
// The rows' levels are the border's colour L0 or the other colour L1 as the code says at each place
// along the side: the profiles are averaged per pattern of the rows (a group), and all groups share
// e, sigma, L0, L1, S1, S2, q. The inner boundaries are edges known on both sides; the outer edge
// brings its own evidence with its surround's levels estimated, not assumed; the blur sigma is fitted.
// A fitted margin level S1 near the border's L0 is no margin a print can have (it would be border):
// that fit has slid the edge into the border (on markers without a margin, about 0.5 px inward), and
// the side is fitted again with one surround level (S2 = S1, no q).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>
#ifdef __SSE2__
#include <emmintrin.h>
#endif

#include "detector/exp_log.h"

namespace mcmt {

struct SideProfiles {
  static constexpr int kRows = 2;  // code rows modelled inside the border
  double u0 = 0, du = 0.25;        // bin j is at u = u0 + j * du
  int bins = 0;
  double OuterU() const { return u0 + (bins - 1) * du; }  // the last bin's u: the profiles' outer end
  // Encoded images (gamma unknown): the model's linear values are encoded as 255 (f / 255)^(1 / gamma)
  // with gamma fitted too; false: the profiles are linear already.
  bool fit_gamma = false;
  // With fit_gamma, the gamma used where this side cannot show it: when no code cell of the other colour
  // lies in the modelled rows (a code row of the border's colour along the whole side), the profile is
  // one step between two free levels, and gamma, blur and edge trade for each other (a sharp edge
  // moved half a pixel with gamma at its bound). The caller gives the marker's other sides' estimate.
  double gamma_hint = 1.0;
  // With fit_gamma: gamma is the camera's, known, and held at gamma_hint on every side (not fitted).
  bool hold_gamma = false;
  double cell = 0;  // mean depth of one cell across this side, px
  // The marker's polarity: +1 the border is darker than the code's other colour (a normal print), -1
  // brighter (inverted), 0 unknown. A fit of the other polarity has taken a code row for the border (the
  // profiles lie about a cell inside the edge) and is rejected (SideFit::wrong_polarity).
  int polarity = 0;
  // Only the edge e is fitted; every other parameter is held at the warm start's (SideFit::params): the
  // edge of a part of the side (its direction, FitSide in detector.cc) with the whole side's levels,
  // blur, margin and gamma.
  bool edge_only = false;
  // The paper's level in the profiles' units (encoded where fit_gamma: the model takes it to linear light
  // with its gamma), measured on the marker's code cells (PaperLevel in detector.cc); 0: unknown. A printed
  // margin is paper: on cells about a pixel deep the profiles fix a narrow margin's area (its width times its
  // excess over the surround) but not its level and width apart, and free fits slide to a margin too wide and
  // too dim (the edge inward). Where the surface beyond the margin is near the border's black, the
  // two-level model's margin level is then tied to the paper's by a soft two-sided penalty (MarginPenalty
  // and MarginWeight in side_model.cc).
  double paper = 0;
  // The margin's level is tied to the paper's (MarginWeight in side_model.cc) whatever the level beyond it:
  // set where the profiles show a second step beyond the margin (SecondStepBeyondMargin), so that the
  // surround beyond the margin is not one level and its fitted level says nothing about the margin's.
  bool tie_paper = false;
  // Per group: the colour (0: border's, 1: other) of rows 1..kRows, the summed profile / counts, and
  // the summed depths (px inward from the outer edge) of the boundaries between rows r-1 and r
  // (r = 1..kRows: perspective makes them differ along a side and from row to row) and their count.
  std::vector<std::array<uint8_t, kRows>> patterns;
  std::vector<double> sum, count;  // group * bins + bin
  std::vector<std::array<double, kRows>> depth_sum;
  // Per group: the summed fractions of each row's level that is the other colour at the rays (blur
  // along the side mixes in the neighbouring columns' cells).
  std::vector<std::array<double, kRows>> other_sum;
  std::vector<int> rays;
  // A ray crossing a column boundary inside code row `row` (1..kRows) where the two cells differ has one
  // more blurred step there, `depth` px inward from its origin (as the rows' depths), the level changing
  // by delta (L1 - L0) (delta +1 / -1) until the row's inner boundary, its blur sigma * sigma_scale (the
  // ray crosses the column boundary obliquely; detector.cc AddRowSteps). A ray with steps is a group of
  // its own; its rows' `other` is then the colour where it enters the row.
  struct RowStep {
    int row;
    double depth, delta, sigma_scale;
  };
  static constexpr int kMaxRowSteps = 4;
  std::vector<RowStep> row_steps;
  std::vector<int> first_step, steps;  // per group: its steps' first index in row_steps, their count

  void Reset(double u0_, double du_, int bins_, double cell_);
  // The group of a pattern (created if new), with one more ray whose row boundaries lie at `depths`.
  int AddRay(const std::array<uint8_t, kRows>& pattern, const std::array<double, kRows>& depths,
             const std::array<double, kRows>& other, const RowStep* ray_steps = nullptr,
             int ray_step_count = 0);
  void Add(int group, int bin, double value) {
    sum[static_cast<size_t>(group) * bins + bin] += value;
    count[static_cast<size_t>(group) * bins + bin] += 1.0;
  }
};

struct SideFit {
  double e = 0;                  // outer edge, px outward from the line the profiles were sampled about
  double sigma = 0;              // blur, px
  double contrast = 0;           // |L1 - L0|
  double gamma = 1;              // fitted encoding gamma (1 unless fit_gamma)
  bool gamma_fitted = false;     // gamma was free (fit_gamma and the side shows code contrast)
  bool single_surround = false;  // fitted with one surround level (S1 = S2: no margin)
  bool wrong_polarity = false;   // the last fit failed only on SideProfiles::polarity
  // The last fit failed only because its edge lay beyond 0.75 cell from the profiles' line (at
  // `beyond_e`): the profiles are to be sampled about that edge again (FitSide in detector.cc).
  bool beyond = false;
  double beyond_e = 0;
  // SecondStepBeyondMargin of the last whole-side fit (FitWholeSide in detector.cc): px beyond `e`, or NaN.
  double second_step = NAN;
  // All parameters (e, sigma, L0, L1, S1, S2, q, gamma); `warm`: start from them (e relative to the
  // profiles' line as given in `e`) instead of from the profiles.
  std::array<double, 8> params{};
  bool warm = false;
  // The margin's width q (params[6]), px: where the margin's far side lies beyond the edge (held, not
  // fitted, where single_surround).
  double margin_width() const { return params[6]; }
};

// The profiles show a step at the fit's outer edge (fit.e about the profiles' line), of the marker's
// polarity: their level a quarter cell beyond the edge differs from the border's (half a cell inside) by
// at least kMinEdgeStep of the border-to-code contrast (the code's other colour a cell and a half inside),
// in the profiles' own units (blurred, so the step read is below the print's). A print's border meets
// paper or a surface of another level (no margin on grey: 0.38 of the contrast in the reflectances of
// the reference renderer); a fit without a step has taken a dark surround for the border and the margin
// beyond the true edge for a code row, its edge placed by nothing (half-cell margin on a black tool:
// 0.02 in reflectance; FitWholeSide in detector.cc). True where a level is missing or the polarity is
// unknown.
constexpr double kMinEdgeStep = 0.15;
bool EdgeHasStep(const SideProfiles& s, const SideFit& fit);

// A second step beyond the margin (issue 15, smallface: bench/results/2026-12-07-smallface.md). On a small
// face the marker and its margin nearly fill it: 1.25-1.5 cells of the face lie beyond a 1-cell margin
// before the face's edge, the next face, the body's top or the other marker's margin (mcmt-sim's pentagon,
// 11-15 px markers on cells of 1.4 px), all within the profiles' reach (1.6 cells + 1 px, 2.3 cells
// there). The model has one level beyond the margin; a step back towards the margin's level at the reach's
// end made the fitted margins narrow and bright (q 0.4-0.85 cell for 1, S1 186-255 for the paper's
// 163-174) and the edges +0.052 px outward (the pentagon's map -0.727 %).
// The profiles (mean over groups per bin) beyond the fitted margin's far side, from one fitted blur past
// it (e + q + sigma), have a dip (their extreme away from the margin's level), and after it they come back
// towards the margin's level by at least kSecondStepRise of the margin's excess over the dip (its peak
// between e and e + q). Returns the dip's u less e (px), or NaN where there is no such step, the fit has
// one surround level or the polarity is not a normal print's (and beyond the two bounds below).
constexpr double kSecondStepRise = 0.1;
// ... only on cells under this depth (px across the side): there the reach's 1 px is half a cell or more,
// 2.1 cells and more beyond the edge. On deeper cells it ends within 2.1 cells, and what passed the test
// there was no face's edge: sharpening's rebound, a texture (bench_accuracy --quick: hard -0.028 -> -0.040
// px, black tool +0.002 -> +0.006 without the gate).
constexpr double kSecondStepMaxCell = 2.0;
// ... and only where the dip lies within this many cells of the edge (a face ending at most about 1.5
// cells beyond a 1-cell margin, where the surround has no level of its own between the steps). The
// reference renderer's rig faces end 3 cells beyond the edge, their dips at 2.1-2.4 cells: there the rule
// took the brighter clutter's outward pull from the silhouette sides and not the darker clutter's inward
// one (its test sees only a step back towards the margin's level), and moved the plain map +0.047 ->
// +0.063 %, black tool +0.031 -> +0.049 % (with this bound +0.052, +0.036; the pentagon's sides keep
// their gain: its dips lie at 1.75-2.0 cells).
constexpr double kSecondStepMaxDip = 2.1;
// ... and not where the fit's margin lies at its width's lower bound (a fifth of a cell) with its level
// less than kSecondStepCollapsedExcess of the paper's contrast to the border above the paper's
// (MarginExcessOverPaper): that margin's far side is not measured, and the window "beyond" it starts inside
// the true margin's blurred fall (issue 15, stepfix: bench/results/2026-12-07-stepfix.md). On the
// reference renderer's wood (half-cell margin, grain) 67 % of the sides the rule fired on were such fits,
// their dip at 1.07 cells (median, within half a cell of the window's start) and their margin 0.32 above
// the paper: the profiles' fall to the grain's trough, not a step. Where a real second step pushes a
// margin to the bound it is pushed far past the paper: 0.83 (median; 10th percentile 0.65) on mcmt-sim's
// pentagon (15 % of its sides), 0.85 on its box (3 %).
constexpr double kSecondStepCollapsedExcess = 0.5;
double SecondStepBeyondMargin(const SideProfiles& s, const SideFit& fit);

// The surround's plateau detrended (issue 15, shade3 / shade3h: bench/results/2026-12-07-shade3.md,
// 2026-12-07-shade3h.md). A face's shade beyond the margin (a third level: mcmt-sim's face shading, the
// reference renderer's darker clutter) lies 1-1.5 cells beyond a 1-cell margin on small cells, its blurred
// tail within the profiles' reach; the model has one level beyond the margin, and the tail pulled the edge
// (mcmt-sim 1.3 m: +0.0075 px outward, +0.016 on cells of 1.0-1.5 px; exact profiles on 1.3 px cells, a
// brighter vs a darker face 2.5 cells out: 0.0185 px apart). After a successful two-level fit on cells under
// kDetrendMaxCellPx (the whole trend under kDetrendFullCellPx, fading between), the straight-line trend of
// the plateau's residuals (from kDetrendStartSigmas blurs beyond the margin's far side, at least
// kDetrendMinBins bins) is taken off the plateau's bins of every group, the level at the plateau's start
// kept, and the side is refitted warm: *fit is that refit where it succeeds (true). Not where a level of the
// fit lies at its bound: such a fit's margin is a valley, not a measured margin, and its plateau may hold the
// paper's own far side (without this condition the reference renderer's white two-cell margin lost a marker:
// each pass's warm fit kept S1 at 275 and each detrend took off a rise larger than the side's contrast;
// bench/results/2026-12-07-shade3h.md). Where the refit fails, *fit and the profiles are unchanged (false).
constexpr double kDetrendFullCellPx = 1.75, kDetrendMaxCellPx = 2.25;  // the trend's weight 1 -> 0 between
constexpr double kDetrendStartSigmas = 1.75;
constexpr int kDetrendMinBins = 3;
bool DetrendSurround(SideProfiles* s, SideFit* fit);

// The fitted margin's level above the paper's (SideProfiles::paper, linear at the fit's gamma), as a part
// of the paper's contrast to the border: (S1 - P_lin) / (P_lin - L0); NaN without the paper's level.
double MarginExcessOverPaper(const SideProfiles& s, const SideFit& fit);

// Where SecondStepBeyondMargin finds a step, the side is fitted again on the profiles ending before it
// (FitSide in detector.cc), first with the margin free. The margin is tied to the paper
// (SideProfiles::tie_paper) only where that fit's margin is still brighter than the paper by more than
// this part of the contrast (MarginExcessOverPaper): the step's brighter tail still pushes it. Elsewhere
// the free margin is the print's paper already and the tie moved the edge inward by nothing it measured
// (stepfix: the tie moved the refit's edges a further -0.022 px on the reference pentagon, -0.011 on
// mcmt-sim's box, -0.007 on wood, whatever the margin's level).
constexpr double kSecondStepTieExcess = 0.1;

// The standard normal distribution Phi(z) and density phi(z) given gauss = exp(-z^2 / 2): Abramowitz and
// Stegun 7.1.26 for erfc (absolute error below 1.5e-7 in Phi, far below the profiles' noise).
inline void PhiAndDensityOf(double z, double gauss, double* big, double* small) {
  const double x = std::abs(z) * M_SQRT1_2, t = 1.0 / (1.0 + 0.3275911 * x);
  const double tail =
      0.5 * t *
      (0.254829592 + t * (-0.284496736 + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429)))) * gauss;
  *big = z >= 0 ? 1.0 - tail : tail;
  *small = 0.3989422804014327 * gauss;
}

// The same with its one exponential (ExpInline: no libm call, the same value on every machine).
inline void PhiAndDensity(double z, double* big, double* small) {
  PhiAndDensityOf(z, ExpInline(-0.5 * z * z), big, small);
}

#ifdef __SSE2__
// PhiAndDensityOf at two points (z and gauss in lanes 0 and 1) into big[0..1], small[0..1], by its
// operations lane by lane: the same values (FillBoundary; SideModel.FillBoundaryIsBinByBins).
inline void PhiAndDensityOfTwo(__m128d z, __m128d gauss, double* big, double* small) {
  const __m128d one = _mm_set1_pd(1.0);
  const __m128d x = _mm_mul_pd(_mm_andnot_pd(_mm_set1_pd(-0.0), z), _mm_set1_pd(M_SQRT1_2));
  const __m128d t = _mm_div_pd(one, _mm_add_pd(one, _mm_mul_pd(_mm_set1_pd(0.3275911), x)));
  __m128d poly = _mm_add_pd(_mm_set1_pd(-1.453152027), _mm_mul_pd(t, _mm_set1_pd(1.061405429)));
  poly = _mm_add_pd(_mm_set1_pd(1.421413741), _mm_mul_pd(t, poly));
  poly = _mm_add_pd(_mm_set1_pd(-0.284496736), _mm_mul_pd(t, poly));
  poly = _mm_add_pd(_mm_set1_pd(0.254829592), _mm_mul_pd(t, poly));
  const __m128d tail = _mm_mul_pd(_mm_mul_pd(_mm_mul_pd(_mm_set1_pd(0.5), t), poly), gauss);
  const __m128d upper = _mm_cmpge_pd(z, _mm_setzero_pd());  // z >= 0 (false for NaN, as the scalar test)
  _mm_storeu_pd(big, _mm_or_pd(_mm_and_pd(upper, _mm_sub_pd(one, tail)), _mm_andnot_pd(upper, tail)));
  _mm_storeu_pd(small, _mm_mul_pd(_mm_set1_pd(0.3989422804014327), gauss));
}
#endif

// The side model's evaluation runs AVX2 code (four bins at a time) where the CPU has it: detector/cpu.h.

// Phi, phi and z of the boundary at `bound` at every bin of `s` (z = (bound - u) / sigma, `inv_sigma`:
// 1 / sigma, `step_ratio`: exp(-(du / sigma)^2)) into zs, big_phi and small_phi (s.bins each). The side
// model's evaluation (side_model.cc); declared here for its test.
void FillBoundary(const SideProfiles& s, double bound, double inv_sigma, double step_ratio, double* zs,
                  double* big_phi, double* small_phi);

// FitSideProfiles' evaluation at parameters p (e, sigma, L0, L1, S1, S2, q, gamma; `single`: one surround
// level S1, S2 and q unused), with the margin's penalty of weight `margin_weight`: the weighted squared
// residuals plus the penalty's square, and with jtj and jtr (both or neither) the normal equations J^T W J
// and J^T W r. Declared here for its test (SideModel.Avx2IsSse2).
double EvaluateSideModel(const SideProfiles& s, const std::array<double, 8>& p, bool single,
                         double margin_weight, Eigen::Matrix<double, 8, 8>* jtj,
                         Eigen::Matrix<double, 8, 1>* jtr);

// The Cholesky factor L (lower triangle of *a; the upper is left as it was) of the side model's 8 x 8
// normal matrices, as Eigen::LLT computes it, to the bit; false where LLT reports a numerical issue.
// Declared here for its test (side_model.cc).
bool CholeskyLower(Eigen::Matrix<double, 8, 8>* a);

// Least-squares fit (Levenberg-Marquardt) of the model above. `start` (optional) warm-starts e and
// sigma. Returns false when the fit fails, finds no contrast between the border and the code, or finds
// the border and code levels in the wrong order for SideProfiles::polarity (then fit->wrong_polarity).
bool FitSideProfiles(const SideProfiles& profiles, SideFit* fit);

// 3 t^2 - 2 t^3 of t = (x - from) / (to - from) clamped to [0, 1]: 0 below `from`, 1 above `to`.
inline double SmoothStep(double x, double from, double to) {
  const double t = std::clamp((x - from) / (to - from), 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

}  // namespace mcmt
