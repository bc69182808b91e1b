// The side model's fixed point on one (marker id, side) of an exactly known blurred print, without an
// image: the profiles are the continuous Gaussian-blurred pattern itself (closed form, as
// diag_side_bias's RenderExact), sampled along the rays the detector uses (CollectSideRays' choice of rays,
// grouping, depths and blur along the side), and fitted by FitSideProfiles. Prints the fitted edge (px,
// outward +; the truth is 0) and each group's residuals, so that a model term that does not match a
// blurred print shows apart from pixel sampling, the crossings' direction and the passes.
//   diag_side_exact ID SIDE BLUR_PX SIDE_PX
// Environment: LINE (px: the profiles' line moved outward), TILT (px per side length: the line turned,
// outward at the side's end), ALONG (px: blur along the side the model assumes; default BLUR_PX, with PIX and
// the pixel's spread), FITGAMMA (1), DUMP (print the profiles, the model and the residuals), PIX (1: the
// profiles bilinear samples of a point-sampled 8-bit image, roll ROLL deg and offset OFFX/OFFY px, as the
// detector samples images), CROSS (1: the line is the crossings' of the detector's model passes, about the
// true line, iterated with the model's offset: the detector's fixed point; prints the line's offset at the
// middle and tilt; clean rays and medians as CrossingLine), PAPER (SideProfiles::paper, 0), BOX (with PIX:
// each pixel the mean of BOX x BOX point samples of its square, the pixel's area as mcmt-sim renders it; 1:
// its centre), QUANT (with PIX, 1: rounded to 8 bits), INK / PAPERL / SURFACE / BG (the print's linear
// levels, 0-255), MARGIN / EXT (cells: the margin, and the surface beyond the marker's edge), ENDS (the first
// and last code columns with rays, 1 as the detector), ROWCAP (r: rows r and deeper from the side take row r
// - 1's colour, as the model's last row reaches inward without end), TRUTHSTART (1: the first fit
// warm-started at the print's own parameters). With DUMP also each ray's crossing about the true line, of the
// profiles and of the fitted model (`clean`: CleanNeighbour's). NODETREND (1: no DetrendSurround after the
// fit, which the detector's whole-side fits take on cells under 2 px). sharptent's
// (bench/results/2026-12-07-sharptent.md): NOTENT (with PIX, 1: each profile value the pixel's value read at
// the point itself, no pixel grid and no bilinear tent), PHASEAVG (with PIX, k: each profile value the mean
// over k x k pixel phases: the profiles convolved with the phase-averaged kernel, fitted once), RAYS (rays
// per cell along the side, 4), DU (the bin width's factor, 1), FRAC (the rays' least distance from their
// column's ends, part of a column: 0.1 as the detector), OTHEREXACT (with PIX, 1: the code rows' parts of
// the other colour read through the same pixels and bilinear reads as the profiles, not from a Gaussian
// along the side), SWEEP (a file of pixel phases: the fit
// averaged over ids, sides and phases per roll; at main()), SWEEPDUMP (1: each phase's mean too). motionmap's
// (bench/results/2026-12-07-motionmap.md): MOTION (px) / MOTIONDEG (deg from the side's outward normal, 0
// default: across the side): the print also blurred by a line of that length (the reference renderer's
// motion_px, a box kernel); ASPECT (below).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <unordered_map>
#include <vector>

#include "bench/detector/diag_support.h"
#include "core/dictionary.h"
#include "detector/side_model.h"

using namespace mcmt;

namespace {
using diag::Env;
using diag::Phi;

struct Print {
  cv::Mat bits;
  int cells = 8;
  double scale = 1.8;  // px per cell
  double sb = 0.5;     // blur, cells
  double margin = 1.0, ext = 3.5;
  double bg = 0.4 * 255, surface = 0.5 * 255, paper = 0.85 * 255, ink = 0.04 * 255;
  int side = 0, row_cap = 0;  // ROWCAP: rows from `side` this deep and deeper take row ROWCAP - 1's colour
  int Cell(int row, int col) const {  // 1: differs from the border (GridCell)
    if (row <= 0 || col <= 0 || row >= cells - 1 || col >= cells - 1) return 0;
    if (row_cap > 0) {
      const int depth = side == 0 ? row : side == 1 ? cells - 1 - col : side == 2 ? cells - 1 - row : col;
      if (depth >= row_cap) {  // row_cap - 1's colour (the model's last row reaches inward without end)
        const int k = row_cap - 1;
        const int r = side == 0 ? k : side == 2 ? cells - 1 - k : row;
        const int c = side == 1 ? cells - 1 - k : side == 3 ? k : col;
        return Cell(r, c);
      }
    }
    return bits.at<uint8_t>(row - 1, col - 1) ? 1 : 0;
  }
  double Rect(double x, double y, double x0, double y0, double x1, double y1) const {
    return (Phi((x1 - x) / sb) - Phi((x0 - x) / sb)) * (Phi((y1 - y) / sb) - Phi((y0 - y) / sb));
  }
  // MOTION: a line of motion_cells (cells) along (motion_x, motion_y), a unit vector, averaged at
  // motion_samples points (the reference renderer's motion blur, its line's bilinear splats aside).
  double motion_cells = 0, motion_x = 1, motion_y = 0;
  int motion_samples = 1;
  // Linear level at (x, y) (cells: x the column, y the row), with the motion line when MOTION is set.
  double At(double x, double y) const {
    if (motion_cells <= 0) return AtStill(x, y);
    double f = 0;
    for (int i = 0; i < motion_samples; ++i) {
      const double t = ((i + 0.5) / motion_samples - 0.5) * motion_cells;
      f += AtStill(x + t * motion_x, y + t * motion_y);
    }
    return f / motion_samples;
  }
  // Linear level at (x, y) (cells) of the still (Gaussian-blurred) print.
  double AtStill(double x, double y) const {
    double f = bg + (surface - bg) * Rect(x, y, -ext, -ext, cells + ext, cells + ext) +
               (paper - surface) * Rect(x, y, -margin, -margin, cells + margin, cells + margin) +
               (ink - paper) * Rect(x, y, 0, 0, cells, cells);
    for (int r = 1; r + 1 < cells; ++r)
      for (int c = 1; c + 1 < cells; ++c)
        if (Cell(r, c)) f += (paper - ink) * Rect(x, y, c, r, c + 1, r + 1);
    return f;
  }
};

// Side `side`'s start corner, direction along it and outward normal (cells), as UnitPoint.
void SideFrame(int side, int cells, double* p, double* a, double* n) {
  const double c = cells;
  const double table[4][6] = {
      {0, 0, 1, 0, 0, -1}, {c, 0, 0, 1, 1, 0}, {c, c, -1, 0, 0, 1}, {0, c, 0, -1, -1, 0}};
  p[0] = table[side][0], p[1] = table[side][1], a[0] = table[side][2], a[1] = table[side][3];
  n[0] = table[side][4], n[1] = table[side][5];
}

// InnerCell: row `row` inward of column `col` along side `side`.
int InnerCell(const Print& m, int side, int col, int row) {
  const int c = m.cells;
  switch (side) {
    case 0:
      return m.Cell(row, col);
    case 1:
      return m.Cell(col, c - 1 - row);
    case 2:
      return m.Cell(c - 1 - row, c - 1 - col);
    default:
      return m.Cell(c - 1 - col, row);
  }
}
}  // namespace

// One fit of side `side` of marker `id` (the program's arguments; the pixel phase offx / offy and the
// roll in deg as OFFX / OFFY / ROLL). Prints as before unless `quiet`; *e_out: the fitted edge (px,
// outward +). Returns the exit code (0: fitted).
int Run(const cv::Ptr<cv::aruco::Dictionary>& dict, int id, int side, double blur, double side_px,
        double offx, double offy, double roll_deg, bool quiet, double* e_out) {
  Print m;
  m.bits = cv::aruco::Dictionary::getBitsFromByteList(dict->bytesList.rowRange(id, id + 1), dict->markerSize);
  m.cells = dict->markerSize + 2;
  m.ink = Env("INK", m.ink), m.paper = Env("PAPERL", m.paper), m.surface = Env("SURFACE", m.surface);
  m.bg = Env("BG", m.bg), m.margin = Env("MARGIN", m.margin), m.ext = Env("EXT", m.ext);
  m.scale = side_px / m.cells, m.sb = blur / m.scale;
  m.side = side, m.row_cap = static_cast<int>(Env("ROWCAP", 0));
  const int cells = m.cells;
  double p0[2], a[2], nrm[2];
  SideFrame(side, cells, p0, a, nrm);
  // MOTION (px): the print blurred by a line of this length (a box kernel, as the reference renderer's
  // motion_px) at MOTIONDEG deg from the side's outward normal (0: across the side, 90: along it).
  if (const double motion_px = Env("MOTION", 0); motion_px > 0) {
    const double th = Env("MOTIONDEG", 0) * M_PI / 180;
    m.motion_cells = motion_px / m.scale;  // along: cells of the side's length; across: ASPECT's depth
    const double aspect = Env("ASPECT", 1.0);
    if (aspect != 1.0 && Env("MOTIONDEG", 0) != 0) {
      std::fprintf(stderr, "ASPECT with MOTIONDEG 0 only\n");
      return 2;
    }
    if (aspect != 1.0 && Env("PIX", 0) > 0) {
      std::fprintf(stderr, "ASPECT without PIX only\n");
      return 2;
    }
    m.motion_cells /= aspect;
    m.motion_x = std::cos(th) * nrm[0] + std::sin(th) * a[0];
    m.motion_y = std::cos(th) * nrm[1] + std::sin(th) * a[1];
    m.motion_samples = std::max(2, static_cast<int>(std::ceil(16 * motion_px)));
  }
  const double cell = m.scale;  // px, fronto-parallel
  // ASPECT (continuous profiles only): the cells' depth across the side this fraction of their length along
  // it (a foreshortened side: the print squeezed across the side, as at a view angle acos(ASPECT) about it).
  const double aspect = Env("ASPECT", 1.0), cell_across = cell * aspect;
  const double margin_t = std::min(0.3, std::max(0.6 * cell, 1.5) / side_px);
  // RAYS: rays per cell along the side (4 as the detector); DU: the bin width's factor (1: the detector's).
  const int n_rays = static_cast<int>(std::lround(Env("RAYS", 4) * cells));
  const double du = Env("DU", 1) * std::clamp(cell_across / 4.0, 0.1, 0.5);
  const double u0 = -(SideProfiles::kRows - 0.4) * cell_across;
  const int bins = static_cast<int>(std::ceil((1.6 * cell_across + 1.0 - u0) / du)) + 1;
  const bool pix = Env("PIX", 0) > 0;
  const double roll = roll_deg * M_PI / 180;
  const int box = std::max(1, static_cast<int>(Env("BOX", 1)));  // PIX: box x box samples per pixel
  const bool quant = Env("QUANT", 1) > 0;                        // PIX: rounded to 8 bits
  // sharptent's switches (bench/results/2026-12-07-sharptent.md), with PIX: NOTENT=1 the pixels' values
  // read at the point itself (its box's mean centred there, or the point sample with BOX=1: no bilinear
  // tent, no pixel grid); PHASEAVG=k each profile value the mean of k x k pixel phases (offx + i / k,
  // offy + j / k): the profiles convolved with the phase-averaged kernel, fitted once.
  const bool no_tent = Env("NOTENT", 0) > 0;
  const int phase_avg = std::max(1, static_cast<int>(Env("PHASEAVG", 1)));
  const double co = std::cos(roll), si = std::sin(roll);
  // Pixel values at one phase, cached: pixel (i, j) -> its centre sample or its box's mean, 8-bit.
  std::vector<std::unordered_map<int64_t, double>> cache(phase_avg * phase_avg);
  // Pixel (i, j)'s value of the image f (print coordinates, cells), unrounded.
  auto pixel_of = [&](const auto& f, double i, double j, double ox, double oy) {
    double sum = 0;
    for (int bj = 0; bj < box; ++bj)
      for (int bi = 0; bi < box; ++bi) {
        const double xx = i - ox + (bi + 0.5) / box - 0.5, yy = j - oy + (bj + 0.5) / box - 0.5;
        const double cx = (co * xx + si * yy) / m.scale, cy = (-si * xx + co * yy) / m.scale;
        sum += f(cx, cy);
      }
    return sum / (box * box);
  };
  auto pixel_at = [&](double i, double j, double ox, double oy) {
    const double v =
        std::clamp(pixel_of([&](double x, double y) { return m.At(x, y); }, i, j, ox, oy), 0.0, 255.0);
    return quant ? std::round(v) : v;
  };
  // The point at `along` (0..1) and `out` px outward of the true side: its level (continuous, or the
  // detector's bilinear sample of the point-sampled 8-bit image with the marker rolled and offset).
  auto level = [&](double along, double out) {
    const double x = p0[0] + a[0] * along * cells + nrm[0] * out / m.scale;
    const double y = p0[1] + a[1] * along * cells + nrm[1] * out / m.scale;
    if (!pix) {
      const double xa = p0[0] + a[0] * along * cells + nrm[0] * out / cell_across;
      const double ya = p0[1] + a[1] * along * cells + nrm[1] * out / cell_across;
      return m.At(xa, ya);
    }
    double total = 0;
    for (int pj = 0; pj < phase_avg; ++pj)
      for (int pi = 0; pi < phase_avg; ++pi) {
        const double ox = offx + static_cast<double>(pi) / phase_avg;
        const double oy = offy + static_cast<double>(pj) / phase_avg;
        const double X = (co * x - si * y) * m.scale + ox, Y = (si * x + co * y) * m.scale + oy;
        if (no_tent) {
          total += pixel_at(X, Y, ox, oy);
          continue;
        }
        auto& memo = cache[pj * phase_avg + pi];
        auto px = [&](double i, double j) {
          const int64_t key = (static_cast<int64_t>(i) + (1 << 20)) * (int64_t{1} << 21) +
                              (static_cast<int64_t>(j) + (1 << 20));
          auto it = memo.find(key);
          if (it != memo.end()) return it->second;
          return memo[key] = pixel_at(i, j, ox, oy);
        };
        const double fx = std::floor(X), fy = std::floor(Y), tx = X - fx, ty = Y - fy;
        total += (1 - ty) * ((1 - tx) * px(fx, fy) + tx * px(fx + 1, fy)) +
                 ty * ((1 - tx) * px(fx, fy + 1) + tx * px(fx + 1, fy + 1));
      }
    return total / (phase_avg * phase_avg);
  };
  // OTHEREXACT=1 (with PIX, sharptent): each row's part of the other colour at a ray (the model's code
  // rows, `other`) read as the profiles are, not from a Gaussian along the side: the image of row r's
  // cells (1 where the column is of the other colour, along the side only, blurred by the print's blur)
  // through the same pixels, phases and bilinear read, at the ray's point in the row's middle.
  const bool other_exact = pix && Env("OTHEREXACT", 0) > 0;
  auto exact_other = [&](double along, int r) {
    auto row_image = [&](double x, double y) {                   // print coordinates (cells)
      const double c = (x - p0[0]) * a[0] + (y - p0[1]) * a[1];  // along the side, cells
      double v = 0;
      for (int k = 0; k < cells; ++k)
        if (InnerCell(m, side, k, r)) v += Phi((k + 1 - c) / m.sb) - Phi((k - c) / m.sb);
      return v;
    };
    const double out = -(r + 0.5) * m.scale;  // px outward: the row's middle
    const double x = p0[0] + a[0] * along * cells + nrm[0] * out / m.scale;
    const double y = p0[1] + a[1] * along * cells + nrm[1] * out / m.scale;
    double total = 0;
    for (int pj = 0; pj < phase_avg; ++pj)
      for (int pi = 0; pi < phase_avg; ++pi) {
        const double ox = offx + static_cast<double>(pi) / phase_avg;
        const double oy = offy + static_cast<double>(pj) / phase_avg;
        const double X = (co * x - si * y) * m.scale + ox, Y = (si * x + co * y) * m.scale + oy;
        if (no_tent) {
          total += pixel_of(row_image, X, Y, ox, oy);
          continue;
        }
        const double fx = std::floor(X), fy = std::floor(Y), tx = X - fx, ty = Y - fy;
        total += (1 - ty) * ((1 - tx) * pixel_of(row_image, fx, fy, ox, oy) +
                             tx * pixel_of(row_image, fx + 1, fy, ox, oy)) +
                 ty * ((1 - tx) * pixel_of(row_image, fx, fy + 1, ox, oy) +
                       tx * pixel_of(row_image, fx + 1, fy + 1, ox, oy));
      }
    return total / (phase_avg * phase_avg);
  };
  double line = Env("LINE", 0), tilt = Env("TILT", 0);
  const int ends = static_cast<int>(Env("ENDS", 1));  // the first and last code columns used
  // FRAC: the rays used lie at least this part of a column from its ends (0.1 as the detector).
  const double frac_min = Env("FRAC", 0.1);
  SideProfiles s;
  SideFit fit;
  // The blur along the side the model's code rows assume (the detector's: the previous pass's fitted
  // sigma): with PIX the pixel's spread too (its box (1 - 1 / BOX^2) / 12 px^2, the bilinear sample's tent
  // 1 / 6), as the fitted sigma has it (0.44-0.51 px on sharp small cells). The optical blur alone made
  // the rows' cells of the other colour a hard step along the side: sharp 1.3 px cells +0.009 px outward
  // with the line at the truth (cellsize table B), +0.003 (se 0.006) with the pixel's spread (smallcell).
  // (NOTENT: the box's alone.)
  const double pixel_var =
      pix ? (Env("NOTENT", 0) > 0 ? 0.0 : 1.0 / 6.0) + (1.0 - 1.0 / (box * box)) / 12.0 : 0.0;
  double sigma_along = Env("ALONG", std::sqrt(blur * blur + pixel_var));
  const bool cross = Env("CROSS", 0) > 0;
  for (int iter = 0; iter < (cross ? 12 : 1); ++iter) {
    if (cross) {  // CrossingLine about the current line, model passes' sampling
      const double h = std::clamp(0.5 * cell_across, 0.75, 3.0), ds = h / 5;
      std::vector<double> ins, outs, ts, xs;
      std::vector<std::vector<double>> profs;
      std::vector<char> clean;
      for (int i = 0; i < n_rays; ++i) {
        const double t = margin_t + (1 - 2 * margin_t) * (i + 0.5) / n_rays;
        const double off = line + tilt * (t - 0.5);
        std::vector<double> prof(11);
        for (int j = 0; j < 11; ++j) prof[j] = level(t, off - h + j * ds);
        bool c = true;
        for (double d : {-0.5, 0.0, 0.5}) {
          const int col = std::clamp(static_cast<int>(std::floor(t * cells + d)), 0, cells - 1);
          if (InnerCell(m, side, col, 1)) c = false;
        }
        clean.push_back(c), profs.push_back(prof), ts.push_back(t);
      }
      int n_clean = 0;
      for (char c : clean) n_clean += c;
      const bool use_clean = n_clean >= std::max(4, n_rays / 5);
      for (int i = 0; i < n_rays; ++i)
        if (!use_clean || clean[i]) ins.push_back(profs[i][0]), outs.push_back(profs[i][10]);
      auto median = [](std::vector<double> v) {
        std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
        return v[v.size() / 2];
      };
      const double mid = 0.5 * (median(ins) + median(outs));
      double st = 0, sx = 0, stt = 0, stx = 0;
      int k = 0;
      for (int i = 0; i < n_rays; ++i) {
        if (use_clean && !clean[i]) continue;
        double best = 1e9;
        for (int j = 0; j + 1 < 11; ++j) {
          const double v0 = profs[i][j] - mid, v1 = profs[i][j + 1] - mid;
          if (v0 <= 0 && v1 > 0) {
            const double at = -h + (j + v0 / (v0 - v1)) * ds;
            if (std::abs(at) < std::abs(best)) best = at;
          }
        }
        if (best > 1e8) continue;
        const double x = line + tilt * (ts[i] - 0.5) + best;  // crossing, px outward of the truth
        st += ts[i], sx += x, stt += ts[i] * ts[i], stx += ts[i] * x, ++k;
      }
      const double slope = (k * stx - st * sx) / (k * stt - st * st), icpt = (sx - slope * st) / k;
      tilt = slope, line = icpt + 0.5 * slope;
      if (std::getenv("DUMP"))
        std::printf("crossings: %d rays (clean %d), line %+.4f tilt %+.4f\n", k, use_clean, line, tilt);
    }
    s.Reset(u0, du, bins, cell_across);
    s.fit_gamma = Env("FITGAMMA", 1) > 0;
    s.polarity = 1;
    s.paper = Env("PAPER", 0);
    for (int i = 0; i < n_rays; ++i) {
      const double t = margin_t + (1 - 2 * margin_t) * (i + 0.5) / n_rays;
      const double at = t * cells;
      const int col = static_cast<int>(std::floor(at));
      const double frac = at - col;
      if (col < 1 || col > cells - 2 || frac < 0.1 || frac > 0.9) continue;
      if ((col == 1 && frac < 0.4) || (col == cells - 2 && frac > 0.6)) continue;
      if (col < ends || col > cells - 1 - ends) continue;
      if (frac < frac_min || frac > 1.0 - frac_min) continue;
      std::array<uint8_t, SideProfiles::kRows> pattern;
      std::array<double, SideProfiles::kRows> depths, other;
      for (int r = 1; r <= SideProfiles::kRows; ++r) {
        pattern[r - 1] = static_cast<uint8_t>(InnerCell(m, side, col, r));
        depths[r - 1] = r * cell_across;
        double o = 0;
        for (int k = std::max(0, col - 3); k <= std::min(cells - 1, col + 3); ++k)
          if (InnerCell(m, side, k, r))
            o += Phi((k + 1 - at) * cell / sigma_along) - Phi((k - at) * cell / sigma_along);
        other[r - 1] = o;
        if (other_exact) other[r - 1] = exact_other(t, r);
      }
      const int g = s.AddRay(pattern, depths, other);
      const double off = line + tilt * (t - 0.5);
      for (int j = 0; j < bins; ++j) s.Add(g, j, level(t, off + u0 + j * du));
    }
    if (iter > 0) fit.e = 0.0;
    if (iter == 0 && Env("TRUTHSTART", 0) > 0) {  // warm start at the print's own parameters
      fit.params = {0.0, blur, m.ink, m.paper, m.paper, m.surface, m.margin * cell_across, 1.0};
      fit.e = 0.0, fit.sigma = blur, fit.warm = true;
    }
    if (!FitSideProfiles(s, &fit)) {
      if (!quiet) std::printf("fit failed\n");
      return 1;
    }
    // As the detector's whole-side fits: the surround's trend taken off on cells under 2 px, a warm refit
    // (DetrendSurround); NODETREND=1: the fit alone (main before shade3h).
    if (std::getenv("NODETREND") == nullptr) DetrendSurround(&s, &fit);
    fit.warm = true;
    if (cross) line += fit.e;
    if (std::getenv("ALONG") == nullptr) sigma_along = fit.sigma;
    if (!quiet && (std::getenv("DUMP") || iter == (cross ? 11 : 0)))
      std::printf(
          "id %d side %d: e %+.4f px (edge at %+.4f, tilt %+.4f) sigma %.3f gamma %.3f L0 %.1f L1 %.1f S1 "
          "%.1f S2 %.1f q %.2f single %d groups %zu\n",
          id, side, fit.e, cross ? line : line + fit.e, tilt, fit.sigma, fit.gamma, fit.params[2],
          fit.params[3], fit.params[4], fit.params[5], fit.params[6], fit.single_surround, s.patterns.size());
  }
  *e_out = fit.e;
  if (quiet) return 0;
  {  // DUMP: each ray's crossing about the true line, of the profiles and of the fitted side model (with
     // the marker's extent along the side: the adjacent sides' edges), as CrossingLine finds them
    const double h = std::clamp(0.5 * cell, 0.75, 3.0), ds = h / 5, sg = fit.sigma;
    const double* q = fit.params.data();
    for (int i = 0; i < n_rays; ++i) {
      const double t = margin_t + (1 - 2 * margin_t) * (i + 0.5) / n_rays, at = t * cells;
      const int col = static_cast<int>(std::floor(at));
      bool c = true;
      for (double d : {-0.5, 0.0, 0.5}) {
        const int cc = std::clamp(static_cast<int>(std::floor(at + d)), 0, cells - 1);
        if (InnerCell(m, side, cc, 1)) c = false;
      }
      double lev[2];
      for (int r = 1; r <= 2; ++r) {
        double o = 0;
        for (int k = std::max(0, col - 3); k <= std::min(cells - 1, col + 3); ++k)
          if (InnerCell(m, side, k, r)) o += Phi((k + 1 - at) * cell / sg) - Phi((k - at) * cell / sg);
        lev[r - 1] = q[2] + (q[3] - q[2]) * o;
      }
      double dp[11], mp[11];
      for (int j = 0; j < 11; ++j) {
        const double u = -h + j * ds;
        dp[j] = level(t, u);
        const double pq = Phi((q[6] - u) / sg), p0 = Phi(-u / sg), p1 = Phi((-cell - u) / sg),
                     p2 = Phi((-2 * cell - u) / sg);
        const double x = at * cell, len = cells * cell;
        const double kp = Phi((len - x) / sg) - Phi(-x / sg),
                     mq = Phi((len + q[6] - x) / sg) - Phi((-q[6] - x) / sg);
        mp[j] = q[5] + (q[4] - q[5]) * pq * mq + (q[2] - q[4]) * p0 * kp + (lev[0] - q[2]) * p1 +
                (lev[1] - lev[0]) * p2;
        if (s.fit_gamma) mp[j] = 255.0 * std::pow(std::max(mp[j], 0.5) / 255.0, 1.0 / fit.gamma);
      }
      double xs[2];
      for (int w = 0; w < 2; ++w) {
        const double* pr = w ? mp : dp;
        const double mid = 0.5 * (m.ink + m.paper);  // the border's and the code's (a fixed level: the
                                                     // crossings' differences along the side matter)
        double best = 1e9;
        for (int j = 0; j + 1 < 11; ++j) {
          const double v0 = pr[j] - mid, v1 = pr[j + 1] - mid;
          if (v0 <= 0 && v1 > 0) {
            const double x = -h + (j + v0 / (v0 - v1)) * ds;
            if (std::abs(x) < std::abs(best)) best = x;
          }
        }
        xs[w] = best;
      }
      if (std::getenv("DUMP"))
        std::printf("ray t %.3f clean %d crossing data %+.4f model %+.4f\n", t, c, xs[0], xs[1]);
    }
  }
  if (std::getenv("DUMP"))
    for (size_t g = 0; g < s.patterns.size(); ++g) {
      std::printf("group %zu pattern %d%d rays %d other %.3f %.3f\n", g, s.patterns[g][0], s.patterns[g][1],
                  s.rays[g], s.other_sum[g][0] / s.rays[g], s.other_sum[g][1] / s.rays[g]);
      // The model at the fit (side_model.h's regions) and the residual, per bin.
      const double* q = fit.params.data();
      const double sg = fit.sigma, e = fit.e;
      const double bound[4] = {e + q[6], e, e - s.depth_sum[g][0] / s.rays[g],
                               e - s.depth_sum[g][1] / s.rays[g]};
      const double lev[5] = {fit.single_surround ? q[4] : q[5], q[4], q[2],
                             q[2] + (q[3] - q[2]) * s.other_sum[g][0] / s.rays[g],
                             q[2] + (q[3] - q[2]) * s.other_sum[g][1] / s.rays[g]};
      double rss = 0;
      for (int j = 0; j < bins; ++j) {
        const double u = u0 + j * du;
        double f = 0;
        for (int k = 0; k < 5; ++k)
          f += lev[k] *
               ((k == 0 ? 1.0 : Phi((bound[k - 1] - u) / sg)) - (k == 4 ? 0.0 : Phi((bound[k] - u) / sg)));
        if (s.fit_gamma) f = 255.0 * std::pow(std::max(f, 0.5) / 255.0, 1.0 / fit.gamma);
        const double data = s.sum[g * bins + j] / s.count[g * bins + j];
        std::printf("  u %+.2f data %6.2f model %6.2f res %+.2f\n", u, data, f, data - f);
        rss += (data - f) * (data - f) * s.count[g * bins + j];
      }
      std::printf(" group rss %.2f\n", rss);
    }
  return 0;
}

int main(int argc, char** argv) {
  if (argc < 5) {
    std::fprintf(stderr, "usage: diag_side_exact ID SIDE BLUR_PX SIDE_PX\n");
    return 2;
  }
  auto dict = LoadDictionary("DICT_6X6_250");
  const int id = std::atoi(argv[1]), side = std::atoi(argv[2]);
  const double blur = std::atof(argv[3]), side_px = std::atof(argv[4]);
  const char* sweep = std::getenv("SWEEP");
  if (sweep == nullptr) {
    double e = 0;
    return Run(dict, id, side, blur, side_px, Env("OFFX", 0.3), Env("OFFY", 0.7), Env("ROLL", 0), false, &e);
  }
  // SWEEP=file (sharptent): the fit averaged over pixel phases, as 2026-12-07-sharpstep-phases.sh in one
  // process. The file holds one phase "OFFX OFFY" per line; for each roll of ROLLS (default
  // "13 37 58 77"), each phase's mean e over ids 0 .. ID - 1 (the first argument: the id count) and sides
  // 0-3 (SIDE < 0; else that side alone), then their mean and se over the phases (SWEEPDUMP=1: each
  // phase's too). A failed fit counts apart.
  std::vector<std::pair<double, double>> phases;
  if (FILE* f = std::fopen(sweep, "r")) {
    double x, y;
    while (std::fscanf(f, "%lf %lf", &x, &y) == 2) phases.emplace_back(x, y);
    std::fclose(f);
  }
  if (phases.empty()) {
    std::fprintf(stderr, "SWEEP: no phases read from %s\n", sweep);
    return 2;
  }
  const char* rolls_env = std::getenv("ROLLS");
  std::vector<double> rolls;
  {
    const std::string text = rolls_env ? rolls_env : "13 37 58 77";
    size_t at = 0;
    while (at < text.size()) {
      size_t used = 0;
      try {
        rolls.push_back(std::stod(text.substr(at), &used));
      } catch (...) {
        break;
      }
      at += used;
    }
  }
  double all_sum = 0;
  int all_n = 0;
  for (double roll : rolls) {
    double s = 0, ss = 0;
    int failed = 0;
    for (const auto& [ox, oy] : phases) {
      double sum = 0;
      int n = 0;
      for (int i = 0; i < id; ++i)
        for (int k = side < 0 ? 0 : side; k <= (side < 0 ? 3 : side); ++k) {
          double e = 0;
          if (Run(dict, i, k, blur, side_px, ox, oy, roll, true, &e) == 0)
            sum += e, ++n;
          else
            ++failed;
        }
      const double mean = n > 0 ? sum / n : NAN;
      if (std::getenv("SWEEPDUMP")) std::printf("phase %.4f %.4f: %+.4f (%d sides)\n", ox, oy, mean, n);
      s += mean, ss += mean * mean;
    }
    const double k = phases.size(), mean = s / k;
    const double se = k > 1 ? std::sqrt(std::max(0.0, ss / k - mean * mean) / (k - 1)) : NAN;
    std::printf("roll %g: phase mean %+.4f (se over phases %.4f; %d phases, %d fits failed)\n", roll, mean,
                se, static_cast<int>(k), failed);
    all_sum += mean, ++all_n;
  }
  std::printf("all rolls: %+.4f\n", all_sum / all_n);
  return 0;
}
