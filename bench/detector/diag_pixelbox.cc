// The side model's own edge offset on exact 1-D profiles (issue 15, bench/results/2026-12-06-pixelbox.md):
// across one side (x outward), surface S2 beyond a paper margin MARGIN cells wide, the border (ink), code
// rows 1 and 2 of each of the 4 patterns, and row 2's colour further in; blurred by a Gaussian of sigma px.
// The image is sampled as MODE says and the profiles are built as FitSide does (detector.cc: u0, du, bins
// from the cell), 16 edge phases per pattern, then fitted by FitSideProfiles. MODE: point (the continuous
// blurred profile at u: the model exactly), bilinear (pixels point-sampled at their centres, bilinear
// between them), box (pixels the area mean of the blurred profile, bilinear between them: the reference
// renderer's pixel-area sampling).
// Environment: PHASE=1 one phase per side (every ray of a side at the same phase, as an axis-aligned
// side; the offsets are the mean over the 16 sides' fits), ROW3=1 code row 3 of either colour (the model
// takes row 2's colour on), QUANT=1 the profile's values rounded to integers.
//   diag_pixelbox [MARGIN_CELLS] [SURFACE]   prints edge offset (px, + outward) and fitted sigma per cell x
//   blur
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "bench/detector/diag_support.h"
#include "detector/side_model.h"

using namespace mcmt;

namespace {
using diag::Phi;
double phi(double z) { return 0.3989422804014327 * std::exp(-0.5 * z * z); }
// The antiderivative of Phi: d/dt (t Phi(t) + phi(t)) = Phi(t).
double IntPhi(double t) { return t * Phi(t) + phi(t); }

struct Edge {
  double at, rise;  // the level steps by `rise` (inner minus outer) at `at`
};

// mode 0 point, 1 bilinear of point-sampled pixels, 2 bilinear of area-sampled pixels.
double Value(const std::vector<Edge>& edges, double base, double sigma, int mode, double x) {
  auto point = [&](double at) {
    double f = base;
    for (const Edge& e : edges) f += e.rise * Phi((e.at - at) / sigma);
    return f;
  };
  auto area = [&](int i) {  // pixel i covers [i - 0.5, i + 0.5]
    double f = base;
    for (const Edge& e : edges)
      f += e.rise * sigma * (IntPhi((e.at - i + 0.5) / sigma) - IntPhi((e.at - i - 0.5) / sigma));
    return f;
  };
  if (mode == 0) return point(x);
  const int i = static_cast<int>(std::floor(x));
  const double t = x - i;
  const double a = mode == 1 ? point(i) : area(i), b = mode == 1 ? point(i + 1) : area(i + 1);
  return a + t * (b - a);
}
}  // namespace

int main(int argc, char** argv) {
  const double margin = argc > 1 ? std::atof(argv[1]) : 1.0, surface = argc > 2 ? std::atof(argv[2]) : 0.5;
  const bool per_phase = std::getenv("PHASE") && std::atoi(std::getenv("PHASE"));
  const bool row3 = std::getenv("ROW3") && std::atoi(std::getenv("ROW3"));
  const bool quant = std::getenv("QUANT") && std::atoi(std::getenv("QUANT"));
  const double paper = 0.85 * 255, ink = 0.04 * 255, s2 = surface * 255;
  const double cells[] = {1.2, 1.5, 1.75, 2.0, 2.5, 3.0}, sigmas[] = {0.3, 0.4, 0.5, 0.6, 0.7, 0.85, 1.0};
  const char* names[] = {"point", "bilinear", "box"};
  std::printf("margin %.2f cells, surface %.2f; edge offset px (+ outward) / fitted sigma\n", margin,
              surface);
  for (int mode = 0; mode < 3; ++mode) {
    std::printf("\n%s\ncell\\sigma", names[mode]);
    for (double sg : sigmas) std::printf("  %13.2f", sg);
    std::printf("\n");
    for (double cell : cells) {
      std::printf("%10.2f", cell);
      for (double sigma : sigmas) {
        double e_sum = 0, sigma_sum = 0;
        int fits = 0, singles = 0;
        for (int side = 0; side < (per_phase ? 16 : 1); ++side) {
          SideProfiles s;
          const double du = std::clamp(cell / 4.0, 0.1, 0.5), u0 = -(SideProfiles::kRows - 0.4) * cell;
          const double u1 = 1.6 * cell + 1.0;
          s.Reset(u0, du, static_cast<int>(std::ceil((u1 - u0) / du)) + 1, cell);
          s.polarity = 1;
          s.paper = paper;
          for (int pattern = 0; pattern < (row3 ? 8 : 4); ++pattern) {
            const int c1 = pattern % 2, c2 = (pattern / 2) % 2, c3 = row3 ? pattern / 4 : c2;
            const double r1 = c1 ? paper : ink, r2 = c2 ? paper : ink, r3 = c3 ? paper : ink;
            for (int k = 0; k < 16; ++k) {
              if (per_phase && k != side) continue;
              const double xe = (k + 0.5) / 16.0;  // the edge's phase in the pixel grid
              std::vector<Edge> edges = {{xe + margin * cell, paper - s2},
                                         {xe, ink - paper},
                                         {xe - cell, r1 - ink},
                                         {xe - 2 * cell, r2 - r1},
                                         {xe - 3 * cell, r3 - r2}};
              const int g = s.AddRay({static_cast<uint8_t>(c1), static_cast<uint8_t>(c2)}, {cell, 2 * cell},
                                     {1.0 * c1, 1.0 * c2});
              for (int j = 0; j < s.bins; ++j) {
                const double v = Value(edges, s2, sigma, mode, xe + u0 + j * du);
                s.Add(g, j, quant ? std::round(v) : v);
              }
            }
          }
          SideFit fit;
          if (!FitSideProfiles(s, &fit)) continue;
          e_sum += fit.e, sigma_sum += fit.sigma, ++fits, singles += fit.single_surround;
        }
        if (fits == 0) {
          std::printf("  %13s", "fail");
          continue;
        }
        std::printf("  %+.4f/%.3f%s", e_sum / fits, sigma_sum / fits, singles ? "1" : " ");
      }
      std::printf("\n");
    }
  }
  return 0;
}
