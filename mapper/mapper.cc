#include "mapper/mapper.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <numeric>
#include <sstream>
#include <thread>
#include <unordered_map>

#include "core/ippe.h"
#include "core/lcm_util.h"
#include "core/medoid.h"
#include "mapper/bundle.h"
#include "mapper/graph.h"

namespace mcmt {

// ---------------------------------------------------------------------------------------------
// Options

MapperOptions MapperOptions::FromConfig(const RigConfig& rig) {
  MapperOptions o;
  const YamlSection& s = rig.mapper;
  s.CheckKnownKeys({"tau_e",
                    "tau_n",
                    "huber_px",
                    "outlier_px",
                    "max_rejection_rounds",
                    "max_iterations",
                    "paper_stop",
                    "paper_stop_px",
                    "threads",
                    "linear_solver",
                    "refine",
                    "reference_camera",
                    "reference_marker",
                    "allow_partial",
                    "min_marker_support",
                    "marker_inlier_fraction",
                    "consistency_deg",
                    "consistency_m",
                    "consistency_rel",
                    "marker_reject_fraction",
                    "max_pair_events",
                    "continuity_gap_s"});
  o.tau_e = s.GetPositiveDouble("tau_e", o.tau_e);
  o.tau_n = s.GetPositiveDouble("tau_n", o.tau_n);
  o.huber_px = s.GetDouble("huber_px", o.huber_px);
  o.outlier_px = s.GetPositiveDouble("outlier_px", o.outlier_px);
  o.max_rejection_rounds = s.GetInt("max_rejection_rounds", o.max_rejection_rounds);
  o.max_iterations = s.GetInt("max_iterations", o.max_iterations);
  o.paper_stop = s.GetBool("paper_stop", o.paper_stop);
  o.paper_stop_px = s.GetPositiveDouble("paper_stop_px", o.paper_stop_px);
  o.threads = s.GetInt("threads", o.threads);
  o.linear_solver = s.GetString("linear_solver", o.linear_solver);
  o.refine = s.GetBool("refine", o.refine);
  o.reference_camera = rig.reference_camera;
  o.reference_marker = s.GetInt("reference_marker", o.reference_marker);
  o.allow_partial = s.GetBool("allow_partial", o.allow_partial);
  o.min_marker_support = s.GetInt("min_marker_support", o.min_marker_support);
  o.marker_inlier_fraction = s.GetDouble("marker_inlier_fraction", o.marker_inlier_fraction);
  o.consistency_deg = s.GetPositiveDouble("consistency_deg", o.consistency_deg);
  o.consistency_m = s.GetDouble("consistency_m", o.consistency_m);
  o.consistency_rel = s.GetDouble("consistency_rel", o.consistency_rel);
  o.marker_reject_fraction = s.GetDouble("marker_reject_fraction", o.marker_reject_fraction);
  o.max_pair_events = s.GetInt("max_pair_events", o.max_pair_events);
  o.continuity_gap_s = s.GetDouble("continuity_gap_s", o.continuity_gap_s);
  if (rig.sync.Has("tolerance_ms"))
    o.sync_tolerance_us =
        static_cast<int64_t>(std::llround(rig.sync.GetPositiveDouble("tolerance_ms", 2.0) * 1000));
  for (const CameraConfig& c : rig.cameras) o.cameras.push_back(c.name);
  o.marker_ids = rig.markers.ids;
  o.sizes = rig.markers.Sizes();
  o.dictionary = rig.markers.dictionary;
  auto fail = [&](const std::string& key, const std::string& what) { s.Fail(key, what); };
  if (o.max_iterations < 1) fail("max_iterations", "must be at least 1");
  if (o.threads < 0) fail("threads", "must be >= 0 (0: all cores)");
  if (o.max_rejection_rounds < 0) fail("max_rejection_rounds", "must be >= 0");
  if (o.min_marker_support < 1) fail("min_marker_support", "must be at least 1");
  if (o.max_pair_events < 10) fail("max_pair_events", "must be at least 10");
  if (!(o.continuity_gap_s >= 0)) fail("continuity_gap_s", "must be >= 0 (0: no continuity)");
  if (!(o.marker_inlier_fraction >= 0 && o.marker_inlier_fraction <= 1))
    fail("marker_inlier_fraction", "must be in [0, 1]");
  if (!(o.marker_reject_fraction > 0 && o.marker_reject_fraction <= 1))
    fail("marker_reject_fraction", "must be in (0, 1]");
  static const std::set<std::string> solvers = {"auto", "sparse_schur", "dense_schur", "iterative_schur"};
  if (!solvers.count(o.linear_solver))
    fail("linear_solver",
         "unknown '" + o.linear_solver + "' (auto, sparse_schur, dense_schur, iterative_schur)");
  if (!o.reference_camera.empty() && !rig.FindCamera(o.reference_camera))
    fail("reference_camera", "no camera named '" + o.reference_camera + "'");
  if (o.reference_marker >= 0 && !o.marker_ids.empty() &&
      std::find(o.marker_ids.begin(), o.marker_ids.end(), o.reference_marker) == o.marker_ids.end())
    fail("reference_marker", std::to_string(o.reference_marker) + " is not in markers.ids");
  o.Validate();
  return o;
}

void MapperOptions::Validate() const {
  auto bad = [](const std::string& what) { throw ConfigError("mapper options: " + what); };
  if (!(tau_e >= 1.0)) bad("tau_e must be >= 1");
  if (!(tau_n > 0)) bad("tau_n must be positive");
  if (!(outlier_px > 0)) bad("outlier_px must be positive");
  if (max_iterations < 1) bad("max_iterations must be at least 1");
  if (sync_tolerance_us < 0) bad("sync tolerance must be >= 0");
  if (!(continuity_gap_s >= 0)) bad("continuity_gap_s must be >= 0");
  if (!(sizes.default_size > 0)) {
    bool all_overridden = !marker_ids.empty();
    for (int id : marker_ids)
      if (!(sizes.Get(id) > 0)) all_overridden = false;
    if (!all_overridden) bad("markers.size must be positive");
  }
}

// ---------------------------------------------------------------------------------------------
// Internals

namespace {

using Clock = std::chrono::steady_clock;
double Seconds(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

template <typename Fn>
void ParallelFor(int n, int threads, const Fn& fn) {
  threads = std::max(1, std::min(threads, n / 64 + 1));
  if (threads == 1) {
    for (int i = 0; i < n; ++i) fn(i);
    return;
  }
  std::atomic<int> next{0};
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t)
    pool.emplace_back([&] {
      for (;;) {
        const int begin = next.fetch_add(64);
        if (begin >= n) return;
        for (int i = begin; i < std::min(n, begin + 64); ++i) fn(i);
      }
    });
  for (auto& th : pool) th.join();
}

struct StoredMarker {
  int id;
  MarkerCorners2d corners;
};

struct StoredMessage {
  int64_t utime = 0;
  int64_t seq = 0;
  int camera = 0;
  std::vector<StoredMarker> markers;
};

struct Frame {
  int64_t utime = 0;
  int64_t seq = 0;
  std::vector<int> messages;  // indices into messages_
};

struct Observation {
  int frame = 0;
  int camera = 0;
  int marker = 0;  // index into marker ids
  int view = 0;    // (frame, camera) group
  MarkerCorners2d corners;
  double side = 0.0;
  SquarePose pose;
  int kept = 0;
};

std::string JoinNames(const std::vector<std::string>& names, size_t max = 12) {
  std::string out;
  for (size_t i = 0; i < names.size() && i < max; ++i) out += (i ? ", " : "") + names[i];
  if (names.size() > max) out += ", ...";
  return out;
}

std::string JoinIds(const std::vector<int>& ids, size_t max = 12) {
  std::vector<std::string> s;
  for (int id : ids) s.push_back(std::to_string(id));
  return JoinNames(s, max);
}

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + mid, v.end());
  return v[mid];
}

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
  void Store(int a, int b, const std::vector<Rigid3>& candidates) {
    slots_[Key(a, b)].pair.AddEvent(candidates);
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

}  // namespace

struct Mapper::Impl {
  std::vector<std::string> camera_names;
  std::map<std::string, int> camera_index;
  std::vector<CameraModel> models;
  std::vector<StoredMessage> messages;
  std::set<std::string> ignored_cameras;
  std::vector<std::string> warnings;
  std::function<void(const MapperProgress&)> progress;
  std::vector<int> messages_per_camera;
  int max_messages_per_camera = 0;
  std::vector<detections_t> inputs;  // as given to Add(), for MapResult::detections (diagnostics)

  std::vector<Frame> AssembleFrames(int64_t tolerance_us) const;
};

std::vector<Frame> Mapper::Impl::AssembleFrames(int64_t tolerance_us) const {
  std::vector<int> order(messages.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int x, int y) {
    return std::make_pair(messages[x].utime, messages[x].camera) <
           std::make_pair(messages[y].utime, messages[y].camera);
  });
  std::vector<Frame> frames;
  std::vector<int64_t> camera_in_frame(camera_names.size(), -1);
  for (int i : order) {
    const StoredMessage& m = messages[i];
    bool join = !frames.empty() && m.utime - frames.back().utime <= tolerance_us &&
                camera_in_frame[m.camera] != static_cast<int64_t>(frames.size()) - 1;
    if (!join) {
      frames.emplace_back();
      frames.back().utime = m.utime;
      frames.back().seq = m.seq;
    }
    frames.back().messages.push_back(i);
    camera_in_frame[m.camera] = static_cast<int64_t>(frames.size()) - 1;
  }
  return frames;
}

Mapper::Mapper(MapperOptions options) : options_(std::move(options)), impl_(new Impl) {
  options_.Validate();
  for (const std::string& name : options_.cameras) {
    if (impl_->camera_index.count(name)) continue;
    impl_->camera_index[name] = static_cast<int>(impl_->camera_names.size());
    impl_->camera_names.push_back(name);
    impl_->models.emplace_back();
  }
}

Mapper::~Mapper() = default;

void Mapper::SetProgressCallback(std::function<void(const MapperProgress&)> callback) {
  impl_->progress = std::move(callback);
}

void Mapper::Reset() {
  impl_->messages.clear();
  impl_->inputs.clear();
  impl_->messages_per_camera.clear();
  impl_->max_messages_per_camera = 0;
  impl_->warnings.clear();
  impl_->ignored_cameras.clear();
}

int Mapper::NumMessages() const { return static_cast<int>(impl_->messages.size()); }

int Mapper::NumFramesApprox() const { return impl_->max_messages_per_camera; }

void Mapper::Add(const detections_t& d) {
  Impl& s = *impl_;
  auto it = s.camera_index.find(d.camera);
  if (it == s.camera_index.end()) {
    if (!options_.cameras.empty()) {
      if (s.ignored_cameras.insert(d.camera).second)
        s.warnings.push_back("ignored detections of camera '" + d.camera + "': not in the rig (" +
                             JoinNames(options_.cameras) + ")");
      return;
    }
    it = s.camera_index.emplace(d.camera, static_cast<int>(s.camera_names.size())).first;
    s.camera_names.push_back(d.camera);
    s.models.emplace_back();
  }
  const int camera = it->second;
  if (s.models[camera].width == 0) {
    CameraModel model;
    try {
      model = FromCameraModelMsg(d.camera_model);
      model.Validate();
    } catch (const std::exception& e) {
      if (s.ignored_cameras.insert(d.camera).second)
        s.warnings.push_back("ignored detections of camera '" + d.camera +
                             "': bad camera model: " + e.what());
      return;
    }
    s.models[camera] = model;
  }
  StoredMessage m;
  m.utime = d.utime;
  m.seq = d.seq;
  m.camera = camera;
  m.markers.reserve(d.markers.size());
  for (const marker_t& mk : d.markers) m.markers.push_back({mk.id, CornersOf(mk)});
  s.messages.push_back(std::move(m));
  s.inputs.push_back(d);
  if (s.messages_per_camera.size() <= static_cast<size_t>(camera))
    s.messages_per_camera.resize(camera + 1, 0);
  s.max_messages_per_camera = std::max(s.max_messages_per_camera, ++s.messages_per_camera[camera]);
}

std::vector<CameraCollectStats> Mapper::CollectStats() const {
  const Impl& s = *impl_;
  const int n = static_cast<int>(s.camera_names.size());
  std::vector<CameraCollectStats> out(n);
  for (int c = 0; c < n; ++c) out[c].name = s.camera_names[c];
  MarkerConfig whitelist;
  whitelist.ids = options_.marker_ids;
  for (const StoredMessage& m : s.messages) {
    ++out[m.camera].frames;
    for (const StoredMarker& mk : m.markers) {
      if (!whitelist.Accepts(mk.id)) continue;
      ++out[m.camera].observations;
      out[m.camera].ids.insert(mk.id);
    }
  }
  // Cameras joined by frames in which both see a marker of the object.
  std::vector<GraphEdge> edges;
  std::set<std::pair<int, int>> joined;
  for (const Frame& f : s.AssembleFrames(options_.sync_tolerance_us)) {
    std::vector<int> seeing;
    for (int i : f.messages) {
      bool any = false;
      for (const StoredMarker& mk : s.messages[i].markers) any = any || whitelist.Accepts(mk.id);
      if (any) seeing.push_back(s.messages[i].camera);
    }
    for (size_t a = 0; a < seeing.size(); ++a)
      for (size_t b = a + 1; b < seeing.size(); ++b) {
        const auto key = std::minmax(seeing[a], seeing[b]);
        if (joined.insert(key).second) {
          GraphEdge e;
          e.a = key.first;
          e.b = key.second;
          e.candidates = 1;
          edges.push_back(e);
        }
      }
  }
  int root = -1;
  for (int c = 0; c < n; ++c)
    if (out[c].observations > 0 && (root < 0 || out[c].observations > out[root].observations)) root = c;
  const std::vector<bool> component = ComponentOf(n, root, edges);
  for (int c = 0; c < n; ++c) out[c].connected = component[c] && out[c].observations > 0;
  return out;
}

// ---------------------------------------------------------------------------------------------
// Solve

MapResult Mapper::Solve() {
  const auto t_total = Clock::now();
  Impl& s = *impl_;
  const MapperOptions& o = options_;
  MapResult result;
  MapReport& report = result.report;
  report.warnings = s.warnings;
  report.detections_messages = static_cast<int>(s.messages.size());
  const int threads = o.threads > 0 ? o.threads : std::max(1u, std::thread::hardware_concurrency());
  report.threads = threads;
  auto stage_start = Clock::now();
  auto end_stage = [&](const std::string& name) {
    report.stage_seconds.emplace_back(name, Seconds(stage_start));
    stage_start = Clock::now();
  };
  auto notify = [&](MapperProgress::Stage stage, const std::string& step, const std::string& message) {
    if (!s.progress) return;
    MapperProgress p;
    p.stage = stage;
    p.step = step;
    p.message = message;
    s.progress(p);
  };

  if (s.messages.empty()) throw MapperError("no detections received (channels MCMT_DETECTIONS_*)");
  const int num_cameras = static_cast<int>(s.camera_names.size());

  // Frames ---------------------------------------------------------------------------------------
  notify(MapperProgress::kInitialising, "frames", "assembling frames");
  const std::vector<Frame> frames = s.AssembleFrames(o.sync_tolerance_us);
  report.frames_assembled = static_cast<int>(frames.size());

  // Observations (whitelist, duplicates) -----------------------------------------------------------
  MarkerConfig whitelist;
  whitelist.ids = o.marker_ids;
  std::vector<Observation> obs;
  std::map<int, int> marker_index;
  std::vector<int> marker_ids;
  std::vector<int> camera_messages(num_cameras, 0);
  int view_count = 0;
  for (size_t f = 0; f < frames.size(); ++f) {
    for (int mi : frames[f].messages) {
      const StoredMessage& m = s.messages[mi];
      ++camera_messages[m.camera];
      std::map<int, int> count;
      for (const StoredMarker& mk : m.markers) ++count[mk.id];
      bool any = false;
      for (const StoredMarker& mk : m.markers) {
        if (!whitelist.Accepts(mk.id)) {
          ++report.ignored_ids;
          continue;
        }
        const int c = count[mk.id];
        if (c != 1) {  // the same id twice in one camera frame: which one is the marker is unknown
          ++report.duplicates;
          if (c > 1) {
            if (report.duplicate_examples.size() < 20)
              report.duplicate_examples.push_back("camera " + s.camera_names[m.camera] + " seq " +
                                                  std::to_string(m.seq) + " id " + std::to_string(mk.id) +
                                                  " x" + std::to_string(c));
            count[mk.id] = -c;
          }
          continue;
        }
        auto it = marker_index.find(mk.id);
        if (it == marker_index.end()) {
          it = marker_index.emplace(mk.id, static_cast<int>(marker_ids.size())).first;
          marker_ids.push_back(mk.id);
        }
        Observation ob;
        ob.frame = static_cast<int>(f);
        ob.camera = m.camera;
        ob.marker = it->second;
        ob.view = view_count;
        ob.corners = mk.corners;
        ob.side = o.sizes.Get(mk.id);
        obs.push_back(ob);
        any = true;
      }
      if (any) ++view_count;
    }
  }
  report.observations_total = static_cast<int>(obs.size());
  if (obs.empty())
    throw MapperError("no marker observations" + std::string(o.marker_ids.empty() ? "" : " of markers.ids") +
                      " in " + std::to_string(s.messages.size()) + " detections messages");
  end_stage("frames");

  // Step 1: IPPE hypotheses -------------------------------------------------------------------------
  notify(MapperProgress::kInitialising, "hypotheses",
         "square poses of " + std::to_string(obs.size()) + " observations");
  ParallelFor(static_cast<int>(obs.size()), threads, [&](int i) {
    Observation& ob = obs[i];
    if (!(ob.side > 0)) return;
    ob.pose = EstimateSquarePose(s.models[ob.camera], ob.corners, ob.side);
    ob.kept = NumKeptHypotheses(ob.pose, o.tau_e);
  });
  for (const Observation& ob : obs) report.ambiguous_observations += ob.kept == 2;
  end_stage("hypotheses");

  // Step 3 (first: it also finds the ids that are not on the object): marker graph ------------------
  notify(MapperProgress::kInitialising, "markers", "marker graph");
  const int num_markers = static_cast<int>(marker_ids.size());
  std::vector<int> marker_obs_count(num_markers, 0);
  for (const Observation& ob : obs)
    if (ob.kept > 0) ++marker_obs_count[ob.marker];
  // marker_from_cam per observation and hypothesis
  std::vector<std::array<Rigid3, 2>> marker_from_cam(obs.size());
  for (size_t i = 0; i < obs.size(); ++i)
    for (int h = 0; h < obs[i].kept; ++h)
      marker_from_cam[i][h] = Inverse(obs[i].pose.hypotheses[h].cam_from_marker);
  // views: contiguous ranges of obs with the same view
  std::vector<std::pair<int, int>> views;  // [begin, end)
  for (size_t i = 0; i < obs.size();) {
    size_t j = i;
    while (j < obs.size() && obs[j].view == obs[i].view) ++j;
    views.emplace_back(static_cast<int>(i), static_cast<int>(j));
    i = j;
  }
  std::vector<GraphEdge> marker_edges;
  {
    PairCollector collector(std::max(1, num_markers), o.max_pair_events);
    auto for_each_pair = [&](const std::function<void(int, int)>& fn) {
      for (const auto& v : views)
        for (int i = v.first; i < v.second; ++i)
          for (int j = i + 1; j < v.second; ++j) {
            if (obs[i].kept == 0 || obs[j].kept == 0) continue;
            if (obs[i].marker < obs[j].marker)
              fn(i, j);
            else
              fn(j, i);
          }
    };
    for_each_pair(
        [&](int i, int j) { collector.Count(obs[i].marker, obs[j].marker, obs[i].kept * obs[j].kept); });
    collector.FinishCounting();
    std::vector<Rigid3> cands;
    for_each_pair([&](int i, int j) {
      if (!collector.Wanted(obs[i].marker, obs[j].marker)) return;
      cands.clear();
      for (int hi = 0; hi < obs[i].kept; ++hi)
        for (int hj = 0; hj < obs[j].kept; ++hj)
          cands.push_back(marker_from_cam[i][hi] * obs[j].pose.hypotheses[hj].cam_from_marker);
      collector.Store(obs[i].marker, obs[j].marker, cands);
    });
    std::vector<PairCandidates*> pairs = collector.Pairs();
    marker_edges.resize(pairs.size());
    double max_side = 0.0;
    for (const Observation& ob : obs) max_side = std::max(max_side, ob.side);
    MedoidOptions medoid_options;
    medoid_options.point_scale = std::max(0.05, 2.0 * max_side);
    ConsistencyOptions consistency;
    consistency.max_angle_rad = o.consistency_deg * M_PI / 180.0;
    consistency.max_distance_m = o.consistency_m;
    consistency.max_distance_rel = o.consistency_rel;
    ParallelFor(static_cast<int>(pairs.size()), threads, [&](int k) {
      marker_edges[k] = EvaluateEdge(*pairs[k], medoid_options, o.tau_n, consistency);
    });
  }
  std::vector<GraphEdge> verified_marker_edges;
  for (const GraphEdge& e : marker_edges)
    if (e.support >= o.min_marker_support && e.SupportFraction() >= o.marker_inlier_fraction)
      verified_marker_edges.push_back(e);
  int ref_marker = -1;
  if (o.reference_marker >= 0) {
    auto it = marker_index.find(o.reference_marker);
    if (it == marker_index.end())
      throw MapperError("reference marker " + std::to_string(o.reference_marker) +
                        " (mapper.reference_marker) was never detected");
    ref_marker = it->second;
  } else {
    ref_marker = BestConnectedNode(num_markers, verified_marker_edges);
    if (ref_marker < 0) {  // no verified pair at all: a single-marker object
      for (int m = 0; m < num_markers; ++m)
        if (ref_marker < 0 || marker_obs_count[m] > marker_obs_count[ref_marker]) ref_marker = m;
    }
  }
  std::vector<bool> marker_placed = ComponentOf(num_markers, ref_marker, verified_marker_edges);
  {
    // Classify the others: false ids (co-observed with placed markers, but inconsistently), too rarely
    // co-observed to verify, or disconnected (never seen with a placed marker).
    std::vector<int> disconnected;
    for (int m = 0; m < num_markers; ++m) {
      if (marker_placed[m]) continue;
      int64_t with_placed = 0;
      int best_support = 0;
      int64_t best_events = 0;
      int best_other = -1;
      for (const GraphEdge& e : marker_edges) {
        if (e.a != m && e.b != m) continue;
        const int other = e.a == m ? e.b : e.a;
        if (!marker_placed[other]) continue;
        with_placed += e.events;
        if (best_other < 0 || e.support > best_support) {
          best_support = e.support;
          best_events = e.stored_events;
          best_other = other;
        }
      }
      RejectedMarker r;
      r.id = marker_ids[m];
      r.observations = marker_obs_count[m];
      if (with_placed >= o.min_marker_support) {
        std::ostringstream why;
        why << "not rigidly attached: its pose relative to marker " << marker_ids[best_other]
            << " agrees in only " << best_support << " of " << best_events << " frames seen together";
        r.reason = why.str();
        report.rejected_markers.push_back(r);
      } else if (with_placed > 0) {
        r.reason = "seen together with the object's markers in only " + std::to_string(with_placed) +
                   " frames (< min_marker_support " + std::to_string(o.min_marker_support) +
                   "): cannot verify it is on the object";
        report.rejected_markers.push_back(r);
      } else if (marker_obs_count[m] < std::max(10, o.min_marker_support)) {
        r.reason =
            "seen in only " + std::to_string(marker_obs_count[m]) +
            " camera frames, never together with the object's markers: cannot verify it is on the object";
        report.rejected_markers.push_back(r);
      } else {
        disconnected.push_back(m);
      }
    }
    if (!disconnected.empty()) {
      std::vector<int> ids, placed_ids;
      for (int m : disconnected) ids.push_back(marker_ids[m]);
      for (int m = 0; m < num_markers; ++m)
        if (marker_placed[m]) placed_ids.push_back(marker_ids[m]);
      std::ostringstream msg;
      msg << "marker" << (ids.size() > 1 ? "s " : " ") << JoinIds(ids)
          << " cannot be placed on the object: never seen "
          << "by one camera in one frame together with a marker connected to the reference marker "
          << marker_ids[ref_marker] << " (" << JoinIds(placed_ids)
          << "); record frames where a camera sees marker " << ids[0] << " together with one of those";
      if (!o.allow_partial) throw MapperError(msg.str() + " (or use --allow-partial to map without it)");
      report.warnings.push_back(msg.str() + ": left out (--allow-partial)");
      for (int m : disconnected) {
        RejectedMarker r;
        r.id = marker_ids[m];
        r.observations = marker_obs_count[m];
        r.reason = "disconnected (left out by --allow-partial)";
        report.rejected_markers.push_back(r);
      }
    }
  }
  std::vector<GraphEdge> marker_tree;
  {
    std::vector<GraphEdge> inside;
    for (const GraphEdge& e : verified_marker_edges)
      if (marker_placed[e.a] && marker_placed[e.b]) inside.push_back(e);
    marker_tree = MinimumSpanningTree(num_markers, inside);
  }
  const TreePoses marker_poses = PosesFromTree(num_markers, ref_marker, marker_tree);
  std::vector<Rigid3> object_from_marker = marker_poses.root_from_node;
  std::vector<Rigid3> marker_from_object(num_markers);
  for (int m = 0; m < num_markers; ++m) marker_from_object[m] = Inverse(object_from_marker[m]);
  end_stage("markers");

  // Step 2: camera graph through the object (same-marker candidates are the paper's; other placed
  // markers of the frame add candidates through object_from_marker) -----------------------------------
  notify(MapperProgress::kInitialising, "cameras", "camera graph");
  double object_scale = 0.0;
  for (int m = 0; m < num_markers; ++m)
    if (marker_placed[m]) object_scale = std::max(object_scale, object_from_marker[m].translation().norm());
  object_scale = std::max(object_scale, 0.05);
  // Per view: cam_from_object candidates. A lone marker gives its kept hypotheses; several markers give
  // one pose fitted to all their corners at once (Levenberg-Marquardt from each hypothesis-derived
  // start, the best kept): far more precise than one square at grazing angles.
  struct View {
    int frame, camera;
    std::vector<Rigid3> cam_from_object;
    double fit_rms = -1.0;  // multi-marker views: RMS pixel error of the fitted pose
  };
  std::vector<View> view_poses(views.size());
  std::vector<char> view_ok(views.size(), 0);
  ParallelFor(static_cast<int>(views.size()), threads, [&](int k) {
    const auto& v = views[k];
    View& vp = view_poses[k];
    vp.frame = obs[v.first].frame;
    vp.camera = obs[v.first].camera;
    std::vector<Rigid3> cands;
    std::vector<Eigen::Vector3d> points;
    std::vector<Eigen::Vector2d> pixels;
    int used_markers = 0;
    for (int i = v.first; i < v.second; ++i) {
      if (!marker_placed[obs[i].marker] || obs[i].kept == 0) continue;
      ++used_markers;
      for (int h = 0; h < obs[i].kept; ++h)
        cands.push_back(obs[i].pose.hypotheses[h].cam_from_marker * marker_from_object[obs[i].marker]);
      const MarkerCorners3d corners = MarkerCornersInMarker(obs[i].side);
      for (int c = 0; c < 4; ++c) {
        points.push_back(object_from_marker[obs[i].marker] * corners[c]);
        pixels.push_back(obs[i].corners[c]);
      }
    }
    if (cands.empty()) return;
    view_ok[k] = 1;
    if (used_markers == 1) {
      vp.cam_from_object = cands;
      return;
    }
    std::vector<Rigid3> starts = {cands[MedoidIndex(cands, object_scale)]};
    for (size_t c = 0; c < cands.size() && starts.size() < 4; c += 2) starts.push_back(cands[c]);
    double best = std::numeric_limits<double>::infinity();
    Rigid3 best_pose = starts[0];
    for (Rigid3 start : starts) {
      const double e = RefinePose(s.models[vp.camera], points, pixels, &start);
      if (e < best) {
        best = e;
        best_pose = start;
      }
    }
    vp.cam_from_object.push_back(best_pose);
    vp.fit_rms = best;
  });
  {
    std::vector<View> kept;
    kept.reserve(view_poses.size());
    for (size_t k = 0; k < view_poses.size(); ++k)
      if (view_ok[k]) kept.push_back(std::move(view_poses[k]));
    view_poses.swap(kept);
  }
  // Median fit of each camera's multi-marker views: a camera whose views do not fit the marker layout has
  // wrong intrinsics or images (e.g. rotated frames), which no initialisation can fix.
  std::vector<double> camera_fit_rms(num_cameras, -1.0);
  {
    std::vector<std::vector<double>> fits(num_cameras);
    for (const View& v : view_poses)
      if (v.fit_rms >= 0) fits[v.camera].push_back(v.fit_rms);
    for (int c = 0; c < num_cameras; ++c)
      if (!fits[c].empty()) camera_fit_rms[c] = Median(fits[c]);
  }
  std::vector<double> depths;
  for (const View& v : view_poses) depths.push_back(v.cam_from_object[0].translation().norm());
  const double camera_scale = std::max(0.1, Median(depths));
  std::vector<int> camera_views(num_cameras, 0);
  for (const View& v : view_poses) ++camera_views[v.camera];
  std::vector<GraphEdge> camera_edges;
  {
    PairCollector collector(std::max(1, num_cameras), o.max_pair_events);
    auto for_each_pair = [&](const std::function<void(int, int)>& fn) {
      for (size_t i = 0; i < view_poses.size();) {
        size_t j = i;
        while (j < view_poses.size() && view_poses[j].frame == view_poses[i].frame) ++j;
        for (size_t x = i; x < j; ++x)
          for (size_t y = x + 1; y < j; ++y) {
            if (view_poses[x].camera < view_poses[y].camera)
              fn(static_cast<int>(x), static_cast<int>(y));
            else
              fn(static_cast<int>(y), static_cast<int>(x));
          }
        i = j;
      }
    };
    for_each_pair([&](int x, int y) {
      collector.Count(
          view_poses[x].camera, view_poses[y].camera,
          static_cast<int64_t>(view_poses[x].cam_from_object.size() * view_poses[y].cam_from_object.size()));
    });
    collector.FinishCounting();
    std::vector<Rigid3> cands;
    for_each_pair([&](int x, int y) {
      if (!collector.Wanted(view_poses[x].camera, view_poses[y].camera)) return;
      cands.clear();
      for (const Rigid3& a : view_poses[x].cam_from_object)
        for (const Rigid3& b : view_poses[y].cam_from_object) cands.push_back(a * Inverse(b));
      collector.Store(view_poses[x].camera, view_poses[y].camera, cands);
    });
    std::vector<PairCandidates*> pairs = collector.Pairs();
    camera_edges.resize(pairs.size());
    MedoidOptions medoid_options;
    medoid_options.point_scale = camera_scale;
    ConsistencyOptions consistency;
    consistency.max_angle_rad = o.consistency_deg * M_PI / 180.0;
    consistency.max_distance_m = o.consistency_m;
    consistency.max_distance_rel = o.consistency_rel;
    ParallelFor(static_cast<int>(pairs.size()), threads, [&](int k) {
      camera_edges[k] = EvaluateEdge(*pairs[k], medoid_options, o.tau_n, consistency);
    });
  }
  int ref_camera = -1;
  if (!o.reference_camera.empty()) {
    auto it = s.camera_index.find(o.reference_camera);
    if (it == s.camera_index.end() || camera_views[it->second] == 0)
      throw MapperError("reference camera '" + o.reference_camera +
                        "' (mapper.reference_camera) never saw the object");
    ref_camera = it->second;
  } else {
    ref_camera = BestConnectedNode(num_cameras, camera_edges);
    if (ref_camera < 0)
      for (int c = 0; c < num_cameras; ++c)
        if (camera_views[c] > 0 && (ref_camera < 0 || camera_views[c] > camera_views[ref_camera]))
          ref_camera = c;
  }
  if (ref_camera < 0) throw MapperError("no camera saw a marker of the object");
  std::vector<bool> camera_placed = ComponentOf(num_cameras, ref_camera, camera_edges);
  {
    std::vector<std::string> placed_names, problems;
    for (int c = 0; c < num_cameras; ++c)
      if (camera_placed[c]) placed_names.push_back(s.camera_names[c]);
    for (int c = 0; c < num_cameras; ++c) {
      if (camera_placed[c]) continue;
      const std::string& name = s.camera_names[c];
      std::ostringstream msg;
      if (camera_messages[c] == 0) {
        msg << "camera '" << name << "' sent no detections";
      } else if (camera_views[c] == 0) {
        msg << "camera '" << name << "' never saw a marker of the object (" << camera_messages[c]
            << " frames)";
      } else {
        msg << "camera '" << name << "' cannot be placed: in none of the " << camera_views[c]
            << " frames where it sees the object does a camera connected to the reference '"
            << s.camera_names[ref_camera] << "' (" << JoinNames(placed_names)
            << ") see it too (sync tolerance " << o.sync_tolerance_us / 1000.0
            << " ms); record frames where '" << name
            << "' and one of those cameras see the object at the same time";
      }
      problems.push_back(msg.str());
      report.dropped_cameras.push_back(name);
    }
    if (!problems.empty()) {
      if (!o.allow_partial) {
        std::string all = problems[0];
        if (problems.size() > 1)
          all += " (and " + std::to_string(problems.size() - 1) + " more cameras: " +
                 JoinNames(std::vector<std::string>(report.dropped_cameras.begin() + 1,
                                                    report.dropped_cameras.end())) +
                 ")";
        throw MapperError(all + "; use --allow-partial to map the connected cameras only");
      }
      for (const std::string& p : problems) report.warnings.push_back(p + ": left out (--allow-partial)");
    }
  }
  std::vector<GraphEdge> camera_tree = MinimumSpanningTree(num_cameras, camera_edges);
  const TreePoses camera_poses = PosesFromTree(num_cameras, ref_camera, camera_tree);
  const std::vector<Rigid3>& rig_from_cam = camera_poses.root_from_node;
  end_stage("cameras");

  // Step 4: object pose per frame -------------------------------------------------------------------
  notify(MapperProgress::kInitialising, "object poses", "object pose per frame");
  const int num_frames = static_cast<int>(frames.size());
  std::vector<Rigid3> rig_from_object(num_frames, Rigid3::Identity());
  std::vector<char> frame_has_pose(num_frames, 0);
  std::vector<char> obs_usable(obs.size(), 0);
  for (size_t i = 0; i < obs.size(); ++i)
    obs_usable[i] = obs[i].kept > 0 && marker_placed[obs[i].marker] && camera_placed[obs[i].camera];
  {
    std::vector<int> frame_first(num_frames + 1, static_cast<int>(obs.size()));
    for (int i = static_cast<int>(obs.size()) - 1; i >= 0; --i) frame_first[obs[i].frame] = i;
    for (int f = num_frames - 1; f >= 0; --f) frame_first[f] = std::min(frame_first[f], frame_first[f + 1]);
    // A frame is weak when its markers are all seen by one camera, or when no two of its observations
    // agree on its pose: a small or distant marker's two planar hypotheses fit its corners about equally,
    // the ratio test may keep the wrong one, and the bundle adjustment cannot leave that minimum. Its
    // candidates (both hypotheses of every marker) are kept and it is decided below by continuity with
    // the nearest frame whose observations agree.
    std::vector<std::vector<Rigid3>> weak_candidates(num_frames);
    const double support_angle = o.consistency_deg * M_PI / 180.0;
    ParallelFor(num_frames, threads, [&](int f) {
      std::vector<Rigid3> cands, all;
      std::vector<int> source;  // observation of each kept candidate
      int first_camera = -1;
      bool one_camera = true;
      for (int i = frame_first[f]; i < frame_first[f + 1]; ++i) {
        if (!obs_usable[i]) continue;
        const Observation& ob = obs[i];
        if (first_camera < 0) first_camera = ob.camera;
        one_camera = one_camera && ob.camera == first_camera;
        for (int h = 0; h < ob.pose.num_hypotheses; ++h) {
          const Rigid3 pose =
              rig_from_cam[ob.camera] * ob.pose.hypotheses[h].cam_from_marker * marker_from_object[ob.marker];
          if (h < ob.kept) {
            cands.push_back(pose);
            source.push_back(i);
          }
          all.push_back(pose);
        }
      }
      if (cands.empty()) return;
      const size_t medoid = MedoidIndex(cands, object_scale);
      rig_from_object[f] = Normalized(cands[medoid]);
      frame_has_pose[f] = 1;
      // Supported: another observation's candidate agrees with the medoid.
      bool supported = false;
      for (size_t k = 0; k < cands.size() && !supported; ++k)
        supported = source[k] != source[medoid] && RotationAngle(cands[k], cands[medoid]) < support_angle &&
                    (cands[k].translation() - cands[medoid].translation()).norm() <
                        o.consistency_m + o.consistency_rel * object_scale;
      if (one_camera || !supported) weak_candidates[f] = std::move(all);
    });
    // Forward, then backward: a weak frame within continuity_gap_s of the last decided frame takes its
    // candidate nearest to that frame's pose in rotation, and is decided in turn.
    std::vector<char> decided(num_frames, 0);
    for (int f = 0; f < num_frames; ++f) decided[f] = frame_has_pose[f] && weak_candidates[f].empty();
    const int64_t max_gap_us = static_cast<int64_t>(1e6 * o.continuity_gap_s);
    auto sweep = [&](int begin, int end, int step) {
      int last = -1;
      for (int f = begin; f != end; f += step) {
        if (!frame_has_pose[f]) continue;
        if (!decided[f] && last >= 0 && std::llabs(frames[f].utime - frames[last].utime) <= max_gap_us) {
          const std::vector<Rigid3>& cands = weak_candidates[f];
          size_t best = 0;
          double best_angle = RotationAngle(cands[0], rig_from_object[last]);
          for (size_t k = 1; k < cands.size(); ++k) {
            const double angle = RotationAngle(cands[k], rig_from_object[last]);
            if (angle < best_angle) best = k, best_angle = angle;
          }
          rig_from_object[f] = Normalized(cands[best]);
          decided[f] = 1;
        }
        if (decided[f]) last = f;
      }
    };
    sweep(0, num_frames, 1);
    sweep(num_frames - 1, -1, -1);
    for (int f = 0; f < num_frames; ++f)
      if (!weak_candidates[f].empty()) {
        ++report.weak_frames;
        report.undecided_frames += !decided[f];
      }
  }
  end_stage("object poses");

  // Bundle problem --------------------------------------------------------------------------------
  BundleProblem bp;
  bp.cam_from_rig.resize(num_cameras);
  bp.models.resize(num_cameras);
  bp.camera_fixed.assign(num_cameras, 0);
  for (int c = 0; c < num_cameras; ++c) {
    bp.cam_from_rig[c] = BlockFromRigid(Inverse(rig_from_cam[c]));
    bp.models[c] = &s.models[c];
  }
  bp.camera_fixed[ref_camera] = 1;
  bp.object_from_marker.resize(num_markers);
  bp.marker_fixed.assign(num_markers, 0);
  for (int m = 0; m < num_markers; ++m) bp.object_from_marker[m] = BlockFromRigid(object_from_marker[m]);
  bp.marker_fixed[ref_marker] = 1;
  bp.rig_from_object.resize(num_frames);
  for (int f = 0; f < num_frames; ++f) bp.rig_from_object[f] = BlockFromRigid(rig_from_object[f]);
  std::vector<int> obs_of_bundle;  // bundle observation -> obs index
  for (size_t i = 0; i < obs.size(); ++i) {
    if (!obs_usable[i] || !frame_has_pose[obs[i].frame]) continue;
    BundleObservation b;
    b.camera = obs[i].camera;
    b.marker = obs[i].marker;
    b.frame = obs[i].frame;
    b.corners = obs[i].corners;
    b.side = obs[i].side;
    bp.observations.push_back(b);
    obs_of_bundle.push_back(static_cast<int>(i));
  }
  bp.active.assign(bp.observations.size(), 1);
  auto reject = [&](size_t k, double rms, const std::string& reason) {
    bp.active[k] = 0;
    const Observation& ob = obs[obs_of_bundle[k]];
    RejectedObservation r;
    r.utime = frames[ob.frame].utime;
    r.seq = frames[ob.frame].seq;
    r.camera = s.camera_names[ob.camera];
    r.id = marker_ids[ob.marker];
    r.rms_px = rms;
    r.reason = reason;
    report.rejected_observations.push_back(r);
  };
  {
    const std::vector<double> rms = ObservationRms(bp);
    for (size_t k = 0; k < rms.size(); ++k)
      if (!std::isfinite(rms[k])) reject(k, rms[k], "behind the camera at initialisation");
  }

  // Statistics and outputs of a state -----------------------------------------------------------
  std::vector<char> marker_rejected(num_markers, 0);
  for (const RejectedMarker& r : report.rejected_markers) marker_rejected[marker_index[r.id]] = 1;
  auto fill = [&](RigMap* map, std::vector<TrajectoryRow>* trajectory) {
    std::vector<double> max_corner;
    const std::vector<double> rms = ObservationRms(bp, &max_corner);
    map->dictionary = o.dictionary;
    map->reference_camera = s.camera_names[ref_camera];
    map->reference_marker = marker_ids[ref_marker];
    map->cameras.clear();
    map->markers.clear();
    std::vector<double> cam_sq(num_cameras, 0), cam_max(num_cameras, 0), mk_sq(num_markers, 0),
        mk_max(num_markers, 0), fr_sq(num_frames, 0);
    std::vector<int> cam_n(num_cameras, 0), mk_n(num_markers, 0), fr_n(num_frames, 0);
    std::vector<std::set<int>> fr_cams(num_frames), fr_markers(num_frames);
    double total_sq = 0;
    int total_n = 0;
    for (size_t k = 0; k < bp.observations.size(); ++k) {
      if (!bp.active[k] || !std::isfinite(rms[k])) continue;
      const BundleObservation& b = bp.observations[k];
      const double sq = rms[k] * rms[k];
      cam_sq[b.camera] += sq;
      cam_max[b.camera] = std::max(cam_max[b.camera], max_corner[k]);
      ++cam_n[b.camera];
      mk_sq[b.marker] += sq;
      mk_max[b.marker] = std::max(mk_max[b.marker], max_corner[k]);
      ++mk_n[b.marker];
      fr_sq[b.frame] += sq;
      ++fr_n[b.frame];
      fr_cams[b.frame].insert(b.camera);
      fr_markers[b.frame].insert(b.marker);
      total_sq += sq;
      ++total_n;
    }
    for (int c = 0; c < num_cameras; ++c) {
      if (!camera_placed[c]) continue;
      MapCamera mc;
      mc.name = s.camera_names[c];
      mc.model = s.models[c];
      mc.rig_from_cam = Normalized(Inverse(RigidFromBlock(bp.cam_from_rig[c].data())));
      mc.observations = cam_n[c];
      mc.rms_px = cam_n[c] ? std::sqrt(cam_sq[c] / cam_n[c]) : 0.0;
      mc.max_px = cam_max[c];
      map->cameras.push_back(mc);
    }
    std::vector<int> order(num_markers);
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int x, int y) { return marker_ids[x] < marker_ids[y]; });
    for (int m : order) {
      if (!marker_placed[m] || marker_rejected[m]) continue;
      MapMarker mm;
      mm.id = marker_ids[m];
      mm.size = o.sizes.Get(mm.id);
      mm.object_from_marker = Normalized(RigidFromBlock(bp.object_from_marker[m].data()));
      mm.observations = mk_n[m];
      mm.rms_px = mk_n[m] ? std::sqrt(mk_sq[m] / mk_n[m]) : 0.0;
      mm.max_px = mk_max[m];
      map->markers.push_back(mm);
    }
    map->rms_px = total_n ? std::sqrt(total_sq / total_n) : 0.0;
    map->num_observations = total_n;
    trajectory->clear();
    for (int f = 0; f < num_frames; ++f) {
      if (fr_n[f] == 0) continue;
      TrajectoryRow row;
      row.utime = frames[f].utime;
      row.seq = frames[f].seq;
      row.rig_from_object = Normalized(RigidFromBlock(bp.rig_from_object[f].data()));
      row.rms_px = std::sqrt(fr_sq[f] / fr_n[f]);
      row.cameras = static_cast<int>(fr_cams[f].size());
      row.markers = static_cast<int>(fr_markers[f].size());
      trajectory->push_back(row);
    }
    map->num_frames = static_cast<int>(trajectory->size());
  };
  fill(&result.initial_map, &result.initial_trajectory);
  report.initial_rms_px = result.initial_map.rms_px;
  end_stage("initial statistics");

  // Step 5: refinement, gross-residual rejection, re-solve --------------------------------------------
  if (o.refine) {
    BundleSettings settings;
    settings.huber_px = o.huber_px;
    settings.max_iterations = o.max_iterations;
    settings.paper_stop = o.paper_stop;
    settings.paper_stop_px = o.paper_stop_px;
    settings.threads = threads;
    settings.linear_solver = o.linear_solver;
    int round = 0;
    settings.on_iteration = [&](int iteration, double cost, double rms) {
      if (!s.progress) return;
      MapperProgress p;
      p.stage = MapperProgress::kRefining;
      p.step = "refine";
      p.iteration = iteration;
      p.max_iterations = o.max_iterations;
      p.cost = cost;
      p.rms_px = rms;
      std::ostringstream msg;
      msg << "refining (solve " << round + 1 << "): iteration " << iteration << ", cost " << cost << ", rms "
          << rms << " px";
      p.message = msg.str();
      s.progress(p);
    };
    for (round = 0;; ++round) {
      const BundleSummary summary = SolveBundle(&bp, settings);
      ++report.solves;
      report.iterations += summary.iterations;
      report.termination = summary.termination;
      report.linear_solver = summary.linear_solver;
      if (!summary.usable) throw MapperError("refinement failed: " + summary.termination);
      if (round >= o.max_rejection_rounds) break;
      const std::vector<double> rms = ObservationRms(bp);
      bool changed = false;
      std::vector<int> active_n(num_markers, 0), rejected_n(num_markers, 0);
      for (size_t k = 0; k < rms.size(); ++k) {
        if (!bp.active[k]) continue;
        ++active_n[bp.observations[k].marker];
        if (!(rms[k] <= o.outlier_px)) {
          std::ostringstream why;
          why << "gross residual (rms " << rms[k] << " px > outlier_px " << o.outlier_px << ")";
          reject(k, rms[k], why.str());
          ++rejected_n[bp.observations[k].marker];
          changed = true;
        }
      }
      for (int m = 0; m < num_markers; ++m) {
        if (m == ref_marker || active_n[m] == 0) continue;
        if (rejected_n[m] > o.marker_reject_fraction * active_n[m]) {
          marker_rejected[m] = 1;
          RejectedMarker r;
          r.id = marker_ids[m];
          r.observations = marker_obs_count[m];
          std::ostringstream why;
          why << "not rigidly attached: " << rejected_n[m] << " of " << active_n[m]
              << " observations have gross residuals after refinement";
          r.reason = why.str();
          report.rejected_markers.push_back(r);
          for (size_t k = 0; k < bp.observations.size(); ++k)
            if (bp.active[k] && bp.observations[k].marker == m) reject(k, rms[k], "marker dropped");
        }
      }
      if (!changed) break;
    }
    // A camera whose observations mostly do not fit after refinement was placed wrongly (e.g. from a few
    // grazing views): it is not part of a trustworthy map.
    std::vector<int> cam_total(num_cameras, 0), cam_active(num_cameras, 0);
    for (size_t k = 0; k < bp.observations.size(); ++k) {
      ++cam_total[bp.observations[k].camera];
      cam_active[bp.observations[k].camera] += bp.active[k];
    }
    std::vector<std::string> problems;
    std::vector<int> bad_cameras;
    for (int c = 0; c < num_cameras; ++c) {
      // The reference camera too: a badly placed reference makes every other pose meaningless.
      if (!camera_placed[c] || cam_total[c] == 0) continue;
      if (cam_active[c] >= 0.5 * cam_total[c]) continue;
      std::ostringstream msg;
      msg << "camera '" << s.camera_names[c]
          << "' cannot be placed reliably: " << cam_total[c] - cam_active[c] << " of its " << cam_total[c]
          << " marker observations (in " << camera_views[c]
          << " frames) do not fit the map after refinement (rms > outlier_px " << o.outlier_px
          << " px); record more frames where '" << s.camera_names[c]
          << "' sees the object closer to face-on at the same time as another camera";
      std::vector<double> others;
      for (int k = 0; k < num_cameras; ++k)
        if (k != c && camera_fit_rms[k] >= 0) others.push_back(camera_fit_rms[k]);
      if (camera_fit_rms[c] >= 0 && !others.empty() && camera_fit_rms[c] > 3.0 * Median(others) &&
          camera_fit_rms[c] > 2.0) {
        msg << ". Its frames with several markers do not fit the marker layout (median rms "
            << std::setprecision(3) << camera_fit_rms[c] << " px; other cameras " << Median(others)
            << " px): check its intrinsics and the orientation of its images";
      }
      problems.push_back(msg.str());
      bad_cameras.push_back(c);
    }
    if (!problems.empty()) {
      if (!o.allow_partial) {
        std::string all = problems[0];
        if (problems.size() > 1) all += " (and " + std::to_string(problems.size() - 1) + " more cameras)";
        throw MapperError(all + "; use --allow-partial to map without it");
      }
      for (int c : bad_cameras)
        if (c == ref_camera)
          throw MapperError(problems[&c - &bad_cameras[0]] +
                            "; it is the reference camera: name another one " +
                            "(--reference-camera or mapper.reference_camera) to map without it");
      for (int c : bad_cameras) {
        camera_placed[c] = false;
        report.dropped_cameras.push_back(s.camera_names[c]);
        for (size_t k = 0; k < bp.observations.size(); ++k)
          if (bp.active[k] && bp.observations[k].camera == c)
            reject(k, 0.0, "camera left out (--allow-partial)");
      }
      for (const std::string& p : problems) report.warnings.push_back(p + ": left out (--allow-partial)");
      const BundleSummary summary = SolveBundle(&bp, settings);
      ++report.solves;
      report.iterations += summary.iterations;
      report.termination = summary.termination;
    }
    end_stage("refine");
  }
  fill(&result.map, &result.trajectory);
  report.final_rms_px = result.map.rms_px;
  report.frames_used = result.map.num_frames;
  report.observations_used = result.map.num_observations;
  for (const MapCamera& c : result.map.cameras)
    if (c.observations == 0)
      report.warnings.push_back("camera '" + c.name + "' kept no observation after outlier rejection");
  result.detections = s.inputs;
  notify(MapperProgress::kDone, "done", "done");
  report.total_seconds = Seconds(t_total);
  return result;
}

}  // namespace mcmt
