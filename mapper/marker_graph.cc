// Stage: the marker graph (the paper's step 3), which also finds the ids that are not on the object.
#include <algorithm>
#include <cmath>
#include <sstream>

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

}  // namespace

std::vector<GraphItem> MarkerItems(const std::vector<Observation>& obs) {
  std::vector<GraphItem> items;
  for (const Observation& ob : obs) {
    if (ob.kept == 0) continue;
    GraphItem item;
    item.group = ob.view;
    item.node = ob.marker;
    for (int h = 0; h < ob.kept; ++h) {
      item.node_from_common.push_back(Inverse(ob.pose.hypotheses[h].cam_from_marker));
      item.common_from_node.push_back(ob.pose.hypotheses[h].cam_from_marker);
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
  layout.edges = BuildGraphEdges(MarkerItems(observations.obs), n, edge_options, threads);
  std::vector<GraphEdge> verified;
  for (const GraphEdge& e : layout.edges)
    if (e.support >= o.min_marker_support && e.SupportFraction() >= o.marker_inlier_fraction)
      verified.push_back(e);
  layout.reference = ReferenceMarker(observations, verified, layout.observations, o);
  layout.placed = ComponentOf(n, layout.reference, verified);
  ReportUnplacedMarkers(layout, observations.marker_ids, o, report);
  std::vector<GraphEdge> inside;
  for (const GraphEdge& e : verified)
    if (layout.placed[e.a] && layout.placed[e.b]) inside.push_back(e);
  layout.object_from_marker =
      PosesFromTree(n, layout.reference, MinimumSpanningTree(n, inside)).root_from_node;
  return layout;
}

}  // namespace mcmt
