// TrackerNode: detections in, object_pose_t out.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <iterator>
#include <set>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include "core/files.h"
#include "core/lcm_util.h"
#include "tracker/relative.h"
#include "tracker/tracker.h"

namespace mcmt {
namespace {

double Percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(std::floor(q * (v.size() - 1) + 0.5)));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}

std::string FormatMs(double ms) {
  std::ostringstream s;
  s << ms;
  return s.str();
}

std::string Join(const std::vector<std::string>& names) {
  std::string out;
  for (size_t i = 0; i < names.size(); ++i) out += (i ? ", " : "") + names[i];
  return out;
}

}  // namespace

TrackerNode::TrackerNode(lcm::LCM& lcm, const RigConfig& rig, const TrackerNodeOptions& options,
                         std::optional<RigMap> map, lcm::LCM* output)
    : lcm_(lcm),
      output_(output ? output : (options.log_mode ? nullptr : &lcm)),
      rig_(rig),
      options_(options) {
  options_.tracker.Validate();
  if (options_.keep_trajectory && !options_.partial_path.empty()) {
    partial_.reset(std::fopen(options_.partial_path.c_str(), "w"));
    if (!partial_) throw std::runtime_error(options_.partial_path + ": cannot write");
    std::fprintf(partial_.get(), "%s\n", TrajectoryHeader(false, true).c_str());
    std::fflush(partial_.get());
  }
  if (map) {
    CheckMapMatchesRig(*map, rig_, "map");
    map_from_file_ = true;
    SetMap(*map, "map file");
  }
  // LCM queues 30 messages per subscription by default and drops the rest: a burst of detections
  // (many cameras, a replay) must not lose any.
  subscriptions_.push_back(lcm_.subscribe(kDetectionsChannelRegex, &TrackerNode::HandleDetections, this));
  subscriptions_.back()->setQueueCapacity(kSubscriptionQueueCapacity);
  waits_for_map_ = !map;
  // Live, newer maps on MCMT_MAP replace the map file too (mcmt-mapper --maintain re-estimates a moved
  // camera, adds a new one); in a log only without a map file.
  if (!map || !options_.log_mode)
    subscriptions_.push_back(lcm_.subscribe(kMapChannel, &TrackerNode::HandleMap, this));
  last_status_wall_us_ = NowUtime();
}

TrackerNode::~TrackerNode() {
  for (auto* s : subscriptions_) lcm_.unsubscribe(s);
}

void TrackerNode::WarnOnce(const std::string& key, const std::string& text) {
  if (!warned_.insert(key).second) return;
  std::cerr << "mcmt-tracker: warning: " << text << std::endl;
}

namespace {

// A stream's partial file: OUT (single) or BodyPath of OUT, for OUT.partial; ".partial" appended.
std::string PartialPath(const std::string& partial_path, const std::string& stream, bool single) {
  const std::string suffix = ".partial";
  const bool ends = partial_path.size() > suffix.size() &&
                    partial_path.compare(partial_path.size() - suffix.size(), suffix.size(), suffix) == 0;
  const std::string base = ends ? partial_path.substr(0, partial_path.size() - suffix.size()) : partial_path;
  return (single ? base : BodyPath(base, stream)) + suffix;
}

}  // namespace

const std::vector<TrajectoryRow>& TrackerNode::trajectory() const {
  static const std::vector<TrajectoryRow> kNone;
  return streams_.empty() ? kNone : streams_[0].trajectory;
}

void TrackerNode::SetStreams(const RigMap& map) {
  const bool single = map.objects.empty();
  const std::vector<BodyName> names = MapBodies(map, options_.tracker.object);
  const std::vector<PoseStreamPlan> plan = PlanPoseStreams(options_.tracker, names, single);
  std::vector<Body> bodies;
  std::vector<Relative> relatives;
  std::map<int, size_t> body_of_marker;
  std::vector<int> body_index(names.size(), -1);  // map body -> index in bodies
  for (size_t s = 0; s < plan.size(); ++s) {
    if (plan[s].body < 0) continue;
    Body b;
    b.stream = s;
    // The map file's covariance describes a single-object map's frames (the mapper writes none for
    // several bodies) and only that map: a newer map from MCMT_MAP comes without one.
    const MapCovariance* covariance =
        single && map_from_file_ && options_.map_covariance ? &*options_.map_covariance : nullptr;
    b.estimator = std::make_unique<PoseEstimator>(single ? map : map.ObjectMap(plan[s].body),
                                                  options_.tracker, covariance);
    b.motion = MotionModel(options_.tracker.max_gap_s);
    body_index[plan[s].body] = static_cast<int>(bodies.size());
    if (!single)
      for (const MapMarker& m : map.objects[plan[s].body].markers) body_of_marker[m.id] = bodies.size();
    bodies.push_back(std::move(b));
  }
  for (size_t s = 0; s < plan.size(); ++s) {
    if (plan[s].body >= 0) continue;
    Relative r;
    r.stream = s;
    r.of = body_index[plan[s].of];
    r.in = body_index[plan[s].in];
    if (r.in < 0) r.rig_from_in = map.objects[plan[s].in].rig_from_object;  // a static body
    relatives.push_back(r);
  }
  // The streams: a stream of the same name (a newer map of the same rig) keeps what it published.
  std::vector<PoseStream> streams;
  std::vector<std::unique_ptr<std::FILE, int (*)(std::FILE*)>> partials;
  std::vector<int> previous;  // index in streams_ of the stream of the same name, or -1
  for (const PoseStreamPlan& p : plan) {
    PoseStream st;
    st.name = p.name;
    st.channel = p.channel;
    st.single = single;
    previous.push_back(-1);
    for (size_t k = 0; k < streams_.size(); ++k)
      if (streams_[k].name == p.name && streams_[k].single == single) previous.back() = static_cast<int>(k);
    std::unique_ptr<std::FILE, int (*)(std::FILE*)> partial{nullptr, &std::fclose};
    if (previous.back() < 0 && options_.keep_trajectory && !options_.partial_path.empty() && !single) {
      const std::string path = PartialPath(options_.partial_path, p.name, false);
      partial.reset(std::fopen(path.c_str(), "w"));
      if (!partial) throw std::runtime_error(path + ": cannot write");
      std::fprintf(partial.get(), "%s\n", TrajectoryHeader(false, true).c_str());
      std::fflush(partial.get());
    }
    streams.push_back(std::move(st));
    partials.push_back(std::move(partial));
  }
  // Nothing throws from here on.
  for (size_t s = 0; s < streams.size(); ++s) {
    if (previous[s] >= 0) {
      PoseStream& old = streams_[previous[s]];
      streams[s].trajectory = std::move(old.trajectory);
      streams[s].frames = old.frames;
      streams[s].tracked = old.tracked;
      partials[s] = std::move(stream_partials_[previous[s]]);
    } else if (single && partial_) {
      partials[s] = std::move(partial_);  // the constructor's
    }
  }
  if (!single && partial_) {  // several bodies: the per-stream files replace the single one
    partial_.reset();
    std::remove(options_.partial_path.c_str());
  }
  bodies_ = std::move(bodies);
  relatives_ = std::move(relatives);
  body_of_marker_ = std::move(body_of_marker);
  streams_ = std::move(streams);
  stream_partials_ = std::move(partials);
  estimator_ = bodies_.front().estimator.get();
}

void TrackerNode::SetMap(const RigMap& map, const std::string& origin) {
  const bool switching = estimator_ != nullptr;
  SetStreams(map);  // throws before anything changes when the map's bodies do not fit the options
  // Frames are assembled over the map's cameras. A newer map (mcmt-mapper --maintain) keeps the frames
  // being assembled: they are solved with it, none is lost; a camera the new map adds joins as it reports.
  if (!switching) {
    FrameSyncOptions& sync = sync_options_;
    sync.tolerance_us = static_cast<int64_t>(options_.tracker.sync_tolerance_ms * 1000.0);
    // A frame spans sync_tolerance_ms of capture time: its views cannot all have come before that.
    sync.deadline_us =
        std::max(static_cast<int64_t>(options_.tracker.deadline_ms * 1000.0), sync.tolerance_us);
    sync.camera_timeout_us = static_cast<int64_t>(options_.tracker.camera_timeout_s * 1e6);
    sync.max_clock_jump_us = static_cast<int64_t>(options_.tracker.max_clock_jump_s * 1e6);
    sync.max_wait_us = static_cast<int64_t>(options_.tracker.max_wait_ms * 1000.0);
    sync.arrival_is_wall_time = !options_.log_mode;
    sync.cameras.clear();
    for (const auto& c : map.cameras) sync.cameras.push_back(c.name);  // waited for from the start
    sync_ = std::make_unique<FrameSynchronizer>(sync);
    // Cameras whose clocks were mapped apart are often not triggered together either: their phases are
    // measured over the first frames before any frame is assembled (a synchronised rig's map has none).
    measuring_window_ = map.HasClocks() && !options_.tracker.sync_tolerance_set;
    reported_stale_.clear();
  }
  if (options_.tracker.camera_health) {
    std::vector<std::string> names;
    for (const auto& c : map.cameras) names.push_back(c.name);
    health_ = std::make_unique<HealthMonitor>(names, options_.tracker.health);  // a new map: every camera ok
    companions_.clear();
    last_seen_utime_.clear();
    if (switching) health_change_ = "new map from " + origin + ": every camera judged afresh";
  }
  if (switching) stats_.map_switches++;
  if (!rig_.markers.dictionary.empty() && !map.dictionary.empty() &&
      map.dictionary != rig_.markers.dictionary)
    WarnOnce("dict-map", "the map's dictionary '" + map.dictionary + "' differs from the rig's '" +
                             rig_.markers.dictionary + "'");
  if (!options_.quiet || switching) {
    std::ostringstream s;
    s << "mcmt-tracker: " << (switching ? "switched to a newer map" : "using map") << " from " << origin
      << ": " << map.cameras.size() << " cameras, ";
    if (map.objects.empty()) {
      s << map.markers.size() << " markers";
    } else {
      s << map.objects.size() << " bodies (";
      for (size_t k = 0; k < map.objects.size(); ++k)
        s << (k ? ", " : "") << map.objects[k].name << " " << map.objects[k].markers.size() << " markers"
          << (map.objects[k].is_static ? " static" : "");
      s << ")";
    }
    s << ", rms " << map.rms_px << " px";
    if (map.objects.empty() && map_from_file_ && options_.map_covariance && options_.tracker.map_uncertainty)
      s << ", its covariance in the poses' (" << options_.map_covariance->cameras.size() << " cameras, "
        << options_.map_covariance->markers.size() << " markers)";
    s << "; poses on ";
    for (size_t k = 0; k < streams_.size(); ++k) s << (k ? ", " : "") << streams_[k].channel;
    std::cerr << s.str() << std::endl;
  }
}

void TrackerNode::HandleDetections(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  OnDetections(channel, rbuf->data, rbuf->data_size);
}

void TrackerNode::HandleMap(const lcm::ReceiveBuffer* rbuf, const std::string& /*channel*/) {
  OnMap(rbuf->data, rbuf->data_size);
}

void TrackerNode::OnMap(const void* data, size_t size) {
  MapMessage msg;  // rig_map2_t (mcmt-mapper) or rig_map_t (older logs)
  std::string error;
  if (!DecodeMapMessage(data, size, &msg, &error)) {
    WarnOnce("bad-map", std::string("ignoring undecodable message on ") + kMapChannel + ": " + error);
    return;
  }
  if (estimator_ && msg.utime <= map_utime_) return;  // the same map again, or an older one
  try {
    CheckMapMatchesRig(msg.map, rig_, kMapChannel);
    map_from_file_ = false;
    SetMap(msg.map, std::string(kMapChannel) + " (utime " + std::to_string(msg.utime) + ")");
    map_utime_ = msg.utime;
  } catch (const std::exception& e) {
    WarnOnce("map-" + std::to_string(msg.utime), std::string("ignoring map: ") + e.what());
  }
}

void TrackerNode::OnDetections(const std::string& channel, const void* data, size_t size) {
  const int64_t arrival_wall = NowUtime();
  detections_t msg;
  std::string error;
  if (!Decode(data, size, &msg, &error)) {
    stats_.bad_messages++;
    WarnOnce("bad:" + channel, "ignoring undecodable message on " + channel + ": " + error);
    return;
  }
  if (!estimator_) {
    stats_.no_map++;
    WarnOnce("no-map", "no map yet: detections are dropped until " + std::string(kMapChannel) + " arrives");
    return;
  }
  if (const std::string problem = DetectionsProblem(msg, channel); !problem.empty()) {
    stats_.invalid++;
    WarnOnce("problem:" + channel + problem, problem + "; its messages are dropped");
    return;
  }
  if (duplicates_.Repeated(msg)) {
    stats_.duplicates++;
    WarnOnce("dup:" + msg.camera, "camera '" + msg.camera + "' on " + channel +
                                      ": repeated message (same seq and utime) dropped, e.g. " +
                                      duplicates_.examples().back());
    return;
  }
  {
    std::vector<int> ids;
    if (const int n = DropInvalidMarkers(&msg, &ids)) {
      stats_.invalid_markers += n;
      WarnOnce("corners:" + msg.camera, "camera '" + msg.camera + "' on " + channel + ": marker " +
                                            std::to_string(ids.front()) + " (seq " + std::to_string(msg.seq) +
                                            ") has non-finite or absurd corners; such markers are dropped");
    }
  }
  if (!estimator_->map().FindCamera(msg.camera)) {
    stats_.unknown_camera++;
    std::vector<std::string> names;
    for (const auto& c : estimator_->map().cameras) names.push_back(c.name);
    WarnOnce("cam:" + msg.camera, "ignoring detections of camera '" + msg.camera + "' on " + channel +
                                      ": not in the map (" + Join(names) + ")");
    return;
  }
  {
    const CameraModel& mapped = estimator_->map().FindCamera(msg.camera)->model;
    const camera_model_t& m = msg.camera_model;
    auto differs = [](double a, double b) { return std::abs(a - b) > 1e-6 * std::max(1.0, std::abs(b)); };
    if (m.width != mapped.width || m.height != mapped.height || differs(m.fx, mapped.fx) ||
        differs(m.fy, mapped.fy) || differs(m.cx, mapped.cx) || differs(m.cy, mapped.cy))
      WarnOnce("intrinsics:" + msg.camera,
               "camera '" + msg.camera +
                   "': the detections' intrinsics differ from the map's; the map's are used");
  }
  if (!msg.dictionary.empty() && !rig_.markers.dictionary.empty() &&
      msg.dictionary != rig_.markers.dictionary)
    WarnOnce("dict:" + msg.camera, "camera '" + msg.camera + "' detects in '" + msg.dictionary +
                                       "', the rig uses '" + rig_.markers.dictionary + "'");
  // The camera's clock against the map's reference camera (map.yaml time_offset_us and time_drift_ppm,
  // issue 18): frames are assembled by true capture time, utime - offset - drift * (utime - reference).
  msg.utime = estimator_->map().ReferenceUtime(msg.camera, msg.utime);
  if (measuring_window_) {
    held_.emplace_back(std::move(msg), arrival_wall);
    // Enough to measure: every camera of the map in kMeasureFrames messages, or kMeasureSpanUs of capture
    // time (a camera that never reports does not hold the others).
    constexpr size_t kMeasureFrames = 12;
    constexpr int64_t kMeasureSpanUs = 5000000;
    std::map<std::string, size_t> count;
    int64_t first = INT64_MAX, last = INT64_MIN;
    for (const auto& [held, arrival] : held_) {
      count[held.camera]++;
      first = std::min(first, held.utime);
      last = std::max(last, held.utime);
    }
    bool every = true;
    for (const std::string& c : sync_options_.cameras) every = every && count[c] >= kMeasureFrames;
    if (every || last - first >= kMeasureSpanUs) ChooseWindowAndReplay();
    return;
  }
  AssembleDetections(msg, arrival_wall);
}

SyncWindowChoice ChooseSyncWindow(const std::map<std::string, std::vector<int64_t>>& capture_utimes,
                                  double tolerance_ms) {
  SyncWindowChoice out;
  out.tolerance_ms = tolerance_ms;
  std::map<std::string, std::vector<int64_t>> times;
  for (const auto& [camera, utimes] : capture_utimes) {
    std::vector<int64_t> t = utimes;
    std::sort(t.begin(), t.end());
    t.erase(std::unique(t.begin(), t.end()), t.end());
    if (t.size() >= 2) times[camera] = std::move(t);
  }
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(1);
  for (const auto& [camera, t] : times) {
    std::vector<double> steps;
    for (size_t i = 1; i < t.size(); ++i) steps.push_back(1e-3 * static_cast<double>(t[i] - t[i - 1]));
    const double interval = Percentile(steps, 0.5);
    out.slowest_interval_ms = std::max(out.slowest_interval_ms, interval);
    s << (s.tellp() > 0 ? ", " : "frame intervals ") << camera << " " << interval << " ms";
  }
  std::string worst;
  for (auto a = times.begin(); a != times.end(); ++a)
    for (auto b = std::next(a); b != times.end(); ++b) {
      std::vector<double> distance;  // from each of a's times to the nearest of b's
      for (const int64_t t : a->second) {
        const auto it = std::lower_bound(b->second.begin(), b->second.end(), t);
        int64_t d = INT64_MAX;
        if (it != b->second.end()) d = *it - t;
        if (it != b->second.begin()) d = std::min(d, t - *std::prev(it));
        distance.push_back(1e-3 * static_cast<double>(d));
      }
      const double phase = Percentile(distance, 0.5);
      if (phase > out.spread_ms) {
        out.spread_ms = phase;
        worst = a->first + " and " + b->first;
      }
    }
  if (times.size() < 2) {
    s << (s.tellp() > 0 ? "; " : "") << "fewer than two cameras with frames: window " << tolerance_ms
      << " ms kept";
  } else if (out.spread_ms <= tolerance_ms) {
    s << "; phases within " << out.spread_ms << " ms: triggered together, window " << tolerance_ms
      << " ms kept";
  } else {
    out.widened = true;
    out.tolerance_ms = std::max(tolerance_ms, std::min(0.5 * out.slowest_interval_ms, kMaxAutoSyncWindowMs));
    s << "; views of one instant up to " << out.spread_ms << " ms apart (" << worst
      << "): not triggered together, window " << out.tolerance_ms
      << " ms (half the slowest camera's frame interval, at most " << kMaxAutoSyncWindowMs
      << " ms), each view moved to its capture time along the body's velocity";
    if (out.spread_ms > out.tolerance_ms)
      s << "; the phase exceeds the window: those cameras' views stay in frames of their own";
  }
  out.reason = s.str();
  return out;
}

void TrackerNode::ChooseWindowAndReplay() {
  measuring_window_ = false;
  std::map<std::string, std::vector<int64_t>> capture;
  for (const auto& [msg, arrival] : held_) capture[msg.camera].push_back(msg.utime);
  const SyncWindowChoice choice = ChooseSyncWindow(capture, options_.tracker.sync_tolerance_ms);
  if (choice.widened) {
    options_.tracker.sync_tolerance_ms = choice.tolerance_ms;  // health's messages name the window used
    sync_options_.tolerance_us = static_cast<int64_t>(choice.tolerance_ms * 1000.0);
    sync_options_.deadline_us = std::max(sync_options_.deadline_us, sync_options_.tolerance_us);
    sync_ = std::make_unique<FrameSynchronizer>(sync_options_);
  }
  std::cerr << "mcmt-tracker: sync window " << FormatMs(options_.tracker.sync_tolerance_ms)
            << " ms (the map has clock offsets and tracker.sync_tolerance_ms is not set; over the first "
            << held_.size() << " messages: " << choice.reason << ")" << std::endl;
  std::vector<std::pair<detections_t, int64_t>> held = std::move(held_);
  held_.clear();
  for (const auto& [msg, arrival] : held) AssembleDetections(msg, arrival);
}

void TrackerNode::AssembleDetections(const detections_t& msg, int64_t arrival_wall) {
  std::vector<SyncedFrame> frames;
  const int64_t late_before = sync_->stats().out_of_order;
  frames = sync_->Add(msg, options_.log_mode ? msg.utime : arrival_wall);
  if (!sync_->clock_rejection().empty()) {  // a far-off utime: moves no clock
    stats_.clock_jumps++;
    WarnOnce("clock:" + msg.camera, sync_->clock_rejection() + " (further ones are counted)");
    return;
  }
  if (options_.log_mode) {
    // Deadlines in message time: deterministic whatever the reading speed.
    auto due = sync_->Poll(msg.utime);
    frames.insert(frames.end(), std::make_move_iterator(due.begin()), std::make_move_iterator(due.end()));
  }
  if (sync_->stats().out_of_order > late_before) {
    // A view of a frame already solved: this camera's messages come later than the frame deadline.
    late_views_[msg.camera]++;
    stats_.late_views++;
    WarnOnce("late:" + msg.camera,
             "views of camera '" + msg.camera + "' arrive after their frame was solved (deadline " +
                 FormatMs(options_.tracker.deadline_ms) + " ms, adaptive wait at most " +
                 FormatMs(options_.tracker.max_wait_ms) +
                 " ms) and are dropped; if this camera's messages lag the others (start offset, slow link), "
                 "raise tracker.max_wait_ms or --max-wait-ms");
  }
  ProcessFrames(std::move(frames), arrival_wall);
}

void TrackerNode::Poll() {
  if (options_.log_mode || !sync_ || measuring_window_)
    return;  // log mode: deadlines advance with the messages
  const int64_t now = NowUtime();
  ProcessFrames(sync_->Poll(now), now);
}

void TrackerNode::Flush() {
  if (measuring_window_) ChooseWindowAndReplay();  // a short session: measured over what came
  if (sync_) ProcessFrames(sync_->Flush(), NowUtime());
}

void TrackerNode::ProcessFrames(std::vector<SyncedFrame> frames, int64_t trigger_wall_us) {
  std::stable_sort(frames.begin(), frames.end(),
                   [](const SyncedFrame& a, const SyncedFrame& b) { return a.utime < b.utime; });
  for (const auto& f : frames) {
    const int64_t last_arrival = options_.log_mode ? trigger_wall_us : f.last_arrival_us;
    ProcessFrame(f, last_arrival);
  }
  if (!frames.empty()) CheckStaleCameras();
  MaybePrintStatus();
}

void TrackerNode::CheckStaleCameras() {
  const std::set<std::string> stale = sync_->StaleCameras();
  for (const auto& c : stale) {
    if (reported_stale_.insert(c).second)
      std::cerr << "mcmt-tracker: camera '" << c << "' stopped reporting; tracking goes on with the others"
                << std::endl;
  }
  for (auto it = reported_stale_.begin(); it != reported_stale_.end();) {
    if (!stale.count(*it)) {
      std::cerr << "mcmt-tracker: camera '" << *it << "' reports again" << std::endl;
      it = reported_stale_.erase(it);
    } else {
      ++it;
    }
  }
}

std::vector<PoseSolution> TrackerNode::SolveBodies(const std::vector<MarkerObservation>& obs, int64_t utime) {
  // Each body gets its own markers' observations (one body: all of them, unmapped ones counted).
  std::vector<std::vector<MarkerObservation>> mine(bodies_.size());
  if (bodies_.size() == 1) {
    mine[0] = obs;
  } else {
    for (const MarkerObservation& o : obs) {
      const auto it = body_of_marker_.find(o.id);
      if (it != body_of_marker_.end()) mine[it->second].push_back(o);
    }
  }
  std::vector<PoseSolution> out;
  FrameJudgement judged;
  for (size_t b = 0; b < bodies_.size(); ++b) {
    Body& body = bodies_[b];
    Rigid3 predicted;
    const Rigid3* prior = body.motion.Predict(utime, &predicted) ? &predicted : nullptr;
    // A view captured at another time than the frame's (within the sync tolerance; clocks corrected by
    // the map's offsets) sees the body moved to its capture time along the body's velocity.
    for (MarkerObservation& o : mine[b]) {
      Rigid3 motion;
      if (o.utime != utime && body.motion.Motion(utime, o.utime, &motion)) body.estimator->SeenAt(motion, &o);
    }
    if (health_)  // every body judges the cameras that see it; excluded cameras are left out of all
      out.push_back(SolveJudgingCameras(*body.estimator, mine[b], prior, &judged));
    else
      out.push_back(body.estimator->Solve(mine[b], prior));
    if (out.back().ok())
      body.motion.Update(utime, out.back().rig_from_object);
    else
      body.motion.Reset();
  }
  if (health_) UpdateHealth(judged, utime);
  return out;
}

namespace {

// The pose of body `of` in body `in`'s frame (tracker/relative.h) as a solution: a pose when both have
// one (ambiguous when either is), the cameras and markers of both.
PoseSolution RelativeSolution(const PoseSolution& of, const PoseSolution* in, const Rigid3& rig_from_static) {
  PoseSolution out;
  const bool in_ok = !in || in->ok();
  out.num_rejected = of.num_rejected + (in ? in->num_rejected : 0);
  if (!of.ok() || !in_ok) return out;
  const RelativePose rel =
      in ? ComposeRelative(of.rig_from_object, of.covariance, in->rig_from_object, in->covariance)
         : ComposeRelative(of.rig_from_object, of.covariance, rig_from_static, Matrix6d::Zero());
  out.status = of.status == PoseStatus::kAmbiguous || (in && in->status == PoseStatus::kAmbiguous)
                   ? PoseStatus::kAmbiguous
                   : PoseStatus::kTracking;
  out.rig_from_object = rel.in_from_of;
  out.covariance = rel.covariance;
  const int n_in = in ? in->num_observations : 0;
  out.num_observations = of.num_observations + n_in;
  const double ss = of.rms_px * of.rms_px * of.num_observations + (in ? in->rms_px * in->rms_px * n_in : 0.0);
  out.rms_px = out.num_observations > 0 ? std::sqrt(ss / out.num_observations) : 0.0;
  std::set<std::string> cameras(of.cameras.begin(), of.cameras.end());
  std::set<int> markers(of.markers.begin(), of.markers.end());
  if (in) {
    cameras.insert(in->cameras.begin(), in->cameras.end());
    markers.insert(in->markers.begin(), in->markers.end());
  }
  out.cameras.assign(cameras.begin(), cameras.end());
  out.markers.assign(markers.begin(), markers.end());
  return out;
}

}  // namespace

void TrackerNode::Emit(size_t stream, const SyncedFrame& frame, const PoseSolution& sol, double latency_ms) {
  PoseStream& st = streams_[stream];
  st.frames++;
  if (sol.ok()) st.tracked++;
  object_pose_t msg;
  msg.utime = frame.utime;
  msg.seq = frame.seq;
  msg.object = st.name;
  msg.rig_from_object = ToPose3d(sol.ok() ? sol.rig_from_object : Rigid3::Identity());
  for (int a = 0; a < 6; ++a)
    for (int b = 0; b < 6; ++b) msg.covariance[a][b] = sol.covariance(a, b);
  msg.rms_px = sol.rms_px;
  msg.cameras = sol.cameras;
  msg.num_cameras = static_cast<int32_t>(msg.cameras.size());
  msg.markers.assign(sol.markers.begin(), sol.markers.end());
  msg.num_markers = static_cast<int32_t>(msg.markers.size());
  msg.num_rejected = sol.num_rejected;
  msg.status = static_cast<int8_t>(sol.status);
  msg.latency_ms = latency_ms;
  // Kept (and on disk) before it is published: whatever a subscriber saw survives a crash.
  if (options_.keep_trajectory && sol.ok()) {
    TrajectoryRow row;
    row.utime = frame.utime;
    row.seq = frame.seq;
    row.rig_from_object = sol.rig_from_object;
    row.rms_px = sol.rms_px;
    row.cameras = static_cast<int>(sol.cameras.size());
    row.markers = static_cast<int>(sol.markers.size());
    row.quality = FromObjectPoseMsg(msg).quality;  // as mcmt-export computes it from the published pose
    st.trajectory.push_back(row);
    if (std::FILE* f = stream_partials_[stream].get()) {
      std::fprintf(f, "%s\n", TrajectoryCsvLine(row, false, true).c_str());
      std::fflush(f);
    }
  }
  if (output_) output_->publish(st.channel, &msg);
}

void TrackerNode::ProcessFrame(const SyncedFrame& frame, int64_t last_arrival_wall_us) {
  if (!estimator_) return;
  if (frame.utime <= last_published_utime_) return;  // never publish out of order
  const std::vector<PoseSolution> solutions = SolveBodies(ObservationsFromViews(frame.views), frame.utime);
  const PoseSolution& sol = solutions.front();  // the counts below are the first body's

  stats_.frames++;
  for (const PoseSolution& s : solutions) stats_.rejected += s.num_rejected;
  status_frames_++;
  if (sol.ok()) {
    stats_.tracked++;
    status_tracked_++;
    if (sol.status == PoseStatus::kAmbiguous) stats_.ambiguous++;
  } else {
    stats_.lost++;
  }
  const int64_t now = NowUtime();
  const double latency_ms = std::max<int64_t>(0, now - last_arrival_wall_us) / 1000.0;
  for (size_t b = 0; b < bodies_.size(); ++b) Emit(bodies_[b].stream, frame, solutions[b], latency_ms);
  for (const Relative& r : relatives_)
    Emit(r.stream, frame,
         RelativeSolution(solutions[r.of], r.in >= 0 ? &solutions[r.in] : nullptr, r.rig_from_in),
         latency_ms);
  if (latencies_ms_.size() >= (1u << 20))
    latencies_ms_.erase(latencies_ms_.begin(), latencies_ms_.begin() + (1u << 19));
  latencies_ms_.push_back(latency_ms);
  last_published_utime_ = frame.utime;
}

std::string TrackerNode::StatusLine() const {
  const int64_t now = NowUtime();
  const double dt = std::max(1e-6, (now - last_status_wall_us_) * 1e-6);
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(1);
  s << "mcmt-tracker: ";
  if (status_frames_ > 0) {  // since the last status line
    s << status_frames_ / dt << " frames/s";
    s.precision(3);
    s << ", latency p50 " << Percentile(latencies_ms_, 0.5) << " ms p99 " << Percentile(latencies_ms_, 0.99)
      << " ms";
    s.precision(1);
    s << ", tracked " << 100.0 * status_tracked_ / status_frames_ << " % of the last " << status_frames_
      << " frames";
  } else {
    s << "no frame";
  }
  s << " (total: " << stats_.frames << " frames, " << stats_.tracked
    << " tracked = " << (stats_.frames > 0 ? 100.0 * stats_.tracked / stats_.frames : 0.0) << " %, "
    << stats_.ambiguous << " ambiguous, " << stats_.lost << " lost, " << stats_.rejected
    << " outliers rejected)";
  if (streams_.size() > 1) {
    s << ", tracked per stream:";
    for (const PoseStream& st : streams_)
      s << " " << st.name << " " << (st.frames > 0 ? 100.0 * st.tracked / st.frames : 0.0) << " %";
  }
  if (!late_views_.empty()) {
    s << ", late views dropped:";
    for (const auto& kv : late_views_) s << " " << kv.first << " " << kv.second;
  }
  if (stats_.duplicates > 0) s << ", " << stats_.duplicates << " repeated messages dropped";
  if (stats_.invalid > 0) s << ", " << stats_.invalid << " invalid messages dropped";
  if (stats_.invalid_markers > 0) s << ", " << stats_.invalid_markers << " markers with bad corners dropped";
  if (stats_.clock_jumps > 0) s << ", " << stats_.clock_jumps << " messages with a far-off utime dropped";
  if (stats_.bad_messages > 0) s << ", " << stats_.bad_messages << " undecodable messages";
  if (!reported_stale_.empty()) {
    s << ", stale cameras:";
    for (const auto& c : reported_stale_) s << " " << c;
  }
  if (!estimator_) s << ", waiting for a map";
  return s.str();
}

void TrackerNode::MaybePrintStatus() {
  if (options_.quiet || options_.tracker.status_period_s <= 0) return;
  const int64_t now = NowUtime();
  if (now - last_status_wall_us_ < static_cast<int64_t>(options_.tracker.status_period_s * 1e6)) return;
  std::cerr << StatusLine() << std::endl;
  last_status_wall_us_ = now;
  latencies_ms_.clear();
  status_frames_ = status_tracked_ = 0;
}

LogReadReport TrackerNode::RunLog(const std::string& path, const StopToken& stop) {
  struct Item {
    int64_t utime = 0, seq = 0;
    int64_t capture = 0;  // utime on the reference clock (the map's offsets)
    std::string camera, channel;
    std::vector<uint8_t> bytes;
  };
  std::vector<Item> segment;  // detections since the last map event
  auto track_segment = [&] {
    // Capture time on the reference clock: the map's clock offsets applied (a camera whose images are
    // 122 ms older than its stamps joins the frames it was captured in, not a frame 122 ms later).
    for (Item& i : segment)
      i.capture = estimator_ ? estimator_->map().ReferenceUtime(i.camera, i.utime) : i.utime;
    std::sort(segment.begin(), segment.end(), [](const Item& a, const Item& b) {
      return CaptureOrderKey(a.capture, a.camera, a.seq, a.bytes) <
             CaptureOrderKey(b.capture, b.camera, b.seq, b.bytes);
    });
    for (const Item& item : segment) OnDetections(item.channel, item.bytes.data(), item.bytes.size());
    segment.clear();
  };
  const bool maps_from_log = waits_for_map_;
  const LogReadReport report = ForEachLogEvent(path, [&](const LogEvent& e) {
    if (IsDetectionsChannel(e.channel)) {
      Item item;
      item.channel = e.channel;
      item.bytes = e.data;
      detections_t msg;
      if (Decode(e.data.data(), e.data.size(), &msg)) {  // undecodable ones sort first (utime 0)
        item.utime = msg.utime;
        item.seq = msg.seq;
        item.camera = msg.camera;
      }
      segment.push_back(std::move(item));
    } else if (maps_from_log && e.channel == kMapChannel) {
      track_segment();
      OnMap(e.data.data(), e.data.size());
    }
    return !stop.stop_requested();
  });
  track_segment();
  Flush();
  for (const std::string& line : report.damage) std::cerr << "mcmt-tracker: warning: " << line << std::endl;
  if (!options_.quiet) std::cerr << StatusLine() << std::endl;
  return report;
}

void TrackerNode::Run(const StopToken& stop) {
  if (options_.log_mode) {
    while (!stop.stop_requested()) {
      if (lcm_.handle() < 0) break;  // end of the log
    }
  } else {
    while (!stop.stop_requested()) {
      const int r = lcm_.handleTimeout(2);
      if (r < 0) {
        if (stop.stop_requested()) break;
        throw std::runtime_error("LCM receive failed");
      }
      Poll();
      MaybePrintStatus();
    }
  }
  Flush();
  if (!options_.quiet) std::cerr << StatusLine() << std::endl;
}

}  // namespace mcmt
