// The paper's selection rule among candidate transforms: every candidate maps three fixed non-zero
// points; the chosen candidate is the one whose mapped points lie nearest to those of all the others
// (a medoid). Robust to wrong hypotheses, unlike an average.
#pragma once

#include <cstdint>
#include <vector>

#include "core/se3.h"

namespace mcmt {

struct MedoidOptions {
  // The three probe points are (scale, 0, 0), (0, scale, 0), (0, 0, scale) in the source frame:
  // choose the size of the scene part the transforms move (metres).
  double point_scale = 0.1;
  // Above this many candidates the distance sums are estimated against a fixed-size random subset
  // of reference candidates (linear time); below, exact (quadratic). Same choice on clean data.
  int max_exact = 400;
  uint64_t seed = 1;
};

struct MedoidResult {
  int index = -1;          // index of the chosen candidate, -1 if there were none
  int num_candidates = 0;  // s in the paper
  // d in the paper: sum over the other candidates of the distance between the chosen candidate's
  // mapped probe points and theirs (sum over the three points of Euclidean distances, metres).
  // When subsampled, scaled up to all candidates.
  double summed_distance = 0.0;
  double MeanDistance() const { return num_candidates > 1 ? summed_distance / (num_candidates - 1) : 0.0; }
};

MedoidResult TransformMedoid(const std::vector<Rigid3>& candidates, const MedoidOptions& options = {});

// The paper's graph edge cost e = (d / s) * max(1, tau_n / s).
double MedoidEdgeCost(const MedoidResult& medoid, double tau_n);

}  // namespace mcmt
