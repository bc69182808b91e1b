// objects: auto / ids: auto (mapper/bodies_auto.h), as named steps:
//   Candidates (ids no declared body claims) -> observations and square hypotheses (the stages)
//   -> RigidPairs (the marker graph's edge builder, a stricter support) -> groups (connected components)
//   -> StaticInCameras (per marker and camera: its pose's medoid support over the session)
//   -> Judge (static or moving, foreign) -> Name.
#include "mapper/bodies_auto.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <sstream>

#include "core/json.h"
#include "core/objects.h"

namespace mcmt {
namespace {

// Ids seen in the messages that no declared body claims by explicit ids.
std::vector<int> Candidates(const std::vector<StoredMessage>& messages,
                            const std::vector<MapperBody>& declared) {
  std::set<int> claimed, seen;
  for (const MapperBody& b : declared)
    if (!b.auto_ids && !b.other) claimed.insert(b.ids.begin(), b.ids.end());
  for (const StoredMessage& m : messages)
    for (const StoredMarker& mk : m.markers)
      if (!claimed.count(mk.id)) seen.insert(mk.id);
  return std::vector<int>(seen.begin(), seen.end());
}

const MapperBody* FirstAuto(const std::vector<MapperBody>& bodies) {
  for (const MapperBody& b : bodies)
    if (b.auto_ids) return &b;
  return nullptr;
}

double MaxSide(const Observations& observations) {
  double side = 0.0;
  for (const Observation& ob : observations.obs) side = std::max(side, ob.side);
  return side;
}

// Marker pairs whose relative pose stays constant while they are seen together.
std::vector<GraphEdge> RigidPairs(const Observations& observations, const MapperOptions& o, int threads) {
  EdgeOptions edge_options;
  edge_options.max_events = o.max_pair_events;
  edge_options.medoid.point_scale = std::max(0.05, 2.0 * MaxSide(observations));
  edge_options.tau_n = o.tau_n;
  edge_options.consistency = ConsistencyFor(o);
  std::vector<GraphEdge> rigid;
  for (const GraphEdge& e :
       BuildGraphEdges(MarkerItems(observations), observations.NumMarkers(), edge_options, threads))
    if (e.stored_events >= o.min_marker_support && e.SupportFraction() >= kRigidFraction) rigid.push_back(e);
  return rigid;
}

// Per marker: the cameras that see it in enough frames to judge, and those in which its pose never
// changes. A static marker's pose in a camera varies by the noise of one square's pose (a degree or two,
// millimetres in depth): tighter than the marker graph's thresholds, whose relative term would allow
// centimetres at a camera's distance.
struct MarkerMotion {
  std::set<int> cameras;      // that see it
  int judged = 0, still = 0;  // cameras with enough frames, of which static
  int views = 0;              // observations with a kept hypothesis
};

std::vector<MarkerMotion> StaticInCameras(const Observations& observations, const MapperOptions& o) {
  const int n = observations.NumMarkers();
  std::vector<MarkerMotion> motion(n);
  std::map<std::pair<int, int>, std::vector<int>> seen;  // (marker, camera) -> observations
  for (size_t i = 0; i < observations.obs.size(); ++i) {
    const Observation& ob = observations.obs[i];
    if (ob.kept == 0) continue;
    seen[{ob.marker, ob.camera}].push_back(static_cast<int>(i));
    motion[ob.marker].cameras.insert(ob.camera);
    ++motion[ob.marker].views;
  }
  MedoidOptions medoid;
  medoid.point_scale = std::max(0.05, 2.0 * MaxSide(observations));
  ConsistencyOptions still;
  still.max_angle_rad = 5.0 * M_PI / 180.0;
  still.max_distance_m = 0.01;
  still.max_distance_rel = 0.01;
  for (const auto& [key, obs] : seen) {
    if (static_cast<int>(obs.size()) < o.min_marker_support) continue;
    PairCandidates pair;
    const size_t stride = std::max<size_t>(1, (obs.size() + o.max_pair_events - 1) / o.max_pair_events);
    for (size_t k = 0; k < obs.size(); k += stride) {
      const Observation& ob = observations.obs[obs[k]];
      std::vector<Rigid3> candidates;
      const SquarePose& pose = observations.poses[obs[k]];
      for (int h = 0; h < ob.kept; ++h) candidates.push_back(pose.hypotheses[h].cam_from_marker);
      pair.AddEvent(candidates);
    }
    const GraphEdge e = EvaluateEdge(pair, medoid, o.tau_n, still);
    MarkerMotion& m = motion[key.first];
    ++m.judged;
    m.still += e.SupportFraction() >= kStaticFraction;
  }
  return motion;
}

std::string UniqueName(const std::string& stem, std::set<std::string>* taken) {
  for (int k = 1;; ++k) {
    const std::string name = stem + "_" + std::to_string(k);
    if (taken->insert(name).second) return name;
  }
}

}  // namespace

bool HasAutoBodies(const std::vector<MapperBody>& bodies) { return FirstAuto(bodies) != nullptr; }

AutoBodies GroupIntoBodies(const std::vector<StoredMessage>& messages,
                           const std::vector<MapperBody>& declared, const BodiesInputs& in,
                           const MapperOptions& o, int threads) {
  AutoBodies out;
  out.ran = true;
  const std::vector<int> ids = Candidates(messages, declared);
  if (ids.empty()) return out;
  MapperOptions options = o;
  options.marker_ids = ids;
  options.bodies.clear();
  if (const MapperBody* first = FirstAuto(declared)) options.sizes = first->sizes;
  const std::vector<Frame> frames =
      AssembleFrames(messages, static_cast<int>(in.camera_names.size()), o.sync_tolerance_us());
  MapReport scratch;
  Observations observations = CollectObservations(messages, frames, in.camera_names, options, &scratch);
  EstimateHypotheses(in.models, options.tau_e, threads, &observations);
  const int n = observations.NumMarkers();
  const std::vector<GraphEdge> rigid = RigidPairs(observations, options, threads);
  const std::vector<MarkerMotion> motion = StaticInCameras(observations, options);

  // Foreign markers first (they join no group): too rarely seen, or static in one camera's view only
  // (rigid with everything static in that view, so it would otherwise join the room).
  const int min_views = std::max(10, o.min_marker_support);
  std::vector<char> foreign(n, 0), paired(n, 0);
  for (const GraphEdge& e : rigid) paired[e.a] = paired[e.b] = 1;
  for (int m = 0; m < n; ++m) {
    const MarkerMotion& mm = motion[m];
    std::string why;
    if (mm.views < min_views && !paired[m]) {
      why = "seen in only " + std::to_string(mm.views) + " camera frames (fewer than " +
            std::to_string(min_views) +
            "), never rigidly with another marker: too few to tell which body "
            "it is on";
    } else if (mm.judged > 0 && mm.still == mm.judged && mm.cameras.size() < 2) {
      why = "static in the view of one camera only (" + in.camera_names[*mm.cameras.begin()] +
            "): constrains nothing, and a false detection stuck in the image looks the same";
    }
    if (why.empty()) continue;
    foreign[m] = 1;
    out.foreign.push_back({observations.marker_ids[m], mm.views, why});
  }
  std::vector<GraphEdge> kept;
  for (const GraphEdge& e : rigid)
    if (!foreign[e.a] && !foreign[e.b]) kept.push_back(e);

  // Groups: connected by rigid pairs; static when every marker is.
  std::vector<char> grouped = foreign;
  std::vector<FoundBody> found;
  for (int m = 0; m < n; ++m) {
    if (grouped[m]) continue;
    const std::vector<bool> component = ComponentOf(n, m, kept);
    FoundBody body;
    std::set<int> cameras;
    bool all_still = true, any_judged = false;
    for (int k = 0; k < n; ++k) {
      if ((!component[k] && k != m) || grouped[k]) continue;
      grouped[k] = 1;
      body.ids.push_back(observations.marker_ids[k]);
      body.observations += motion[k].views;
      cameras.insert(motion[k].cameras.begin(), motion[k].cameras.end());
      any_judged = any_judged || motion[k].judged > 0;
      all_still = all_still && motion[k].still == motion[k].judged;
    }
    std::sort(body.ids.begin(), body.ids.end());
    body.is_static = any_judged && all_still;
    for (int c : cameras) body.cameras.push_back(in.camera_names[c]);
    found.push_back(std::move(body));
  }
  std::stable_sort(found.begin(), found.end(),
                   [](const FoundBody& a, const FoundBody& b) { return a.observations > b.observations; });
  std::sort(out.foreign.begin(), out.foreign.end(),
            [](const ForeignId& a, const ForeignId& b) { return a.id < b.id; });

  // Names: every `ids: auto` body takes the largest found body of its kind left; the rest are numbered.
  std::set<std::string> taken;
  for (const MapperBody& b : declared)
    if (!b.name.empty()) taken.insert(b.name);
  std::vector<char> used(found.size(), 0);
  for (const MapperBody& b : declared) {
    if (!b.auto_ids || b.name.empty()) continue;
    for (size_t k = 0; k < found.size(); ++k)
      if (!used[k] && found[k].is_static == b.is_static) {
        used[k] = 1;
        found[k].name = b.name;
        found[k].declared_as = b.name;
        break;
      }
  }
  for (size_t k = 0; k < found.size(); ++k)
    if (!used[k]) found[k].name = UniqueName(found[k].is_static ? "static" : "body", &taken);
  out.bodies = std::move(found);
  return out;
}

std::vector<MapperBody> ResolveAutoBodies(const std::vector<MapperBody>& declared, const AutoBodies& found,
                                          MapReport* report) {
  std::vector<MapperBody> out;
  const MapperBody* first = FirstAuto(declared);
  for (const MapperBody& b : declared) {
    if (!b.auto_ids) {
      out.push_back(b);
      continue;
    }
    if (b.name.empty()) continue;
    const bool taken = std::any_of(found.bodies.begin(), found.bodies.end(),
                                   [&](const FoundBody& f) { return f.declared_as == b.name; });
    if (!taken)
      report->warnings.push_back("object '" + b.name + "' (ids: auto): no " +
                                 (b.is_static ? "static" : "moving") + " body was found for it: left out");
  }
  for (const FoundBody& f : found.bodies) {
    MapperBody body;
    body.name = f.name;
    body.is_static = f.is_static;
    body.ids = f.ids;
    body.sizes = first ? first->sizes : MarkerSizes();
    out.push_back(body);
  }
  return out;
}

std::string ObjectsSectionYaml(const std::vector<MapperBody>& bodies, const std::string& rig_frame) {
  std::ostringstream s;
  s << "# The rig's bodies as mcmt-mapper found them (objects: auto / ids: auto); paste into rig.yaml.\n";
  s << "objects:\n";
  const MapperBody* largest_static = nullptr;
  for (const MapperBody& b : bodies) {
    s << "  - name: " << b.name << "\n    ids: ";
    if (b.other) {
      s << "other\n";
    } else {
      std::string ids = DescribeIds(std::set<int>(b.ids.begin(), b.ids.end())), item;
      std::istringstream items(ids);
      s << "[";
      for (bool first = true; std::getline(items, item, ','); first = false) {
        if (item[0] == ' ') item.erase(0, 1);
        s << (first ? "" : ", ") << (item.find('-') != std::string::npos ? "\"" + item + "\"" : item);
      }
      s << "]\n";
    }
    s << "    size: " << b.sizes.default_size << "\n";
    std::vector<std::pair<int, double>> overrides;
    for (const auto& [id, size] : b.sizes.overrides)
      if (b.other || std::binary_search(b.ids.begin(), b.ids.end(), id)) overrides.emplace_back(id, size);
    if (!overrides.empty()) {
      s << "    sizes: {";
      for (size_t k = 0; k < overrides.size(); ++k)
        s << (k ? ", " : "") << overrides[k].first << ": " << overrides[k].second;
      s << "}\n";
    }
    if (b.is_static) {
      s << "    static: true\n";
      if (!largest_static) largest_static = &b;
    }
  }
  if (!rig_frame.empty())
    s << "rig_frame: " << rig_frame << "\n";
  else if (largest_static)
    s << "# rig_frame: " << largest_static->name << "   # the static body's frame as the rig frame\n";
  return s.str();
}

std::string AutoBodiesJson(const AutoBodies& found) {
  if (!found.ran) return "";
  std::ostringstream j;
  j << "  \"auto_objects\": {\n    \"bodies\": [";
  for (size_t k = 0; k < found.bodies.size(); ++k) {
    const FoundBody& b = found.bodies[k];
    j << (k ? "," : "") << "\n      {\"name\": " << JsonString(b.name)
      << ", \"static\": " << (b.is_static ? "true" : "false") << ", \"ids\": [";
    for (size_t i = 0; i < b.ids.size(); ++i) j << (i ? ", " : "") << b.ids[i];
    j << "], \"observations\": " << b.observations << ", \"cameras\": [";
    for (size_t i = 0; i < b.cameras.size(); ++i) j << (i ? ", " : "") << JsonString(b.cameras[i]);
    j << "]" << (b.declared_as.empty() ? "" : ", \"declared\": true") << "}";
  }
  j << "],\n    \"foreign\": [";
  for (size_t k = 0; k < found.foreign.size(); ++k) {
    const ForeignId& f = found.foreign[k];
    j << (k ? "," : "") << "\n      {\"id\": " << f.id << ", \"observations\": " << f.observations
      << ", \"reason\": " << JsonString(f.reason) << "}";
  }
  j << "],\n    \"objects_yaml\": " << JsonString(found.objects_yaml) << "\n  },\n";
  return j.str();
}

}  // namespace mcmt
