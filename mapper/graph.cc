#include "mapper/graph.h"

#include <algorithm>
#include <limits>
#include <numeric>
#include <queue>
#include <tuple>
#include <unordered_map>

#include "core/marker.h"
#include "core/math.h"
#include "mapper/parallel.h"

namespace mcmt {

MahalanobisFactor::MahalanobisFactor(const Matrix6d& covariance) {
  const Eigen::LLT<Matrix6d> llt(covariance);
  valid_ = llt.info() == Eigen::Success;
  if (!valid_) return;
  const Matrix6d l = llt.matrixL();
  for (int row = 0; row < 6; ++row)
    for (int col = 0; col <= row; ++col) l_[Index(row, col)] = l(row, col);
}

double MahalanobisFactor::SquaredDistance(const Vector6d& delta) const {
  if (!valid_) return std::numeric_limits<double>::infinity();
  // y = L^-1 delta: L y = delta, row by row.
  double y[6], sum = 0.0;
  for (int row = 0; row < 6; ++row) {
    double v = delta[row];
    for (int col = 0; col < row; ++col) v -= l_[Index(row, col)] * y[col];
    y[row] = v / l_[Index(row, row)];
    sum += y[row] * y[row];
  }
  return sum;
}

void PairCandidates::AddEvent(const std::vector<Rigid3>& candidates,
                              const std::vector<Matrix6d>& covariances) {
  if (candidates.empty()) return;
  for (const Rigid3& c : candidates) {
    a_from_b.push_back(c);
    event.push_back(num_events);
  }
  for (const Matrix6d& c : covariances) noise.emplace_back(2.0 * c);
  ++num_events;
}

bool Consistent(const Rigid3& x, const Rigid3& y, const ConsistencyOptions& options) {
  if (RotationAngle(x, y) > options.max_angle_rad) return false;
  const double scale = 0.5 * (x.translation().norm() + y.translation().norm());
  return TranslationDistance(x, y) <= options.max_distance_m + options.max_distance_rel * scale;
}

bool Consistent(const Rigid3& x, const MahalanobisFactor& x_noise, const Rigid3& y,
                const ConsistencyOptions& options) {
  if (Consistent(x, y, options)) return true;
  if (!(options.max_mahalanobis_sq > 0)) return false;
  // x = y Exp(delta) to first order: delta = (rotation vector, translation) of y^-1 x. Its covariance is
  // x's twice over (y's error taken as large as x's): y's own covariance would let a y from a poorly
  // pinned event agree with everything. On a marker moved 5-15 cm between frames
  // (SmallSquaresAgreeWithinTheirPosesNoise, measured while proposals were also chosen by this test) the sum
  // of both covariances agreed in 26 of 60 frames, twice x's in 12 of 60 (attached: 59 and 58 of 60).
  const Rigid3 d = Inverse(y) * x;
  Vector6d delta;
  delta << VectorFromRotation(d.rotation()), d.translation();
  return x_noise.SquaredDistance(delta) <= options.max_mahalanobis_sq;
}

double MeanSideLength(const MarkerCorners2d& corners) {
  double side = 0.0;
  for (int k = 0; k < 4; ++k) side += 0.25 * (corners[(k + 1) % 4] - corners[k]).norm();
  return side;
}

Matrix6d SquarePoseCovariance(const Rigid3& cam_from_marker, double side, double observed_side_px,
                              double sigma_px) {
  const Eigen::Matrix3d r = cam_from_marker.rotation();
  const MarkerCorners3d corners = MarkerCornersInMarker(side);
  MarkerCorners2d image;
  Matrix6d information = Matrix6d::Zero();
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector3d p = cam_from_marker * corners[k];
    image[k] = p.head<2>() / p.z();
    // d(x/z, y/z)/dp, and dp/d(w, v) = (-R [X]x, R) for cam_from_marker * Exp((w, v)).
    Eigen::Matrix<double, 2, 3> projection;
    projection << 1 / p.z(), 0, -p.x() / (p.z() * p.z()), 0, 1 / p.z(), -p.y() / (p.z() * p.z());
    Eigen::Matrix<double, 3, 6> dp;
    dp << -r * Skew(corners[k]), r;
    const Eigen::Matrix<double, 2, 6> j = projection * dp;
    information += j.transpose() * j;
  }
  const double sigma = sigma_px * MeanSideLength(image) / std::max(observed_side_px, 1e-9);
  information /= sigma * sigma;
  information.diagonal() += Vector6d::Ones();  // the prior: 1 rad, 1 m (0.26 rad: the same supports)
  return information.inverse();
}

int EventSupport(const PairCandidates& pair, const Rigid3& x, const ConsistencyOptions& consistency) {
  const bool with_covariance = pair.noise.size() == pair.a_from_b.size();
  int support = 0, last_supported = -1;
  for (size_t i = 0; i < pair.a_from_b.size(); ++i) {
    if (pair.event[i] == last_supported) continue;
    if (with_covariance ? Consistent(pair.a_from_b[i], pair.noise[i], x, consistency)
                        : Consistent(pair.a_from_b[i], x, consistency)) {
      last_supported = pair.event[i];
      ++support;
    }
  }
  return support;
}

namespace {

double SummedProbeDistance(const std::vector<Rigid3>& candidates, const Rigid3& x, double scale) {
  const Eigen::Vector3d u[3] = {Eigen::Vector3d(scale, 0, 0), Eigen::Vector3d(0, scale, 0),
                                Eigen::Vector3d(0, 0, scale)};
  Eigen::Vector3d px[3];
  for (int k = 0; k < 3; ++k) px[k] = x * u[k];
  double sum = 0.0;
  for (const Rigid3& c : candidates)
    for (int k = 0; k < 3; ++k) sum += (c * u[k] - px[k]).norm();
  return sum;
}

}  // namespace

GraphEdge EvaluateEdge(const PairCandidates& pair, const MedoidOptions& medoid_options, double tau_n,
                       const ConsistencyOptions& consistency) {
  GraphEdge edge;
  edge.a = pair.a;
  edge.b = pair.b;
  const MedoidResult medoid = TransformMedoid(pair.a_from_b, medoid_options);
  if (medoid.index < 0) {
    edge.cost = std::numeric_limits<double>::infinity();
    return edge;
  }
  const int64_t total = std::max<int64_t>(pair.total_candidates, pair.a_from_b.size());
  const int n = static_cast<int>(pair.a_from_b.size());
  // The paper's medoid counts every candidate, so when most events keep both hypotheses of both squares
  // (3 wrong combinations for 1 right one) a tight cluster of wrong combinations can win. Other
  // proposals -- the medoid of the best-hypothesis combinations (first candidate of each event), the
  // medoid of the events with a single sure candidate -- compete by how many events they agree with;
  // ties keep the paper's medoid.
  std::vector<int> proposals = {medoid.index};
  {
    std::vector<Rigid3> firsts, sure;
    std::vector<int> firsts_index, sure_index;
    for (int i = 0; i < n; ++i) {
      if (i > 0 && pair.event[i] == pair.event[i - 1]) continue;
      firsts.push_back(pair.a_from_b[i]);
      firsts_index.push_back(i);
      if (i + 1 >= n || pair.event[i + 1] != pair.event[i]) {
        sure.push_back(pair.a_from_b[i]);
        sure_index.push_back(i);
      }
    }
    if (firsts.size() != static_cast<size_t>(n)) {
      const int f = TransformMedoid(firsts, medoid_options).index;
      if (f >= 0) proposals.push_back(firsts_index[f]);
      if (sure.size() >= 3) {
        const int s = TransformMedoid(sure, medoid_options).index;
        if (s >= 0) proposals.push_back(sure_index[s]);
      }
    }
  }
  // Proposals compete by the fixed tolerances alone (the covariances only widen what counts as support
  // for the chosen one): with the Mahalanobis test in the choice, a proposal that many poorly pinned frames
  // agree with won, and CameraGraphPlacesEveryCameraRelativeToTheReference's initial cameras were 54-66 mm
  // off (bound 50 mm; main's choice passes).
  ConsistencyOptions fixed = consistency;
  fixed.max_mahalanobis_sq = 0.0;
  int best = medoid.index, best_support = -1;
  for (int p : proposals) {
    const int support = EventSupport(pair, pair.a_from_b[p], fixed);
    if (support > best_support) {
      best_support = support;
      best = p;
    }
  }
  edge.a_from_b = pair.a_from_b[best];
  edge.support =
      consistency.max_mahalanobis_sq > 0 ? EventSupport(pair, edge.a_from_b, consistency) : best_support;
  // s counts every candidate, also those left out of a strided subset; d scales with it.
  MedoidResult scaled = medoid;
  scaled.index = best;
  scaled.num_candidates = static_cast<int>(std::min<int64_t>(total, INT32_MAX));
  if (n > 1) {
    const double mean =
        best == medoid.index
            ? medoid.MeanDistance()
            : SummedProbeDistance(pair.a_from_b, edge.a_from_b, medoid_options.point_scale) / (n - 1);
    scaled.summed_distance = mean * static_cast<double>(total - 1);
  }
  edge.cost = MedoidEdgeCost(scaled, tau_n);
  edge.candidates = total;
  edge.events = std::max<int64_t>(pair.total_events, pair.num_events);
  edge.stored_events = pair.num_events;
  return edge;
}

namespace {

// Two passes over co-observation events of node pairs: first count (Count), then store a strided
// subset (Store) so that memory stays bounded on long sequences.
class PairCollector {
 public:
  PairCollector(int num_nodes, int max_events) : n_(num_nodes), max_events_(max_events) {}
  void Count(int a, int b, int64_t candidates) {
    Slot& s = slots_[Key(a, b)];
    ++s.events;
    s.candidates += candidates;
  }
  void FinishCounting() {
    for (auto& kv : slots_) {
      kv.second.stride = std::max<int64_t>(1, (kv.second.events + max_events_ - 1) / max_events_);
      kv.second.pair.a = static_cast<int>(kv.first / n_);
      kv.second.pair.b = static_cast<int>(kv.first % n_);
      kv.second.pair.total_events = kv.second.events;
      kv.second.pair.total_candidates = kv.second.candidates;
    }
  }
  // Returns true when the event at this position is stored (then call Store with its candidates).
  bool Wanted(int a, int b) {
    Slot& s = slots_[Key(a, b)];
    return (s.seen++ % s.stride) == 0;
  }
  void Store(int a, int b, const std::vector<Rigid3>& candidates, const std::vector<Matrix6d>& covariances) {
    slots_[Key(a, b)].pair.AddEvent(candidates, covariances);
  }
  std::vector<PairCandidates*> Pairs() {
    std::vector<PairCandidates*> out;
    for (auto& kv : slots_) out.push_back(&kv.second.pair);
    std::sort(out.begin(), out.end(), [](const PairCandidates* x, const PairCandidates* y) {
      return std::make_pair(x->a, x->b) < std::make_pair(y->a, y->b);
    });
    return out;
  }

 private:
  struct Slot {
    int64_t events = 0, candidates = 0, stride = 1, seen = 0;
    PairCandidates pair;
  };
  int64_t Key(int a, int b) const { return static_cast<int64_t>(a) * n_ + b; }
  int n_;
  int max_events_;
  std::unordered_map<int64_t, Slot> slots_;
};

// fn(x, y) for every pair of items of a group, ordered so that items[x].node < items[y].node.
template <typename Fn>
void ForEachPair(const std::vector<GraphItem>& items, const Fn& fn) {
  for (size_t i = 0; i < items.size();) {
    size_t j = i;
    while (j < items.size() && items[j].group == items[i].group) ++j;
    for (size_t x = i; x < j; ++x)
      for (size_t y = x + 1; y < j; ++y) {
        if (items[x].node < items[y].node)
          fn(items[x], items[y]);
        else
          fn(items[y], items[x]);
      }
    i = j;
  }
}

}  // namespace

std::vector<PairCandidates> CollectPairs(const std::vector<GraphItem>& items, int num_nodes, int max_events) {
  PairCollector collector(std::max(1, num_nodes), max_events);
  ForEachPair(items, [&](const GraphItem& a, const GraphItem& b) {
    collector.Count(a.node, b.node,
                    static_cast<int64_t>(a.node_from_common.size() * b.common_from_node.size()));
  });
  collector.FinishCounting();
  std::vector<Rigid3> candidates;
  std::vector<Matrix6d> covariances;
  ForEachPair(items, [&](const GraphItem& a, const GraphItem& b) {
    if (!collector.Wanted(a.node, b.node)) return;
    candidates.clear();
    covariances.clear();
    const bool with_covariance = a.covariance.size() == a.node_from_common.size() &&
                                 b.covariance.size() == b.common_from_node.size() && !a.covariance.empty();
    for (size_t i = 0; i < a.node_from_common.size(); ++i)
      for (size_t j = 0; j < b.common_from_node.size(); ++j) {
        candidates.push_back(a.node_from_common[i] * b.common_from_node[j]);
        if (!with_covariance) continue;
        // x = A^-1 B with A = A0 Exp(da), B = B0 Exp(db): x = x0 Exp(db - Ad(x0^-1) da) to first order,
        // with core's Adjoint (rotation, translation).
        const Matrix6d adjoint = Adjoint(Inverse(candidates.back()));
        covariances.push_back(b.covariance[j] + adjoint * a.covariance[i] * adjoint.transpose());
      }
    collector.Store(a.node, b.node, candidates, covariances);
  });
  std::vector<PairCandidates> pairs;
  for (PairCandidates* p : collector.Pairs()) pairs.push_back(std::move(*p));
  return pairs;
}

std::vector<GraphEdge> EvaluateEdges(const std::vector<PairCandidates>& pairs, const EdgeOptions& options,
                                     int threads) {
  std::vector<GraphEdge> edges(pairs.size());
  ParallelFor(static_cast<int>(pairs.size()), threads, [&](int k) {
    edges[k] = EvaluateEdge(pairs[k], options.medoid, options.tau_n, options.consistency);
  });
  return edges;
}

std::vector<GraphEdge> BuildGraphEdges(const std::vector<GraphItem>& items, int num_nodes,
                                       const EdgeOptions& options, int threads) {
  return EvaluateEdges(CollectPairs(items, num_nodes, options.max_events), options, threads);
}

namespace {
struct UnionFind {
  std::vector<int> parent;
  explicit UnionFind(int n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int Find(int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  bool Join(int a, int b) {
    a = Find(a);
    b = Find(b);
    if (a == b) return false;
    parent[b] = a;
    return true;
  }
};
}  // namespace

std::vector<GraphEdge> MinimumSpanningTree(int n, std::vector<GraphEdge> edges,
                                           const std::vector<GraphEdge>& forest) {
  std::sort(edges.begin(), edges.end(), [](const GraphEdge& x, const GraphEdge& y) {
    const bool x_unconfirmed = !x.Confirmed(), y_unconfirmed = !y.Confirmed();
    return std::tie(x_unconfirmed, x.cost, x.a, x.b) < std::tie(y_unconfirmed, y.cost, y.a, y.b);
  });
  edges.insert(edges.begin(), forest.begin(), forest.end());
  UnionFind uf(n);
  std::vector<GraphEdge> tree;
  for (const GraphEdge& e : edges) {
    if (e.a < 0 || e.b < 0 || e.a >= n || e.b >= n || !std::isfinite(e.cost)) continue;
    if (uf.Join(e.a, e.b)) tree.push_back(e);
  }
  return tree;
}

int BestConnectedNode(int n, const std::vector<GraphEdge>& edges, const std::vector<bool>& eligible) {
  std::vector<int64_t> weight(n, 0);
  for (const GraphEdge& e : edges) {
    if (e.a < 0 || e.b < 0 || e.a >= n || e.b >= n) continue;
    weight[e.a] += e.candidates;
    weight[e.b] += e.candidates;
  }
  int best = -1;
  for (int i = 0; i < n; ++i) {
    if (!eligible.empty() && !eligible[i]) continue;
    if (weight[i] <= 0) continue;
    if (best < 0 || weight[i] > weight[best]) best = i;
  }
  return best;
}

std::vector<bool> ComponentOf(int n, int root, const std::vector<GraphEdge>& edges) {
  std::vector<bool> in(n, false);
  if (root < 0 || root >= n) return in;
  std::vector<std::vector<int>> adjacent(n);
  for (const GraphEdge& e : edges) {
    if (e.a < 0 || e.b < 0 || e.a >= n || e.b >= n) continue;
    adjacent[e.a].push_back(e.b);
    adjacent[e.b].push_back(e.a);
  }
  std::queue<int> todo;
  todo.push(root);
  in[root] = true;
  while (!todo.empty()) {
    const int x = todo.front();
    todo.pop();
    for (int y : adjacent[x])
      if (!in[y]) {
        in[y] = true;
        todo.push(y);
      }
  }
  return in;
}

TreePoses PosesFromTree(int n, int root, const std::vector<GraphEdge>& tree) {
  TreePoses out;
  out.root_from_node.assign(n, Rigid3::Identity());
  out.placed.assign(n, false);
  out.depth.assign(n, -1);
  if (root < 0 || root >= n) return out;
  // adjacency with the transform node_from_neighbour
  struct Link {
    int to;
    Rigid3 from_to;  // this_from_to
  };
  std::vector<std::vector<Link>> adjacent(n);
  for (const GraphEdge& e : tree) {
    adjacent[e.a].push_back({e.b, e.a_from_b});
    adjacent[e.b].push_back({e.a, Inverse(e.a_from_b)});
  }
  std::queue<int> todo;
  todo.push(root);
  out.placed[root] = true;
  out.depth[root] = 0;
  while (!todo.empty()) {
    const int x = todo.front();
    todo.pop();
    for (const Link& link : adjacent[x]) {
      if (out.placed[link.to]) continue;
      out.placed[link.to] = true;
      out.depth[link.to] = out.depth[x] + 1;
      out.root_from_node[link.to] = Normalized(out.root_from_node[x] * link.from_to);
      todo.push(link.to);
    }
  }
  return out;
}

int MedoidIndex(const std::vector<Rigid3>& candidates, double point_scale) {
  MedoidOptions options;
  options.point_scale = point_scale;
  return TransformMedoid(candidates, options).index;
}

}  // namespace mcmt
