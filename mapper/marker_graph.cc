// Stage: the marker graph (the paper's step 3), which also finds the ids that are not on the object.
#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

#include "core/math.h"
#include "mapper/stages.h"

namespace mcmt {
namespace {

std::string JoinIds(const std::vector<int>& ids, size_t max = 12) {
  std::vector<std::string> s;
  for (int id : ids) s.push_back(std::to_string(id));
  return JoinNames(s, max);
}

int ReferenceMarker(const Observations& observations, const std::vector<GraphEdge>& verified,
                    const std::vector<int>& counts, const MapperOptions& o) {
  if (o.reference_marker >= 0) {
    auto it = observations.marker_index.find(o.reference_marker);
    if (it == observations.marker_index.end())
      throw MapperError("reference marker " + std::to_string(o.reference_marker) +
                        " (mapper.reference_marker) was never detected");
    return it->second;
  }
  int reference = BestConnectedNode(observations.NumMarkers(), verified);
  if (reference < 0)  // no verified pair at all: a single-marker object
    for (int m = 0; m < observations.NumMarkers(); ++m)
      if (reference < 0 || counts[m] > counts[reference]) reference = m;
  return reference;
}

// Why marker m is not placed: a false id (co-observed with placed markers, but inconsistently), too
// rarely co-observed to verify, or (empty reason) disconnected: never seen with a placed marker.
std::string WhyNotPlaced(int m, const MarkerLayout& layout, const std::vector<int>& ids,
                         const MapperOptions& o) {
  int64_t with_placed = 0;
  int best_support = 0, best_other = -1;
  int64_t best_events = 0;
  for (const GraphEdge& e : layout.edges) {
    if (e.a != m && e.b != m) continue;
    const int other = e.a == m ? e.b : e.a;
    if (!layout.placed[other]) continue;
    with_placed += e.events;
    if (best_other < 0 || e.support > best_support) {
      best_support = e.support;
      best_events = e.stored_events;
      best_other = other;
    }
  }
  const int seen = layout.observations[m];
  if (with_placed >= o.min_marker_support) {
    std::ostringstream why;
    why << "not rigidly attached: its pose relative to marker " << ids[best_other] << " agrees in only "
        << best_support << " of " << best_events << " frames seen together";
    return why.str();
  }
  if (with_placed > 0)
    return "seen together with the object's markers in only " + std::to_string(with_placed) +
           " frames (< min_marker_support " + std::to_string(o.min_marker_support) +
           "): cannot verify it is on the object";
  if (seen < std::max(10, o.min_marker_support))
    return "seen in only " + std::to_string(seen) +
           " camera frames, never together with the object's markers: cannot verify it is on the object";
  return "";
}

bool Declared(int id, const MapperOptions& o) {
  return std::find(o.marker_ids.begin(), o.marker_ids.end(), id) != o.marker_ids.end();
}

// Markers the rig declares (markers.ids) rejected as not rigidly attached or unverifiable: when they hold
// more of the declared markers' observations than the placed ones, the square poses of this session
// disagree more often than they agree (ambiguous at grazing views, biased corners), and the placed
// markers' layout rests on the same kind of poses: an error (a warning with --allow-partial), not a map.
void CheckRejectedDeclaredMarkers(const MarkerLayout& layout, const std::vector<int>& ids,
                                  const std::vector<std::pair<int, std::string>>& rejected,
                                  const MapperOptions& o, MapReport* report) {
  int64_t placed_obs = 0, rejected_obs = 0;
  std::vector<int> placed_ids, rejected_ids;
  for (int m = 0; m < static_cast<int>(ids.size()); ++m)
    if (layout.placed[m] && Declared(ids[m], o)) {
      placed_obs += layout.observations[m];
      placed_ids.push_back(ids[m]);
    }
  for (const auto& [m, why] : rejected)
    if (Declared(ids[m], o)) {
      rejected_obs += layout.observations[m];
      rejected_ids.push_back(ids[m]);
    }
  if (rejected_obs <= placed_obs) return;
  std::sort(rejected_ids.begin(), rejected_ids.end());
  const auto first = std::find_if(rejected.begin(), rejected.end(),
                                  [&](const auto& r) { return Declared(ids[r.first], o); });
  std::ostringstream msg;
  msg << "marker" << (rejected_ids.size() > 1 ? "s " : " ") << JoinIds(rejected_ids)
      << " of markers.ids cannot be placed on the object (marker " << ids[first->first] << ": "
      << first->second << ") and hold " << rejected_obs << " of the " << rejected_obs + placed_obs
      << " observations of the object's markers: the markers' poses seen together disagree more than they "
         "agree, so the layout of marker"
      << (placed_ids.size() > 1 ? "s " : " ") << JoinIds(placed_ids)
      << " rests on the same doubtful poses; record frames where a camera sees two markers at once less "
         "obliquely";
  if (!o.allow_partial) throw MapperError(msg.str() + " (or use --allow-partial to map without them)");
  report->warnings.push_back(msg.str() + ": mapped without them (--allow-partial)");
}

void ReportDisconnectedMarkers(const MarkerLayout& layout, const std::vector<int>& ids,
                               const std::vector<int>& disconnected, const MapperOptions& o,
                               MapReport* report) {
  std::vector<int> lost, placed_ids;
  for (int m : disconnected) lost.push_back(ids[m]);
  for (int m = 0; m < static_cast<int>(ids.size()); ++m)
    if (layout.placed[m]) placed_ids.push_back(ids[m]);
  std::ostringstream msg;
  msg << "marker" << (lost.size() > 1 ? "s " : " ") << JoinIds(lost)
      << " cannot be placed on the object: never seen "
      << "by one camera in one frame together with a marker connected to the reference marker "
      << ids[layout.reference] << " (" << JoinIds(placed_ids)
      << "); record frames where a camera sees marker " << lost[0] << " together with one of those";
  if (!o.allow_partial) throw MapperError(msg.str() + " (or use --allow-partial to map without it)");
  report->warnings.push_back(msg.str() + ": left out (--allow-partial)");
  for (int m : disconnected)
    report->rejected_markers.push_back(
        {ids[m], layout.observations[m], "disconnected (left out by --allow-partial)"});
}

void ReportUnplacedMarkers(const MarkerLayout& layout, const std::vector<int>& ids, const MapperOptions& o,
                           MapReport* report) {
  std::vector<int> disconnected;
  std::vector<std::pair<int, std::string>> rejected;
  for (int m = 0; m < static_cast<int>(ids.size()); ++m) {
    if (layout.placed[m]) continue;
    const std::string why = WhyNotPlaced(m, layout, ids, o);
    if (why.empty()) {
      disconnected.push_back(m);
      continue;
    }
    report->rejected_markers.push_back({ids[m], layout.observations[m], why});
    rejected.emplace_back(m, why);
  }
  // A disconnected marker's error first (what would connect it); the rejected ones' after it.
  if (!disconnected.empty()) ReportDisconnectedMarkers(layout, ids, disconnected, o, report);
  CheckRejectedDeclaredMarkers(layout, ids, rejected, o, report);
}

// chi^2 with 6 degrees of freedom at 0.999 (MapperOptions::consistency_noise_px).
constexpr double kPoseNoiseChiSquare = 22.46;

bool IsVerified(const GraphEdge& e, const MapperOptions& o) {
  return e.support >= o.min_marker_support && e.SupportFraction() >= o.marker_inlier_fraction;
}

// The paper's step 2 on single markers: two cameras that see one marker in one frame give candidates of
// their relative pose, whatever the layout. A preliminary rig (only confirmed edges), used only to check
// the layout against the views of different cameras.
TreePoses CamerasFromSingleMarkers(const Observations& observations, EdgeOptions options, int threads) {
  const std::vector<Observation>& obs = observations.obs;
  std::vector<int> order;
  std::vector<double> depths;
  int num_cameras = 0;
  for (int i = 0; i < static_cast<int>(obs.size()); ++i) {
    if (obs[i].kept == 0) continue;
    order.push_back(i);
    num_cameras = std::max(num_cameras, obs[i].camera + 1);
    depths.push_back(observations.poses[i].best().cam_from_marker.translation().norm());
  }
  const auto key = [&](int i) { return std::make_pair(obs[i].frame, obs[i].marker); };
  std::stable_sort(order.begin(), order.end(), [&](int x, int y) { return key(x) < key(y); });
  std::vector<GraphItem> items(order.size());
  for (size_t k = 0; k < order.size(); ++k) {
    const Observation& ob = obs[order[k]];
    const SquarePose& pose = observations.poses[order[k]];
    items[k].group = k == 0 ? 0 : items[k - 1].group + (key(order[k]) != key(order[k - 1]));
    items[k].node = ob.camera;
    for (int h = 0; h < ob.kept; ++h) {
      items[k].node_from_common.push_back(pose.hypotheses[h].cam_from_marker);
      items[k].common_from_node.push_back(Inverse(pose.hypotheses[h].cam_from_marker));
    }
  }
  options.medoid.point_scale = std::max(0.1, Median(depths));
  std::vector<GraphEdge> confirmed;
  for (const GraphEdge& e : BuildGraphEdges(items, num_cameras, options, threads))
    if (e.Confirmed()) confirmed.push_back(e);
  return PosesFromTree(num_cameras, BestConnectedNode(num_cameras, confirmed),
                       MinimumSpanningTree(num_cameras, confirmed));
}

// Marker pairs seen in one frame by the preliminary rig's cameras: per frame and marker the observation
// that sees it most face-on (where its square pose is surest), rig_from_marker per kept hypothesis.
std::vector<PairCandidates> RigPairs(const Observations& observations, const TreePoses& rig, int max_events) {
  std::vector<GraphItem> items;
  std::vector<double> facing;  // per item
  for (size_t i = 0; i < observations.obs.size(); ++i) {
    const Observation& ob = observations.obs[i];
    const SquarePose& pose = observations.poses[i];
    if (ob.kept == 0 || ob.camera >= static_cast<int>(rig.placed.size()) || !rig.placed[ob.camera]) continue;
    int same = -1;
    for (int k = static_cast<int>(items.size()) - 1; k >= 0 && items[k].group == ob.frame; --k)
      if (items[k].node == ob.marker) same = k;
    const double cosine = FacingCosine(pose.best().cam_from_marker);
    if (same >= 0 && facing[same] >= cosine) continue;
    GraphItem item;
    item.group = ob.frame;
    item.node = ob.marker;
    for (int h = 0; h < ob.kept; ++h) {
      item.common_from_node.push_back(rig.root_from_node[ob.camera] * pose.hypotheses[h].cam_from_marker);
      item.node_from_common.push_back(Inverse(item.common_from_node.back()));
    }
    if (same >= 0) {
      items[same] = std::move(item);
      facing[same] = cosine;
    } else {
      items.push_back(std::move(item));
      facing.push_back(cosine);
    }
  }
  return CollectPairs(items, observations.NumMarkers(), max_events);
}

// Issue 15: neighbouring faces seen together by one camera only at grazing angles, where one square's pose
// flips the same way in most of their shared frames, give a verified but wrong relative pose. Each pair is
// checked against the rig's views (the pair seen in one frame by any cameras, each marker where its pose
// is surest): a verified edge that they clearly contradict is replaced by theirs (the rig's edge verified,
// different, and supported by more than twice the rig's frames that support the edge), an unverified one
// they verify is taken from them. The rig's edges are evaluated only where they can decide.
class RigCheck {
 public:
  RigCheck(const Observations& observations, const EdgeOptions& options, const MapperOptions& o, int threads)
      : options_(options), o_(o), threads_(threads) {
    pairs_ =
        RigPairs(observations, CamerasFromSingleMarkers(observations, options, threads), options.max_events);
    for (size_t k = 0; k < pairs_.size(); ++k) index_[{pairs_[k].a, pairs_[k].b}] = k;
  }

  std::vector<GraphEdge> Verified(const std::vector<GraphEdge>& edges, const std::vector<int>& ids,
                                  MapReport* report) const {
    std::vector<GraphEdge> out;
    for (const GraphEdge& e : edges) {
      const auto it = index_.find({e.a, e.b});
      const PairCandidates* pair = it == index_.end() ? nullptr : &pairs_[it->second];
      const bool verified = IsVerified(e, o_);
      const int rig_support = pair && verified ? EventSupport(*pair, e.a_from_b, options_.consistency) : 0;
      if (!pair || (verified && 2 * rig_support >= pair->num_events)) {
        if (verified) out.push_back(e);
        continue;
      }
      const GraphEdge r = EvaluateEdge(*pair, options_.medoid, options_.tau_n, options_.consistency);
      if (!IsVerified(r, o_)) {
        if (verified) out.push_back(e);
      } else if (!verified) {
        out.push_back(r);
      } else if (Consistent(e.a_from_b, r.a_from_b, options_.consistency) || 2 * rig_support >= r.support) {
        out.push_back(e);
      } else {
        report->warnings.push_back(
            "markers " + std::to_string(ids[e.a]) + " and " + std::to_string(ids[e.b]) +
            ": their relative pose seen by one camera (agreeing in " + std::to_string(e.support) + " of " +
            std::to_string(e.stored_events) + " frames) is contradicted by the views of several cameras (" +
            std::to_string(r.support) + " of " + std::to_string(r.stored_events) +
            " frames agree on another, " + std::to_string(rig_support) +
            " with it): taken from those (square poses flipped at grazing views)");
        out.push_back(r);
      }
    }
    return out;
  }

  // The rig's verified edges of pairs that no camera saw together (not in `edges`).
  std::vector<GraphEdge> Bridges(const std::vector<GraphEdge>& edges) const {
    std::vector<PairCandidates> unseen;
    for (const PairCandidates& pair : pairs_)
      if (std::none_of(edges.begin(), edges.end(),
                       [&](const GraphEdge& e) { return e.a == pair.a && e.b == pair.b; }))
        unseen.push_back(pair);
    std::vector<GraphEdge> bridges;
    for (const GraphEdge& r : EvaluateEdges(unseen, options_, threads_))
      if (IsVerified(r, o_)) bridges.push_back(r);
    return bridges;
  }

 private:
  EdgeOptions options_;
  const MapperOptions& o_;
  int threads_;
  std::vector<PairCandidates> pairs_;
  std::map<std::pair<int, int>, size_t> index_;
};

}  // namespace

std::vector<GraphItem> MarkerItems(const Observations& observations, double pose_noise_px) {
  std::vector<GraphItem> items;
  for (size_t i = 0; i < observations.obs.size(); ++i) {
    const Observation& ob = observations.obs[i];
    if (ob.kept == 0) continue;
    GraphItem item;
    item.group = ob.view;
    item.node = ob.marker;
    const double side_px = MeanSideLength(ob.corners);
    for (int h = 0; h < ob.kept; ++h) {
      const Rigid3& cam_from_marker = observations.poses[i].hypotheses[h].cam_from_marker;
      item.node_from_common.push_back(Inverse(cam_from_marker));
      item.common_from_node.push_back(cam_from_marker);
      if (pose_noise_px > 0)
        item.covariance.push_back(SquarePoseCovariance(cam_from_marker, ob.side, side_px, pose_noise_px));
    }
    items.push_back(std::move(item));
  }
  return items;
}

ConsistencyOptions ConsistencyFor(const MapperOptions& o) {
  ConsistencyOptions consistency;
  consistency.max_angle_rad = o.consistency_deg * M_PI / 180.0;
  consistency.max_distance_m = o.consistency_m;
  consistency.max_distance_rel = o.consistency_rel;
  return consistency;
}

double MarkerLayout::ObjectScale() const {
  double scale = 0.0;
  for (size_t m = 0; m < placed.size(); ++m)
    if (placed[m]) scale = std::max(scale, object_from_marker[m].translation().norm());
  return std::max(scale, 0.05);
}

MarkerLayout BuildMarkerGraph(const Observations& observations, const MapperOptions& o, int threads,
                              MapReport* report) {
  const int n = observations.NumMarkers();
  MarkerLayout layout;
  layout.observations.assign(n, 0);
  double max_side = 0.0;
  for (const Observation& ob : observations.obs) {
    if (ob.kept > 0) ++layout.observations[ob.marker];
    max_side = std::max(max_side, ob.side);
  }
  EdgeOptions edge_options;
  edge_options.max_events = o.max_pair_events;
  edge_options.medoid.point_scale = std::max(0.05, 2.0 * max_side);
  edge_options.tau_n = o.tau_n;
  edge_options.consistency = ConsistencyFor(o);
  edge_options.consistency.max_mahalanobis_sq = kPoseNoiseChiSquare;
  layout.edges = BuildGraphEdges(MarkerItems(observations, o.consistency_noise_px), n, edge_options, threads);
  const RigCheck rig(observations, edge_options, o, threads);
  const std::vector<GraphEdge> verified = rig.Verified(layout.edges, observations.marker_ids, report);
  // The reference as the paper chooses it, from the edges one camera verifies (the rig's edges count
  // their candidates differently): a session whose edges the rig confirms keeps its frame.
  std::vector<GraphEdge> seen_verified;
  for (const GraphEdge& e : layout.edges)
    if (IsVerified(e, o)) seen_verified.push_back(e);
  layout.reference =
      ReferenceMarker(observations, seen_verified.empty() ? verified : seen_verified, layout.observations, o);
  layout.placed = ComponentOf(n, layout.reference, verified);
  // Pairs that no camera saw together join only markers the other edges leave unplaced.
  std::vector<GraphEdge> bridges;
  if (std::count(layout.placed.begin(), layout.placed.end(), false) > 0) {
    bridges = rig.Bridges(layout.edges);
    std::vector<GraphEdge> all = verified;
    all.insert(all.end(), bridges.begin(), bridges.end());
    layout.placed = ComponentOf(n, layout.reference, all);
  }
  ReportUnplacedMarkers(layout, observations.marker_ids, o, report);
  const auto inside = [&](std::vector<GraphEdge> edges) {
    edges.erase(
        std::remove_if(edges.begin(), edges.end(),
                       [&](const GraphEdge& e) { return !layout.placed[e.a] || !layout.placed[e.b]; }),
        edges.end());
    return edges;
  };
  const std::vector<GraphEdge> tree =
      MinimumSpanningTree(n, inside(bridges), MinimumSpanningTree(n, inside(verified)));
  layout.object_from_marker = PosesFromTree(n, layout.reference, tree).root_from_node;
  return layout;
}

}  // namespace mcmt
