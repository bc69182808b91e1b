// Building blocks of the paper's initialisation (steps 2-4), exposed for unit tests:
// candidate sets per node pair -> medoid -> edge cost -> minimum spanning tree -> poses along tree paths.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/marker.h"
#include "core/medoid.h"
#include "core/se3.h"

namespace mcmt {

// A covariance C kept for squared Mahalanobis distances delta^T C^-1 delta only: its lower Cholesky factor
// C = L L^T packed row by row (21 doubles: 168 bytes instead of a Matrix6d's 288), the distance |L^-1
// delta|^2 by forward substitution (21 multiply-adds, no factorisation per test). A covariance that is not
// positive definite gives a factor whose every distance is infinite.
class MahalanobisFactor {
 public:
  MahalanobisFactor() = default;
  explicit MahalanobisFactor(const Matrix6d& covariance);
  double SquaredDistance(const Vector6d& delta) const;
  bool valid() const { return valid_; }

 private:
  static constexpr int Index(int row, int col) { return row * (row + 1) / 2 + col; }
  double l_[21] = {};
  bool valid_ = false;
};

// Candidates of a_from_b for one pair of nodes (a < b), grouped by the co-observation event
// (frame and camera, or frame) that produced them: one event yields one or more candidates
// (one per combination of kept IPPE hypotheses).
struct PairCandidates {
  int a = -1, b = -1;
  std::vector<Rigid3> a_from_b;
  std::vector<int> event;        // event index of each candidate (0 .. num_events-1, non-decreasing)
  int num_events = 0;            // events stored (a strided subset when there were many)
  int64_t total_events = 0;      // events seen in all
  int64_t total_candidates = 0;  // candidates seen in all (s in the paper)
  // Per candidate (or empty: unknown), twice the covariance of a_from_b under a_from_b * Exp(delta), delta =
  // (rotation vector, translation) in b's frame, from the noise of the square poses it was composed of
  // (Consistent's test). One factor per candidate: up to max_events x 4 per pair.
  std::vector<MahalanobisFactor> noise;
  // `covariances`: empty, or one per candidate (of a_from_b, not yet doubled).
  void AddEvent(const std::vector<Rigid3>& candidates, const std::vector<Matrix6d>& covariances = {});
};

// When are two relative poses the same, up to noise.
struct ConsistencyOptions {
  double max_angle_rad = 15.0 * 3.14159265358979323846 / 180.0;
  double max_distance_m = 0.02;
  double max_distance_rel = 0.15;  // plus this fraction of the translation's length
  // Also the same when x has a covariance (PairCandidates::noise) and the squared Mahalanobis distance
  // of their difference under twice x's covariance is at most this (0: the tolerances above only).
  double max_mahalanobis_sq = 0.0;
};
bool Consistent(const Rigid3& x, const Rigid3& y, const ConsistencyOptions& options);
// `x_noise`: twice x's covariance (PairCandidates::noise).
bool Consistent(const Rigid3& x, const MahalanobisFactor& x_noise, const Rigid3& y,
                const ConsistencyOptions& options);

// The mean of a quad's four side lengths (pixels for image corners).
double MeanSideLength(const MarkerCorners2d& corners);

// Covariance of a square's pose cam_from_marker under cam_from_marker * Exp(delta) (delta = rotation vector,
// translation, in the marker's frame), from independent noise of sigma_px on each corner coordinate:
// (J^T J / sigma^2 + prior)^-1 with J the pinhole Jacobian of the four corners' normalised image points,
// sigma in normalised units = sigma_px x the side's length there / its length in pixels (observed_side_px:
// MeanSideLength of the observed corners),
// and a weak prior (1 rad, 1 m) where the corners do not pin the pose (a face-on square's tilt).
Matrix6d SquarePoseCovariance(const Rigid3& cam_from_marker, double side, double observed_side_px,
                              double sigma_px);

struct GraphEdge {
  int a = -1, b = -1;
  Rigid3 a_from_b = Rigid3::Identity();  // the medoid candidate
  double cost = 0.0;                     // the paper's e = (d / s) * max(1, tau_n / s)
  int64_t candidates = 0;                // s
  int64_t events = 0;                    // co-observation events (all)
  int support = 0;                       // stored events with a candidate consistent with the medoid
  int stored_events = 0;
  double SupportFraction() const { return stored_events > 0 ? double(support) / stored_events : 0.0; }
  // A second co-observation agrees with a_from_b. An edge of one candidate has d = 0, so the paper's
  // cost calls it the cheapest of all; one co-observation (a grazing view, a flipped square) proves nothing.
  bool Confirmed() const { return support >= 2; }
};

// Events (not candidates) of the pair with a candidate consistent with x: each co-observation votes once.
// Candidates with a covariance are also tested within their poses' noise (ConsistencyOptions).
int EventSupport(const PairCandidates& pair, const Rigid3& x, const ConsistencyOptions& consistency);

// Medoid of the pair's candidates and the paper's edge cost; support against `consistency`.
GraphEdge EvaluateEdge(const PairCandidates& pair, const MedoidOptions& medoid_options, double tau_n,
                       const ConsistencyOptions& consistency);

// The one edge builder of both graphs. Items are nodes seen in one co-observation event (`group`: a camera
// frame for the marker graph, a frame for the camera graph), each with its candidate poses relative to
// what the group shares (the camera, or the object), node_from_common[h] and common_from_node[h] =
// inverse of the former. Every pair of items (a < b by node) of a group gives the candidates
// a_from_b = a.node_from_common[i] * b.common_from_node[j]; at most max_events events per pair are kept
// (a strided subset); each pair's medoid and cost by EvaluateEdge.
struct GraphItem {
  int group = 0;  // items of one group are contiguous
  int node = 0;
  std::vector<Rigid3> node_from_common;
  std::vector<Rigid3> common_from_node;
  // Optional (empty or one per hypothesis): covariance of common_from_node[h] (SquarePoseCovariance's
  // convention, delta in the node's frame).
  std::vector<Matrix6d> covariance;
};

struct EdgeOptions {
  int max_events = 3000;
  MedoidOptions medoid;
  double tau_n = 10.0;
  ConsistencyOptions consistency;
};

std::vector<GraphEdge> BuildGraphEdges(const std::vector<GraphItem>& items, int num_nodes,
                                       const EdgeOptions& options, int threads);
// BuildGraphEdges in two steps: the candidates of every pair (sorted by (a, b)), then their edges.
std::vector<PairCandidates> CollectPairs(const std::vector<GraphItem>& items, int num_nodes, int max_events);
std::vector<GraphEdge> EvaluateEdges(const std::vector<PairCandidates>& pairs, const EdgeOptions& options,
                                     int threads);

// Kruskal's minimum spanning forest over nodes 0..n-1: confirmed edges (GraphEdge::Confirmed) first by
// cost, then the others by cost, so an unconfirmed edge joins only what no confirmed path joins (ties broken
// by (a, b)). Edges of infinite cost (no candidate) are left out. `forest` (optional): edges of a forest
// joined before all others (extending a tree with more edges).
std::vector<GraphEdge> MinimumSpanningTree(int n, std::vector<GraphEdge> edges,
                                           const std::vector<GraphEdge>& forest = {});

// The node with the largest summed number of candidates over its edges (the paper's "best connected"),
// -1 if there are no edges. `eligible` (optional, size n) restricts the choice.
int BestConnectedNode(int n, const std::vector<GraphEdge>& edges, const std::vector<bool>& eligible = {});

// Connected component (node flags) of `root` in the graph of `edges`.
std::vector<bool> ComponentOf(int n, int root, const std::vector<GraphEdge>& edges);

// root_from_node for every node reachable from root through the tree (product of the edge transforms
// along the path); placed[i] false for the others.
struct TreePoses {
  std::vector<Rigid3> root_from_node;
  std::vector<bool> placed;
  std::vector<int> depth;
};
TreePoses PosesFromTree(int n, int root, const std::vector<GraphEdge>& tree);

// Index of the medoid among candidates (core's TransformMedoid), -1 when empty.
int MedoidIndex(const std::vector<Rigid3>& candidates, double point_scale);

}  // namespace mcmt
