#include "mapper/mapper.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <map>
#include <numeric>
#include <set>
#include <sstream>
#include <thread>
#include <tuple>
#include <unordered_map>

#include "core/lcm_util.h"
#include "mapper/bodies.h"
#include "mapper/diagnostics.h"
#include "mapper/epochs.h"
#include "mapper/intrinsics.h"
#include "mapper/stages.h"
#include "mapper/update.h"

namespace mcmt {

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
  std::unique_ptr<RigMap> base_map;  // offline update
  UpdateSettings update;
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
  for (const Frame& f : AssembleFrames(s.messages, n, options_.sync_tolerance_us())) {
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

// What one pass of the method reads besides the messages (the same for one object and for several).
using SolveInputs = BodiesInputs;

// The marker layout and the cameras' placement of an earlier pass's map (`start`), for a pass on the same
// session: its graphs are not built again. A camera's views are the frames it sees a placed marker in.
void PlacedAsIn(const RigMap& start, const Observations& observations,
                const std::vector<std::string>& camera_names, MarkerLayout* layout,
                CameraPlacement* cameras) {
  *layout = LayoutFromMap(start, observations);
  *cameras = PlacementFromMap(start, camera_names);
  std::set<std::pair<int, int>> views;
  for (const Observation& ob : observations.obs)
    if (layout->placed[ob.marker] && ob.kept > 0) views.insert({ob.camera, ob.frame});
  for (const auto& view : views) ++cameras->views[view.first];
}

// The square poses (step 1) depend on an observation's camera (its given intrinsics), corners and side
// only, not on the frame its message joins: a pass on the same messages with other clocks takes them from
// an earlier pass's observations (`earlier`, the same models and tau_e) and estimates the rest.
void HypothesesAsIn(const Observations& earlier, const std::vector<CameraModel>& models, double tau_e,
                    int threads, Observations* observations) {
  using Key = std::tuple<int, double, std::array<double, 8>>;
  auto key_of = [](const Observation& ob) {
    Key key{ob.camera, ob.side, {}};
    for (int i = 0; i < 4; ++i) {
      std::get<2>(key)[2 * i] = ob.corners[i].x();
      std::get<2>(key)[2 * i + 1] = ob.corners[i].y();
    }
    return key;
  };
  std::map<Key, size_t> found;
  for (size_t i = 0; i < earlier.obs.size(); ++i) found.emplace(key_of(earlier.obs[i]), i);
  std::vector<Observation>& obs = observations->obs;
  observations->poses.assign(obs.size(), SquarePose());
  Observations missing;
  std::vector<size_t> missing_at;
  for (size_t i = 0; i < obs.size(); ++i) {
    Observation& ob = obs[i];
    const auto it = found.find(key_of(ob));
    if (it != found.end()) {
      observations->poses[i] = earlier.poses[it->second];
      ob.kept = earlier.obs[it->second].kept;
    } else {
      missing.obs.push_back(ob);
      missing_at.push_back(i);
    }
  }
  EstimateHypotheses(models, tau_e, threads, &missing);
  for (size_t j = 0; j < missing.obs.size(); ++j) {
    obs[missing_at[j]] = missing.obs[j];
    observations->poses[missing_at[j]] = missing.poses[j];
  }
}

// The time offsets' first pass only finds the clocks the frames are re-assembled on (to about a
// millisecond; the second pass refines them on every frame): on a session of more frames than this it
// maps every stride-th frame (stride = ceil(frames / kFirstPassFrames)), and every frame that sees a
// marker, a camera or a pair of cameras seen together that the thinned frames would leave with fewer than
// kFirstPassRareFrames frames (the graphs and the second pass, which starts from the first pass's layout
// and cameras, keep what the data have of them).
constexpr size_t kFirstPassFrames = 150;
constexpr size_t kFirstPassRareFrames = 20;

std::vector<Frame> ThinnedFrames(const std::vector<Frame>& frames, const std::vector<StoredMessage>& messages,
                                 int num_cameras) {
  if (frames.size() <= kFirstPassFrames) return frames;
  const size_t stride = (frames.size() + kFirstPassFrames - 1) / kFirstPassFrames;
  // What each frame sees: marker ids, cameras, camera pairs (keys: id, -1 - camera, -1 - n - pair).
  auto seen_in = [&](const Frame& f) {
    std::set<int64_t> keys;
    for (int a : f.messages) {
      keys.insert(-1 - messages[a].camera);
      for (int b : f.messages)
        if (messages[a].camera < messages[b].camera)
          keys.insert(-1 - num_cameras - (messages[a].camera * num_cameras + messages[b].camera));
      for (const StoredMarker& mk : messages[a].markers) keys.insert(mk.id);
    }
    return keys;
  };
  std::vector<std::set<int64_t>> keys(frames.size());
  std::map<int64_t, size_t> frames_of;
  for (size_t f = 0; f < frames.size(); ++f) {
    keys[f] = seen_in(frames[f]);
    for (int64_t k : keys[f]) ++frames_of[k];
  }
  std::vector<Frame> out;
  for (size_t f = 0; f < frames.size(); ++f) {
    bool keep = f % stride == 0;
    for (int64_t k : keys[f]) keep = keep || frames_of[k] < kFirstPassRareFrames * stride;
    if (keep) out.push_back(frames[f]);
  }
  return out;
}

// The whole method on `messages` (their utimes as the frames' clocks). With `moves`, cameras that moved
// are looked for after the first refinement: when there are any, the pass stops there with them and the
// reference camera's name in *reference. With `start`, the layout and the cameras begin where that map
// has them (PlacedAsIn) instead of from the graphs. velocity_passes: RefineWithRejection's. With
// `square_poses` empty, it receives the observations with their square poses; non-empty, the poses are
// taken from it (HypothesesAsIn). `thinned`: on ThinnedFrames (the time offsets' first pass).
MapResult SolvePass(const std::vector<StoredMessage>& messages, const SolveInputs& s, const MapperOptions& o,
                    std::vector<EpochSplit>* moves = nullptr, std::string* reference = nullptr,
                    const std::vector<char>& split = {}, const RigMap* start = nullptr,
                    int velocity_passes = 2, Observations* square_poses = nullptr, bool thinned = false) {
  const auto t_total = Clock::now();
  MapResult result;
  MapReport& report = result.report;
  report.warnings = s.warnings;
  report.detections_messages = static_cast<int>(messages.size());
  const int threads = o.threads > 0 ? o.threads : std::max(1u, std::thread::hardware_concurrency());
  report.threads = threads;
  StageLog log(s.progress, &report);

  log.Begin("frames", "assembling frames");
  const int num_cameras = static_cast<int>(s.camera_names.size());
  std::vector<Frame> frames = AssembleFrames(messages, num_cameras, o.sync_tolerance_us());
  if (thinned) frames = ThinnedFrames(frames, messages, num_cameras);
  report.frames_assembled = static_cast<int>(frames.size());
  Observations observations = CollectObservations(messages, frames, s.camera_names, o, &report);
  log.End("frames");

  log.Begin("hypotheses", "square poses of " + std::to_string(observations.obs.size()) + " observations");
  if (square_poses && !square_poses->obs.empty()) {
    HypothesesAsIn(*square_poses, s.models, o.tau_e, threads, &observations);
  } else {
    EstimateHypotheses(s.models, o.tau_e, threads, &observations);
    if (square_poses) *square_poses = observations;
  }
  for (const Observation& ob : observations.obs) report.ambiguous_observations += ob.kept == 2;
  log.End("hypotheses");

  MarkerLayout layout;
  CameraPlacement cameras;
  if (start) {
    PlacedAsIn(*start, observations, s.camera_names, &layout, &cameras);
    log.End("layout and cameras (first pass)");
  } else {
    log.Begin("markers", "marker graph");
    layout = BuildMarkerGraph(observations, o, threads, &report);
    log.End("markers");
    log.Begin("cameras", "camera graph");
    const std::vector<ViewPose> views = FitViews(observations, layout, s.models, threads);
    cameras = BuildCameraGraph(views, observations, s.camera_names, o, threads, &report);
    log.End("cameras");
  }

  log.Begin("object poses", "object pose per frame");
  const ObjectPoses poses = InitialObjectPoses(observations, frames, layout, cameras, o, threads, &report);
  log.End("object poses");
  // Nothing after the initial poses reads the hypotheses: released before the bundle adjustment, the peak
  // (8-camera board session, 3000 frames: 29.7 MB, 320 bytes per observation).
  std::vector<SquarePose>().swap(observations.poses);

  const ObservationNames names{&frames, &s.camera_names, &observations.marker_ids};
  MapperBundle bundle = MakeBundleProblem(observations, names, layout, cameras, poses, s.models, &report);
  FillMap(bundle, observations, names, layout, cameras, o, &result.initial_map, &result.initial_trajectory);
  report.initial_rms_px = result.initial_map.rms_px;
  log.End("initial statistics");

  if (o.refine) {
    const BundleSettings settings =
        WithProgress(BundleSettingsFor(o, threads), s.progress, o.max_iterations, &report.solves);
    RefineWithRejection(observations, names, layout, o, settings, &bundle, &report, velocity_passes);
    log.End("refine");
    if (moves && o.detect_moves) {
      *moves = FindCameraMoves(bundle.problem, frames, o, split);
      log.End("moved cameras");
      if (!moves->empty()) {
        *reference = s.camera_names[cameras.reference];
        report.total_seconds = std::chrono::duration<double>(Clock::now() - t_total).count();
        return result;
      }
    }
    DropUnreliableCameras(observations, names, o, settings, &cameras, &bundle, &report);
    log.End("unreliable cameras");
  }
  std::vector<int> row_frames;
  FillMap(bundle, observations, names, layout, cameras, o, &result.map, &result.trajectory, &row_frames);
  result.membership = MembershipOf(frames, row_frames, messages.size());
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
// result. The first pass only finds the clocks the frames are re-assembled on (it stops early): the
// intrinsics are refined in the second (refining them in both took 2.2 of the 3.9 s of bench_selfcal's
// everything row; the clocks after the second pass are the same within a few microseconds), and so are the
// velocities (the second pass refines the clocks again from the first's). When the first pass's frames are
// the result, it is solved again in full.
MapResult SolveWithTimeOffsets(const std::vector<StoredMessage>& messages, const SolveInputs& s,
                               const MapperOptions& o) {
  MapperOptions first_options = o;
  first_options.sync_tolerance_ms = std::max(o.sync_tolerance_ms, o.max_time_offset_ms);
  first_options.intrinsics.refine = IntrinsicsRefinement::kNone;
  // The clocks for re-assembly, not the result: the rough stop (bench_selfcal's everything row: 8 of its
  // 11 iterations, the same errors and clocks to the table's digits but for a last one).
  first_options.paper_stop_px = kRoughStopFactor * o.paper_stop_px;
  Observations square_poses;  // the first pass's, for the second (the same given intrinsics)
  const MapResult first =
      SolvePass(messages, s, first_options, nullptr, nullptr, {}, nullptr, 0, &square_poses, true);
  std::vector<StoredMessage> corrected = messages;
  for (StoredMessage& m : corrected) m.utime = first.map.ReferenceUtime(s.camera_names[m.camera], m.utime);
  MapperOptions second_options = o;
  second_options.reference_camera = first.map.reference_camera;  // offsets against the same clock
  const int64_t second_window_us =
      SecondPassWindowUs(messages, corrected, static_cast<int>(s.camera_names.size()),
                         first_options.sync_tolerance_us(), o.sync_tolerance_us());
  second_options.sync_tolerance_ms = 1e-3 * static_cast<double>(second_window_us);
  std::ostringstream worse;
  MapResult result;
  if (second_window_us == 0) {
    worse << "would spread the frames further";
  } else {
    try {
      result = SolvePass(corrected, s, second_options, nullptr, nullptr, {}, &first.map, 2, &square_poses);
      if (!(result.map.rms_px <= first.map.rms_px))
        worse << "fit worse (rms " << result.map.rms_px << " px against " << first.map.rms_px << " px)";
    } catch (const MapperError& e) {
      worse << "cannot be mapped (" << e.what() << ")";
    }
  }
  if (!worse.str().empty()) {
    // The first pass's frames (and its offsets) are the result: solved again in full (the velocities
    // updated, the intrinsics refined when asked).
    first_options.intrinsics = o.intrinsics;
    first_options.paper_stop_px = o.paper_stop_px;
    MapResult kept = SolvePass(messages, s, first_options, nullptr, nullptr, {}, nullptr, 2, &square_poses);
    kept.report.total_seconds += first.report.total_seconds;
    kept.report.total_seconds += result.report.total_seconds;
    kept.report.warnings.push_back("time offsets: frames re-assembled on the corrected clocks " +
                                   worse.str() + ": the first pass's frames are kept");
    return kept;
  }
  // The clocks are the sum of both passes' (the second's on clocks already corrected), expressed at the
  // second pass's time reference.
  ComposeClocks(first.map, &result.map);
  const int64_t reference = result.map.time_reference_utime;
  for (MapCamera& c : result.initial_map.cameras) {
    const MapCamera* f = first.map.FindCamera(c.name);
    c.time_offset_us = f ? f->ClockUs(reference, first.map.time_reference_utime) : 0.0;
    c.time_drift_ppm = f ? f->time_drift_ppm : 0.0;
  }
  result.initial_map.time_reference_utime = reference;
  // What the first pass's graphs left out stays out (the second pass began from its map), and is said.
  for (const std::string& w : first.report.warnings)
    if (std::find(result.report.warnings.begin(), result.report.warnings.end(), w) ==
        result.report.warnings.end())
      result.report.warnings.push_back(w);
  for (const std::string& c : first.report.dropped_cameras)
    if (std::find(result.report.dropped_cameras.begin(), result.report.dropped_cameras.end(), c) ==
        result.report.dropped_cameras.end())
      result.report.dropped_cameras.push_back(c);
  std::set<int> rejected;
  for (const RejectedMarker& r : result.report.rejected_markers) rejected.insert(r.id);
  for (const RejectedMarker& r : first.report.rejected_markers)
    if (rejected.insert(r.id).second) result.report.rejected_markers.push_back(r);
  result.report.stage_seconds.insert(result.report.stage_seconds.begin(),
                                     {"time offsets (first pass)", first.report.total_seconds});
  result.report.total_seconds += first.report.total_seconds;
  return result;
}

// Cameras that moved (mapper/epochs.h): a pass up to the first refinement looks for them; the strongest
// move found has the camera's earlier epoch become a camera of its own, and the method runs again, until
// no camera splits (one move per camera). The splits in the order made (*splits).
MapResult SolveWithEpochs(const std::vector<StoredMessage>& messages, const SolveInputs& s,
                          const MapperOptions& o, std::vector<EpochSplit>* splits) {
  // The messages are copied only when a camera splits (a copy made up front stayed alive through every
  // pass's bundle adjustment, the mapper's peak: 80 bytes per observation).
  std::vector<StoredMessage> split_messages;
  const std::vector<StoredMessage>* pass_messages = &messages;
  std::vector<std::string> names = s.camera_names;
  std::vector<CameraModel> models = s.models;
  MapperOptions options = o;
  std::vector<char> split(names.size(), 0);
  double seconds = 0.0;
  for (;;) {
    const SolveInputs inputs{names, models, s.warnings, s.progress};
    std::vector<EpochSplit> found;
    std::string reference;
    MapResult result = SolvePass(*pass_messages, inputs, options, &found, &reference, split);
    if (found.empty()) {
      if (seconds > 0)
        result.report.stage_seconds.insert(result.report.stage_seconds.begin(),
                                           {"moved cameras (earlier passes)", seconds});
      result.report.total_seconds += seconds;
      return result;
    }
    seconds += result.report.total_seconds;
    found.resize(1);
    if (pass_messages != &split_messages) {
      split_messages = messages;
      pass_messages = &split_messages;
    }
    SplitCameraEpochs(found, &split_messages, &names, &models);
    split[found[0].camera] = 1;
    split.push_back(1);                    // the earlier epoch
    options.reference_camera = reference;  // its later epoch when it moved
    splits->push_back(found[0]);
  }
}

// A refined map that no camera supports (mapper/diagnostics.h UnsupportedMapText) is an error, a warning
// in report.warnings under --allow-partial. Nothing is written then (as for the other MapperErrors); a
// live session's detections are kept by the node, and --allow-partial maps them again with the warning.
void CheckSupported(const MapperOptions& o, MapResult* result) {
  // With time offsets too: the diagnostics move each frame's pose to its observations' capture times along
  // the bundle's own velocities (the trajectory's), so each camera's RMS is the bundle's.
  if (!o.refine || o.unsupported_rms_ratio <= 0) return;
  DiagnosticsOptions d;
  d.covariance = false;
  const std::string problem = UnsupportedMapText(ComputeObjectDiagnostics(*result, d),
                                                 o.unsupported_rms_ratio, o.unsupported_side_fraction);
  if (problem.empty()) return;
  const std::string advice =
      ": it is likely wrong (markers placed in a wrong relative pose, or intrinsics or markers.sizes that do "
      "not fit the images); check those, record frames where a camera sees two markers at once less "
      "obliquely";
  if (!o.allow_partial)
    throw MapperError(problem + advice + ", or use --allow-partial to write it with this warning");
  result->report.warnings.push_back(problem + advice);
}

}  // namespace

void Mapper::SetBaseMap(const RigMap& old_map, bool refine_layout,
                        const std::vector<std::string>& only_cameras) {
  impl_->base_map = std::make_unique<RigMap>(old_map);
  impl_->update.refine_layout = refine_layout;
  impl_->update.only_cameras = only_cameras;
}

MapResult Mapper::Solve() {
  const Impl& s = *impl_;
  if (s.messages.empty()) throw MapperError("no detections received (channels MCMT_DETECTIONS_*)");
  const SolveInputs inputs{s.camera_names, s.models, s.warnings, s.progress};
  if (!options_.bodies.empty()) {
    MapResult result = SolveBodies(s.messages, inputs, options_);
    result.detections = s.inputs;
    result.report.marker_size_sigma_percent = options_.marker_size_sigma_percent;
    CheckSupported(options_, &result);
    return result;
  }
  std::vector<EpochSplit> splits;
  MapResult result = s.base_map ? SolveUpdate(s.messages, s.camera_names, s.models, s.warnings, options_,
                                              *s.base_map, s.update)
                     : options_.estimate_time_offsets && options_.refine
                         ? SolveWithTimeOffsets(s.messages, inputs, options_)
                         : SolveWithEpochs(s.messages, inputs, options_, &splits);
  result.detections = s.inputs;  // for the diagnostics (mapper/diagnostics.h)
  MergeCameraEpochs(splits, s.camera_names, &result);
  result.report.marker_size_sigma_percent = options_.marker_size_sigma_percent;
  CheckSupported(options_, &result);
  return result;
}

}  // namespace mcmt
