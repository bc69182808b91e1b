// The mapper in maintenance mode (mapper/maintain.h has the steps).
#include "mapper/maintain.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "core/lcm_util.h"
#include "core/math.h"
#include "mapper/stages.h"
#include "mcmt/camera_health_t.hpp"
#include "mcmt/object_pose_t.hpp"
#include "mcmt/tracker_status_t.hpp"

namespace mcmt {
namespace {

constexpr double kPi = 3.14159265358979323846;

}  // namespace

MaintainNode::MaintainNode(lcm::LCM& input, lcm::LCM* output, const RigConfig& rig,
                           const MapperOptions& options, const RigMap& map, MaintainNodeOptions node_options,
                           std::ostream& log)
    : input_(input),
      output_(output),
      rig_(rig),
      options_(options),
      node_options_(std::move(node_options)),
      log_(log),
      map_(map) {
  subscriptions_.push_back(input_.subscribe(kDetectionsChannelRegex, &MaintainNode::HandleDetections, this));
  subscriptions_.push_back(input_.subscribe(node_options_.pose_channel, &MaintainNode::HandlePose, this));
  subscriptions_.push_back(input_.subscribe(kTrackerStatusChannel, &MaintainNode::HandleStatus, this));
  for (lcm::Subscription* s : subscriptions_) s->setQueueCapacity(kSubscriptionQueueCapacity);
}

MaintainNode::~MaintainNode() {
  for (lcm::Subscription* s : subscriptions_) input_.unsubscribe(s);
}

void MaintainNode::HandleDetections(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  OnDetections(channel, rbuf->data, rbuf->data_size);
}
void MaintainNode::HandlePose(const lcm::ReceiveBuffer* rbuf, const std::string&) {
  OnPose(rbuf->data, rbuf->data_size);
}
void MaintainNode::HandleStatus(const lcm::ReceiveBuffer* rbuf, const std::string&) {
  OnTrackerStatus(rbuf->data, rbuf->data_size);
}

void MaintainNode::OnDetections(const std::string& channel, const void* data, size_t size) {
  detections_t msg;
  std::string error;
  if (!Decode(data, size, &msg, &error)) {
    if (warned_.insert("bad:" + channel).second)
      log_ << "warning: ignoring an undecodable message on " << channel << ": " << error << "\n";
    return;
  }
  if (const std::string problem = DetectionsProblem(msg, channel); !problem.empty()) {
    if (warned_.insert("problem:" + channel).second) log_ << "warning: " << problem << "; dropped\n";
    return;
  }
  if (!rig_.FindCamera(msg.camera)) {
    if (warned_.insert("rig:" + msg.camera).second)
      log_ << "warning: camera '" << msg.camera << "' on " << channel << " is not a camera of " << rig_.path
           << ": not added to the map\n";
    return;
  }
  DropInvalidMarkers(&msg);
  std::map<int64_t, detections_t>& mine = views_[msg.camera];
  // Kept by the time on the reference camera's clock, as the tracker's poses are stamped (the map's
  // clock offsets and drifts); the update puts the messages on the same clocks (mapper/update.cc).
  const int64_t utime = map_.ReferenceUtime(msg.camera, msg.utime);
  const bool has_markers = !msg.markers.empty();
  mine[utime] = std::move(msg);
  while (static_cast<int>(mine.size()) > node_options_.history_frames) mine.erase(mine.begin());
  const std::string& camera = mine[utime].camera;
  if (has_markers && !map_.FindCamera(camera) && !candidates_.count(camera)) {
    log_ << "maintain: camera '" << camera << "' publishes and is not in the map: collecting "
         << options_.maintain_added_frames << " frames to add it\n";
    Suspect(camera, true, utime);
  }
}

void MaintainNode::OnPose(const void* data, size_t size) {
  object_pose_t msg;
  if (!Decode(data, size, &msg)) return;
  if (msg.status != 0) return;  // tracking only (not lost, not ambiguous)
  PoseInfo info;
  info.cameras.insert(msg.cameras.begin(), msg.cameras.end());
  CountFrame(msg.utime, info);
  poses_[msg.utime] = std::move(info);
  while (static_cast<int>(poses_.size()) > node_options_.history_frames) poses_.erase(poses_.begin());
}

void MaintainNode::OnTrackerStatus(const void* data, size_t size) {
  tracker_status_t msg;
  if (!Decode(data, size, &msg)) return;
  if (msg.map_utime < map_utime_) return;  // judged under a map older than the one published last
  for (const camera_health_t& h : msg.cameras) {
    if (!map_.FindCamera(h.camera)) continue;
    if (h.state == camera_health_t::STATE_NOT_JUDGED) continue;  // nothing known of it yet
    const auto it = candidates_.find(h.camera);
    if (h.state == camera_health_t::STATE_OK) {
      if (it != candidates_.end() && !it->second.added) {
        log_ << "maintain: camera '" << h.camera << "' is ok again before it was re-estimated\n";
        candidates_.erase(it);
      }
      continue;
    }
    if (it != candidates_.end()) continue;
    log_ << "maintain: camera '" << h.camera << "' is "
         << (h.state == camera_health_t::STATE_SUSPECT ? "suspect" : "excluded") << " (rms "
         << Fixed(h.rms_px, 2) << " px, baseline " << Fixed(h.baseline_px, 2) << " px): collecting "
         << options_.maintain_frames << " frames seen by the others\n";
    Suspect(h.camera, false, h.since_utime);
  }
}

void MaintainNode::Suspect(const std::string& camera, bool added, int64_t since_utime) {
  Candidate& c = candidates_[camera];
  c.added = added;
  const auto settled = settled_until_.find(camera);  // a failed attempt: only newer frames
  c.since_utime = settled == settled_until_.end() ? since_utime : std::max(since_utime, settled->second + 1);
  for (const auto& [utime, pose] : poses_)  // the poses already received
    if (utime >= c.since_utime) CountFrame(utime, pose);
  Status(mapper_status_t::STATE_COLLECTING,
         "maintain: camera '" + camera + "' " + (added ? "is new" : "is suspect") + ": collecting frames");
}

const detections_t* MaintainNode::ViewAt(const std::string& camera, int64_t utime) const {
  const auto views = views_.find(camera);
  if (views == views_.end()) return nullptr;
  const int64_t tolerance = options_.sync_tolerance_us();
  const auto it = views->second.lower_bound(utime - tolerance);
  if (it == views->second.end() || it->first > utime + tolerance) return nullptr;
  return &it->second;
}

void MaintainNode::CountFrame(int64_t pose_utime, const PoseInfo& pose) {
  for (auto& [camera, c] : candidates_) {
    if (pose_utime < c.since_utime || pose.cameras.count(camera)) continue;
    const detections_t* view = ViewAt(camera, pose_utime);
    if (view && !view->markers.empty()) c.frames.insert(pose_utime);
  }
}

void MaintainNode::Step() {
  for (auto it = candidates_.begin(); it != candidates_.end();) {
    const int needed = it->second.added ? options_.maintain_added_frames : options_.maintain_frames;
    if (static_cast<int>(it->second.frames.size()) < needed) {
      ++it;
      continue;
    }
    const std::string camera = it->first;
    const Candidate candidate = it->second;
    it = candidates_.erase(it);
    Reestimate(camera, candidate);
    it = candidates_.begin();  // Reestimate may drop candidates
  }
}

void MaintainNode::Reestimate(const std::string& camera, const Candidate& candidate) {
  MaintainEvent event;
  event.camera = camera;
  event.added = candidate.added;
  event.since_utime = candidate.since_utime;
  event.frames = static_cast<int>(candidate.frames.size());
  event.solved_utime = *candidate.frames.rbegin();
  // The frames' detections of every camera but the other suspects (each is solved in its own turn).
  Mapper mapper(options_);
  mapper.SetBaseMap(map_, false, {camera});  // only this camera may move: the others are held
  for (const auto& [name, views] : views_) {
    if (name != camera && candidates_.count(name)) continue;
    for (int64_t utime : candidate.frames)
      if (const detections_t* d = ViewAt(name, utime)) mapper.Add(*d);
  }
  std::string problem;
  MapResult result;
  try {
    result = mapper.Solve();
  } catch (const std::exception& e) {
    problem = std::string("the update failed: ") + e.what();
  }
  const MapCamera* solved = problem.empty() ? result.map.FindCamera(camera) : nullptr;
  if (problem.empty()) {
    const MapReport& r = result.report;
    const bool moved = std::any_of(r.moved_cameras.begin(), r.moved_cameras.end(),
                                   [&](const MovedCamera& m) { return m.camera == camera; });
    const bool added =
        std::find(r.added_cameras.begin(), r.added_cameras.end(), camera) != r.added_cameras.end();
    if (!solved || (candidate.added ? !added : !moved)) {
      problem = candidate.added ? "it could not be placed from the others"
                                : "it has not moved beyond mapper.move_min_deg / move_min_mm";
    } else {
      std::vector<double> others;
      for (const MapCamera& c : result.map.cameras)
        if (c.name != camera && c.observations > 0) others.push_back(c.rms_px);
      const double limit = others.empty() ? 0.0 : options_.maintain_max_rms_ratio * Median(others);
      if (others.empty() || solved->rms_px > limit)
        problem = "its rms " + Fixed(solved->rms_px, 3) + " px exceeds " +
                  Fixed(options_.maintain_max_rms_ratio, 1) + " x the others' median (" + Fixed(limit, 3) +
                  " px)";
    }
    for (const MovedCamera& m : r.moved_cameras)
      if (m.camera == camera) {
        event.rotation_deg = m.rotation_deg;
        event.translation_mm = m.translation_mm;
      }
  }
  std::ostringstream line;
  line << "maintain: camera '" << camera << "' ";
  if (!problem.empty()) {
    line << (candidate.added ? "not added" : "not re-estimated") << " from " << event.frames
         << " frames: " << problem << "; the map is unchanged";
    event.message = line.str();
    log_ << event.message << "\n";
    Status(mapper_status_t::STATE_FAILED, event.message);
    events_.push_back(event);
    settled_until_[camera] = event.solved_utime;
    return;
  }
  if (candidate.added)
    line << "added";
  else
    line << "re-estimated (moved " << Fixed(event.rotation_deg, 3) << " deg, "
         << Fixed(event.translation_mm, 2) << " mm)";
  line << " from " << event.frames << " frames, rms " << Fixed(solved->rms_px, 3) << " px, solved in "
       << Fixed(result.report.total_seconds, 2) << " s";
  for (const MovedCamera& m : result.report.moved_cameras)
    if (m.camera != camera)
      line << "; camera '" << m.camera << "' re-estimated too (moved " << Fixed(m.rotation_deg, 3) << " deg, "
           << Fixed(m.translation_mm, 2) << " mm)";
  // The map's version: its utime, above every map before it.
  map_utime_ = std::max(NowUtime(), map_utime_ + 1);
  line << "; new map " << map_utime_ << " on " << kMapChannel;
  event.published = true;
  event.map_utime = map_utime_;
  event.message = line.str();
  Publish(result.map, event.message);
  events_.push_back(event);
  // Suspicions were judged under the old map: the trackers judge every camera afresh under the new one.
  for (auto it = candidates_.begin(); it != candidates_.end();)
    it = it->second.added && !map_.FindCamera(it->first) ? std::next(it) : candidates_.erase(it);
}

void MaintainNode::Publish(const RigMap& map, const std::string& message) {
  map_ = map;
  if (!node_options_.outdir.empty()) {
    std::filesystem::create_directories(node_options_.outdir);
    WriteMap((std::filesystem::path(node_options_.outdir) / "map.yaml").string(), map_);
  }
  if (output_) {
    const rig_map2_t msg = ToRigMap2Msg(map_, map_utime_);
    output_->publish(kMapChannel, &msg);
  }
  log_ << message << "\n";
  Status(mapper_status_t::STATE_DONE, message);
}

void MaintainNode::Status(int8_t state, const std::string& message) {
  if (!output_) return;
  mapper_status_t st{};
  st.utime = NowUtime();
  st.state = state;
  st.rms_px = map_.rms_px;
  st.cameras_connected = static_cast<int32_t>(map_.cameras.size());
  st.message = message;
  output_->publish(kMapperStatusChannel, &st);
}

void MaintainNode::Run(const StopToken& stop) {
  log_ << "maintain: keeping the map of " << map_.cameras.size() << " cameras true (detections, "
       << node_options_.pose_channel << ", " << kTrackerStatusChannel << ")" << std::endl;
  while (!stop.stop_requested()) {
    const int r = input_.handleTimeout(50);
    if (r < 0) {
      if (errno == EINTR || stop.stop_requested()) continue;
      throw std::runtime_error(std::string("LCM receive failed: ") + std::strerror(errno));
    }
    Step();
  }
}

}  // namespace mcmt
