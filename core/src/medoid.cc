#include "core/medoid.h"

#include <algorithm>
#include <limits>
#include <numeric>
#include <random>

namespace mcmt {
namespace {

struct Probes {
  Eigen::Vector3d p[3];
};

// Distance between two candidates: sum over the three probe points of the Euclidean distance between
// their images under each candidate.
double ProbeDistance(const Probes& a, const Probes& b) {
  return (a.p[0] - b.p[0]).norm() + (a.p[1] - b.p[1]).norm() + (a.p[2] - b.p[2]).norm();
}

}  // namespace

MedoidResult TransformMedoid(const std::vector<Rigid3>& candidates, const MedoidOptions& options) {
  MedoidResult result;
  const int n = static_cast<int>(candidates.size());
  result.num_candidates = n;
  if (n == 0) return result;
  if (n == 1) {
    result.index = 0;
    return result;
  }
  const double s = options.point_scale;
  const Eigen::Vector3d u[3] = {Eigen::Vector3d(s, 0, 0), Eigen::Vector3d(0, s, 0), Eigen::Vector3d(0, 0, s)};
  std::vector<Probes> mapped(n);
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) mapped[i].p[k] = candidates[i] * u[k];

  const int max_exact = std::max(2, options.max_exact);
  double best = std::numeric_limits<double>::infinity();
  int best_index = 0;
  if (n <= max_exact) {
    // Exact: all pairwise distances (symmetric, computed once).
    std::vector<double> sums(n, 0.0);
    for (int i = 0; i < n; ++i)
      for (int j = i + 1; j < n; ++j) {
        const double d = ProbeDistance(mapped[i], mapped[j]);
        sums[i] += d;
        sums[j] += d;
      }
    for (int i = 0; i < n; ++i)
      if (sums[i] < best) {
        best = sums[i];
        best_index = i;
      }
  } else {
    // Subsampled: a fixed random subset of max_exact references (seeded), scaled to n - 1 others.
    std::vector<int> order(n);
    std::iota(order.begin(), order.end(), 0);
    std::mt19937_64 rng(options.seed);
    for (int k = 0; k < max_exact; ++k) {  // partial Fisher-Yates
      std::uniform_int_distribution<int> pick(k, n - 1);
      std::swap(order[k], order[pick(rng)]);
    }
    std::vector<char> is_reference(n, 0);
    for (int k = 0; k < max_exact; ++k) is_reference[order[k]] = 1;
    for (int i = 0; i < n; ++i) {
      double sum = 0.0;
      for (int k = 0; k < max_exact; ++k) sum += ProbeDistance(mapped[i], mapped[order[k]]);
      // A reference candidate compares against itself (distance 0): max_exact - 1 real others.
      const int others = is_reference[i] ? max_exact - 1 : max_exact;
      const double scaled = sum * static_cast<double>(n - 1) / static_cast<double>(others);
      if (scaled < best) {
        best = scaled;
        best_index = i;
      }
    }
  }
  result.index = best_index;
  result.summed_distance = best;
  return result;
}

double MedoidEdgeCost(const MedoidResult& medoid, double tau_n) {
  const double s = static_cast<double>(medoid.num_candidates);
  if (s <= 0) return std::numeric_limits<double>::infinity();
  return (medoid.summed_distance / s) * std::max(1.0, tau_n / s);
}

}  // namespace mcmt
