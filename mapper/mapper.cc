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

#include "core/lcm_util.h"
#include "mapper/intrinsics.h"
#include "mapper/stages.h"

namespace mcmt {

// ---------------------------------------------------------------------------------------------
// Options

namespace {

// mapper.refine_intrinsics, refine_intrinsics_cameras, intrinsics_sigma {focal_rel, center_px, radial,
// tangential}, observability_ratio.
void ReadIntrinsicsSettings(const RigConfig& rig, IntrinsicsSettings* out) {
  const YamlSection& s = rig.mapper;
  try {
    out->refine = IntrinsicsRefinementFromName(s.GetString("refine_intrinsics", "none"));
  } catch (const std::invalid_argument& e) {
    s.Fail("refine_intrinsics", e.what());
  }
  if (s.Has("refine_intrinsics_cameras")) {
    const YAML::Node list = s.node()["refine_intrinsics_cameras"];
    if (!list.IsSequence()) s.Fail("refine_intrinsics_cameras", "expected a list of camera names");
    for (const YAML::Node& n : list) {
      const std::string name = n.as<std::string>();
      if (!rig.FindCamera(name)) s.Fail("refine_intrinsics_cameras", "no camera named '" + name + "'");
      out->cameras.push_back(name);
    }
  }
  const YamlSection sigma = s.Child("intrinsics_sigma");
  sigma.CheckKnownKeys({"focal_rel", "center_px", "radial", "tangential"});
  out->sigma.focal_rel = sigma.GetPositiveDouble("focal_rel", out->sigma.focal_rel);
  out->sigma.center_px = sigma.GetPositiveDouble("center_px", out->sigma.center_px);
  out->sigma.radial = sigma.GetPositiveDouble("radial", out->sigma.radial);
  out->sigma.tangential = sigma.GetPositiveDouble("tangential", out->sigma.tangential);
  out->observability_ratio = s.GetPositiveDouble("observability_ratio", out->observability_ratio);
  if (!(out->observability_ratio <= 1)) s.Fail("observability_ratio", "must be in (0, 1]");
}

}  // namespace

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
                    "continuity_gap_s",
                    "refine_intrinsics",
                    "refine_intrinsics_cameras",
                    "intrinsics_sigma",
                    "observability_ratio",
                    "time_offsets",
                    "max_time_offset_ms"});
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
  ReadIntrinsicsSettings(rig, &o.intrinsics);
  o.estimate_time_offsets = s.GetBool("time_offsets", o.estimate_time_offsets);
  o.max_time_offset_ms = s.GetPositiveDouble("max_time_offset_ms", o.max_time_offset_ms);
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

// Stage timings (report.stage_seconds, in order) and progress messages.
class StageLog {
 public:
  StageLog(const std::function<void(const MapperProgress&)>& progress, MapReport* report)
      : progress_(progress), report_(report), start_(Clock::now()) {}
  void Begin(const std::string& step, const std::string& message) const {
    Notify(MapperProgress::kInitialising, step, message);
  }
  void End(const std::string& name) {
    report_->stage_seconds.emplace_back(name, std::chrono::duration<double>(Clock::now() - start_).count());
    start_ = Clock::now();
  }
  void Notify(MapperProgress::Stage stage, const std::string& step, const std::string& message) const {
    if (!progress_) return;
    MapperProgress p;
    p.stage = stage;
    p.step = step;
    p.message = message;
    progress_(p);
  }

 private:
  const std::function<void(const MapperProgress&)>& progress_;
  MapReport* report_;
  Clock::time_point start_;
};

// Bundle settings whose iterations are reported as "refining (solve N)".
BundleSettings WithProgress(BundleSettings settings, std::function<void(const MapperProgress&)> progress,
                            int max_iterations, const int* solves) {
  if (!progress) return settings;
  settings.on_iteration = [progress, max_iterations, solves](int iteration, double cost, double rms) {
    MapperProgress p;
    p.stage = MapperProgress::kRefining;
    p.step = "refine";
    p.iteration = iteration;
    p.max_iterations = max_iterations;
    p.cost = cost;
    p.rms_px = rms;
    std::ostringstream msg;
    msg << "refining (solve " << *solves + 1 << "): iteration " << iteration << ", cost " << cost << ", rms "
        << rms << " px";
    p.message = msg.str();
    progress(p);
  };
  return settings;
}

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
};

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
  for (const Frame& f : AssembleFrames(s.messages, n, options_.sync_tolerance_us)) {
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

namespace {

// What one pass of the method reads besides the messages.
struct SolveInputs {
  const std::vector<std::string>& camera_names;
  const std::vector<CameraModel>& models;
  const std::vector<std::string>& warnings;
  const std::function<void(const MapperProgress&)>& progress;
};

// The whole method on `messages` (their utimes as the frames' clocks).
MapResult SolvePass(const std::vector<StoredMessage>& messages, const SolveInputs& s,
                    const MapperOptions& o) {
  const auto t_total = Clock::now();
  MapResult result;
  MapReport& report = result.report;
  report.warnings = s.warnings;
  report.detections_messages = static_cast<int>(messages.size());
  const int threads = o.threads > 0 ? o.threads : std::max(1u, std::thread::hardware_concurrency());
  report.threads = threads;
  StageLog log(s.progress, &report);

  log.Begin("frames", "assembling frames");
  const std::vector<Frame> frames =
      AssembleFrames(messages, static_cast<int>(s.camera_names.size()), o.sync_tolerance_us);
  report.frames_assembled = static_cast<int>(frames.size());
  Observations observations = CollectObservations(messages, frames, s.camera_names, o, &report);
  log.End("frames");

  log.Begin("hypotheses", "square poses of " + std::to_string(observations.obs.size()) + " observations");
  EstimateHypotheses(s.models, o.tau_e, threads, &observations.obs);
  for (const Observation& ob : observations.obs) report.ambiguous_observations += ob.kept == 2;
  log.End("hypotheses");

  log.Begin("markers", "marker graph");
  const MarkerLayout layout = BuildMarkerGraph(observations, o, threads, &report);
  log.End("markers");

  log.Begin("cameras", "camera graph");
  const std::vector<ViewPose> views = FitViews(observations, layout, s.models, threads);
  CameraPlacement cameras = BuildCameraGraph(views, observations, s.camera_names, o, threads, &report);
  log.End("cameras");

  log.Begin("object poses", "object pose per frame");
  const ObjectPoses poses = InitialObjectPoses(observations, frames, layout, cameras, o, threads, &report);
  log.End("object poses");

  const ObservationNames names{&frames, &s.camera_names, &observations.marker_ids};
  MapperBundle bundle = MakeBundleProblem(observations, names, layout, cameras, poses, s.models, &report);
  FillMap(bundle, observations, names, layout, cameras, o, &result.initial_map, &result.initial_trajectory);
  report.initial_rms_px = result.initial_map.rms_px;
  log.End("initial statistics");

  if (o.refine) {
    const BundleSettings settings =
        WithProgress(BundleSettingsFor(o, threads), s.progress, o.max_iterations, &report.solves);
    RefineWithRejection(observations, names, layout, o, settings, &bundle, &report);
    DropUnreliableCameras(observations, names, o, settings, &cameras, &bundle, &report);
    log.End("refine");
  }
  FillMap(bundle, observations, names, layout, cameras, o, &result.map, &result.trajectory);
  report.final_rms_px = result.map.rms_px;
  report.frames_used = result.map.num_frames;
  report.observations_used = result.map.num_observations;
  for (const MapCamera& c : result.map.cameras)
    if (c.observations == 0)
      report.warnings.push_back("camera '" + c.name + "' kept no observation after outlier rejection");
  log.Notify(MapperProgress::kDone, "done", "done");
  report.total_seconds = std::chrono::duration<double>(Clock::now() - t_total).count();
  return result;
}

// Frames assembled over `window_us` on the messages' times: the 95th percentile of their capture-time
// spread (microseconds) and how many messages are alone in their frame.
struct FrameSpread {
  double p95_us = 0.0;
  int alone = 0;
};

FrameSpread SpreadOf(const std::vector<StoredMessage>& messages, int num_cameras, int64_t window_us) {
  FrameSpread out;
  std::vector<double> spreads;
  for (const Frame& f : AssembleFrames(messages, num_cameras, window_us)) {
    int64_t lo = messages[f.messages[0]].utime, hi = lo;
    for (int i : f.messages) {
      lo = std::min(lo, messages[i].utime);
      hi = std::max(hi, messages[i].utime);
    }
    if (f.messages.size() < 2)
      ++out.alone;
    else
      spreads.push_back(static_cast<double>(hi - lo));
  }
  std::sort(spreads.begin(), spreads.end());
  if (!spreads.empty())
    out.p95_us = spreads[static_cast<size_t>(0.95 * static_cast<double>(spreads.size() - 1))];
  return out;
}

// The window the second pass assembles frames over, or 0 when it is not worth running. Offsets that bring
// the cameras' frames together (clocks that differ by a constant: the spread falls to the noise) re-assemble
// them over 1.5 x the spread left (at least the sync tolerance, at most the first window): clocks that also
// jitter frame to frame (caliscope's per-camera times, 5-6 ms RMS) keep their frames whole, the rest being
// each observation's dt. Offsets that leave the frames as spread or leave more images alone (a camera's
// capture latency that its timestamps do not show, e.g. 120 ms at 6 fps, puts its images between the
// others' frames) keep the first pass's frames.
int64_t SecondPassWindowUs(const std::vector<StoredMessage>& raw, const std::vector<StoredMessage>& corrected,
                           int num_cameras, int64_t first_window_us, int64_t sync_tolerance_us) {
  const FrameSpread before = SpreadOf(raw, num_cameras, first_window_us);
  const FrameSpread after = SpreadOf(corrected, num_cameras, first_window_us);
  if (!(after.p95_us < before.p95_us) || after.alone > before.alone) return 0;
  return std::clamp(static_cast<int64_t>(std::llround(1.5 * after.p95_us)), sync_tolerance_us,
                    std::max(sync_tolerance_us, first_window_us));
}

// Time offsets: a first pass with frames assembled over max_time_offset_ms, then the method again on the
// clocks it found corrected (frames assembled at the sync tolerance, offsets refined once more from 0):
// the offsets are the sum, the second pass's map and trajectory (in the reference camera's clock) the
// result.
MapResult SolveWithTimeOffsets(const std::vector<StoredMessage>& messages, const SolveInputs& s,
                               const MapperOptions& o) {
  MapperOptions first_options = o;
  first_options.sync_tolerance_us =
      std::max(o.sync_tolerance_us, static_cast<int64_t>(std::llround(o.max_time_offset_ms * 1000)));
  const MapResult first = SolvePass(messages, s, first_options);
  std::map<std::string, double> offset_us;
  for (const MapCamera& c : first.map.cameras) offset_us[c.name] = c.time_offset_us;
  std::vector<StoredMessage> corrected = messages;
  for (StoredMessage& m : corrected) {
    const auto it = offset_us.find(s.camera_names[m.camera]);
    if (it != offset_us.end()) m.utime -= std::llround(it->second);
  }
  MapperOptions second_options = o;
  second_options.reference_camera = first.map.reference_camera;  // offsets against the same clock
  second_options.sync_tolerance_us =
      SecondPassWindowUs(messages, corrected, static_cast<int>(s.camera_names.size()),
                         first_options.sync_tolerance_us, o.sync_tolerance_us);
  std::ostringstream worse;
  MapResult result;
  if (second_options.sync_tolerance_us == 0) {
    worse << "would spread the frames further";
  } else {
    try {
      result = SolvePass(corrected, s, second_options);
      if (!(result.map.rms_px <= first.map.rms_px))
        worse << "fit worse (rms " << result.map.rms_px << " px against " << first.map.rms_px << " px)";
    } catch (const MapperError& e) {
      worse << "cannot be mapped (" << e.what() << ")";
    }
  }
  if (!worse.str().empty()) {
    // The first pass's frames (and its offsets) are the result.
    MapResult kept = first;
    kept.report.total_seconds += result.report.total_seconds;
    kept.report.warnings.push_back("time offsets: frames re-assembled on the corrected clocks " +
                                   worse.str() + ": the first pass's frames are kept");
    return kept;
  }
  for (MapCamera& c : result.map.cameras)
    c.time_offset_us += offset_us.count(c.name) ? offset_us[c.name] : 0.0;
  for (MapCamera& c : result.initial_map.cameras)
    c.time_offset_us = offset_us.count(c.name) ? offset_us[c.name] : 0.0;
  result.report.stage_seconds.insert(result.report.stage_seconds.begin(),
                                     {"time offsets (first pass)", first.report.total_seconds});
  result.report.total_seconds += first.report.total_seconds;
  return result;
}

}  // namespace

MapResult Mapper::Solve() {
  const Impl& s = *impl_;
  if (s.messages.empty()) throw MapperError("no detections received (channels MCMT_DETECTIONS_*)");
  const SolveInputs inputs{s.camera_names, s.models, s.warnings, s.progress};
  MapResult result = options_.estimate_time_offsets && options_.refine
                         ? SolveWithTimeOffsets(s.messages, inputs, options_)
                         : SolvePass(s.messages, inputs, options_);
  result.detections = s.inputs;  // for the diagnostics (mapper/diagnostics.h)
  return result;
}

}  // namespace mcmt
