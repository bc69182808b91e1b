#include "mapper/node.h"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "core/lcm_util.h"
#include "core/progress.h"
#include "mapper/bodies.h"
#include "mapper/out_folder.h"

namespace mcmt {

MapperNode::MapperNode(lcm::LCM& input, lcm::LCM* output, Mapper& mapper, MapperNodeOptions options,
                       std::ostream& log)
    : input_(input), output_(output), mapper_(mapper), options_(std::move(options)), log_(log) {
  subscriptions_.push_back(input_.subscribe(kDetectionsChannelRegex, &MapperNode::OnDetections, this));
  if (options_.log_path.empty())
    subscriptions_.push_back(input_.subscribe(kMapperCommandChannel, &MapperNode::OnCommand, this));
  for (lcm::Subscription* s : subscriptions_) s->setQueueCapacity(kSubscriptionQueueCapacity);
  tty_ = (&log_ == &std::cerr) && isatty(STDERR_FILENO);
  // Before hours of collecting: a bad path or another session's results must not lose this session.
  CheckOutputFolder(options_.outdir);
  CheckOutFolder(options_.outdir, options_.session, options_.force);
}

MapperNode::~MapperNode() {
  for (lcm::Subscription* s : subscriptions_) input_.unsubscribe(s);
}

void MapperNode::Warn(const std::string& key, const std::string& text) {
  if (warned_.insert(key).second) log_ << "warning: " << text << "\n";
}

bool MapperNode::Decode(const std::string& channel, const void* data, size_t size, detections_t* msg) {
  std::string error;
  if (mcmt::Decode(data, size, msg, &error)) return true;
  ++bad_messages_;
  if (bad_by_channel_[channel]++ == 0)
    log_ << "warning: ignoring a message on " << channel << " that is not a detections_t: " << error
         << " (further ones on this channel are counted silently)\n";
  return false;
}

bool MapperNode::Admit(detections_t* msg, const std::string& channel) {
  const std::string problem = DetectionsProblem(*msg, channel);
  if (!problem.empty()) {
    ++invalid_messages_;
    Warn("problem:" + channel + ":" + problem, problem + "; its messages are dropped");
    return false;
  }
  if (duplicates_.Repeated(*msg)) return false;
  std::vector<int> ids;
  if (const int n = DropInvalidMarkers(msg, &ids)) {
    invalid_markers_ += n;
    Warn("corners:" + msg->camera, "camera '" + msg->camera + "' on " + channel + ": marker " +
                                       std::to_string(ids.front()) + " (seq " + std::to_string(msg->seq) +
                                       ") has non-finite or absurd corners; such markers are dropped");
  }
  const auto rig_size = options_.rig_image_sizes.find(msg->camera);
  if (rig_size != options_.rig_image_sizes.end() &&
      rig_size->second != std::make_pair(msg->camera_model.width, msg->camera_model.height))
    Warn("size:" + msg->camera,
         "camera '" + msg->camera + "' on " + channel + ": detections of " +
             std::to_string(msg->camera_model.width) + "x" + std::to_string(msg->camera_model.height) +
             " images, but the rig's intrinsics are " + std::to_string(rig_size->second.first) + "x" +
             std::to_string(rig_size->second.second) +
             " (another calibration? the detections' own model is used)");
  auto first = first_model_.find(msg->camera);
  if (first == first_model_.end()) {
    first_model_.emplace(msg->camera, msg->camera_model);
  } else if (Encode(first->second) != Encode(msg->camera_model)) {
    Warn("model:" + msg->camera,
         "camera '" + msg->camera + "' on " + channel + ": its camera model changed mid-stream (seq " +
             std::to_string(msg->seq) + "); the mapper keeps the first one it received");
  }
  return true;
}

void MapperNode::AddChecked(const detections_t& msg) {
  if (first_utime_ == INT64_MIN) first_utime_ = msg.utime;
  first_utime_ = std::min(first_utime_, msg.utime);
  last_utime_ = std::max(last_utime_, msg.utime);
  mapper_.Add(msg);
}

void MapperNode::OnDetections(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  detections_t msg;
  if (!Decode(channel, rbuf->data, rbuf->data_size, &msg) || !Admit(&msg, channel)) return;
  AddChecked(msg);
  AppendEncodedEvent(collected_events_++, rbuf->recv_utime, channel, rbuf->data, rbuf->data_size,
                     &collected_);
}

std::string MapperNode::SaveCollected() const {
  const std::string name = "collected-" + std::to_string(NowUtime() / 1000000) + ".lcmlog";
  for (const std::string& dir : {options_.outdir, std::filesystem::temp_directory_path().string()}) {
    try {
      const std::string path = (std::filesystem::path(dir) / name).string();
      WriteFileAtomic(path, collected_);
      return path;
    } catch (const std::exception&) {
    }
  }
  return "";
}

std::string MapperNode::CollectFromLog() {
  struct Item {
    std::string channel;
    detections_t msg;
    std::vector<uint8_t> bytes;
  };
  std::vector<Item> items;
  std::unique_ptr<Progress> reading;  // a long log takes minutes: bytes read, rate and ETA
  if (&log_ == &std::cerr) {
    std::error_code ec;
    const auto size = std::filesystem::file_size(options_.log_path, ec);
    reading = std::make_unique<Progress>("reading the log", ec ? 0 : static_cast<int64_t>(size >> 10), "KiB");
  }
  log_report_ = ForEachLogEvent(options_.log_path, [&](const LogEvent& e) {
    if (reading) reading->Update(static_cast<int64_t>(e.offset >> 10));
    if (!IsDetectionsChannel(e.channel)) return true;
    Item item;
    item.channel = e.channel;
    item.bytes = e.data;
    if (Decode(e.channel, e.data.data(), e.data.size(), &item.msg)) items.push_back(std::move(item));
    return !options_.stop.stop_requested();
  });
  if (reading) reading->Finish();
  // Capture-time order (then camera, seq, bytes): the same result whatever the order of the events.
  std::sort(items.begin(), items.end(), [](const Item& a, const Item& b) {
    return CaptureOrderKey(a.msg.utime, a.msg.camera, a.msg.seq, a.bytes) <
           CaptureOrderKey(b.msg.utime, b.msg.camera, b.msg.seq, b.bytes);
  });
  std::string reason = "end of log";
  for (Item& item : items) {
    if (LimitReached(&reason, first_utime_ == INT64_MIN ? 0.0 : (last_utime_ - first_utime_) * 1e-6)) break;
    if (options_.stop.stop_requested()) {
      reason = "signal";
      break;
    }
    if (Admit(&item.msg, item.channel)) AddChecked(item.msg);
  }
  for (const std::string& line : log_report_.damage) log_ << "warning: " << line << "\n";
  return reason;
}

bool MapperNode::LimitReached(std::string* reason, double elapsed_s) const {
  if (options_.max_frames > 0 && mapper_.NumFramesApprox() >= options_.max_frames) {
    *reason = std::to_string(options_.max_frames) + " frames";
    return true;
  }
  if (options_.max_seconds > 0 && elapsed_s >= options_.max_seconds) {
    *reason = "time limit";
    return true;
  }
  return false;
}

void MapperNode::OnCommand(const lcm::ReceiveBuffer*, const std::string&, const mapper_command_t* msg) {
  if (msg->command == "solve") {
    solve_requested_ = true;
  } else if (msg->command == "reset") {
    mapper_.Reset();
    first_utime_ = last_utime_ = INT64_MIN;
    collected_.clear();
    collected_events_ = 0;
    log_ << "reset: collected detections dropped\n";
  } else {
    log_ << "warning: unknown mapper command '" << msg->command << "' (solve, reset)\n";
  }
}

void MapperNode::PublishStatus(int8_t state, const std::string& message, int iteration, double cost,
                               double rms) {
  if (!options_.publish || !output_) return;
  mapper_status_t st;
  st.utime = NowUtime();
  st.state = state;
  st.frames = mapper_.NumFramesApprox();
  st.observations = 0;
  st.cameras_seen = 0;
  st.cameras_connected = 0;
  std::set<int> ids;
  if (state == mapper_status_t::STATE_COLLECTING) {
    for (const CameraCollectStats& c : mapper_.CollectStats()) {
      st.observations += c.observations;
      st.cameras_seen += c.frames > 0;
      st.cameras_connected += c.connected;
      ids.insert(c.ids.begin(), c.ids.end());
    }
  }
  st.markers_seen = static_cast<int32_t>(ids.size());
  st.iteration = iteration;
  st.cost = cost;
  st.rms_px = rms;
  st.message = message;
  output_->publish(kMapperStatusChannel, &st);
}

void MapperNode::ShowProgress(bool final_line) {
  const std::vector<CameraCollectStats> stats = mapper_.CollectStats();
  std::ostringstream line;
  int observations = 0, connected = 0, seen = 0;
  std::set<int> ids;
  for (const CameraCollectStats& c : stats) {
    observations += c.observations;
    connected += c.connected;
    seen += c.frames > 0;
    ids.insert(c.ids.begin(), c.ids.end());
  }
  line << "collecting: " << mapper_.NumFramesApprox() << " frames, " << observations << " markers, "
       << ids.size() << " ids, " << connected << "/" << stats.size() << " cameras connected |";
  for (const CameraCollectStats& c : stats)
    line << " " << c.name << ": " << c.frames << "f " << c.observations << "m "
         << (c.connected ? "yes" : "no") << ";";
  const std::string text = line.str();
  if (tty_)
    log_ << "\r\033[K" << text << (final_line ? "\n" : "") << std::flush;
  else
    log_ << text << "\n";
  PublishStatus(mapper_status_t::STATE_COLLECTING, text);
}

std::string MapperNode::Collect() {
  using Clock = std::chrono::steady_clock;
  std::string reason;
  if (!options_.log_path.empty()) {
    reason = CollectFromLog();
  } else {
    const auto start = Clock::now();
    auto last_progress = start;
    for (;;) {
      if (options_.stop.stop_requested()) {
        reason = "signal";
        break;
      }
      if (solve_requested_) {
        reason = "solve command";
        break;
      }
      if (LimitReached(&reason, std::chrono::duration<double>(Clock::now() - start).count())) break;
      if (input_.handleTimeout(50) < 0) {
        // A signal (SIGINT/SIGTERM/SIGUSR1: solve) interrupts the wait: the loop's top decides.
        if (errno == EINTR || options_.stop.stop_requested()) continue;
        throw std::runtime_error(std::string("LCM receive failed: ") + std::strerror(errno));
      }
      const auto now = Clock::now();
      if (std::chrono::duration<double>(now - last_progress).count() >= options_.progress_period_s) {
        ShowProgress(false);
        last_progress = now;
      }
    }
    ShowProgress(true);
  }
  if (bad_messages_ > 0)
    log_ << "warning: ignored " << bad_messages_
         << " messages on detections channels that were not detections_t\n";
  if (invalid_messages_ > 0)
    log_ << "warning: dropped " << invalid_messages_ << " invalid detections messages\n";
  if (invalid_markers_ > 0)
    log_ << "warning: dropped " << invalid_markers_ << " markers with non-finite or absurd corners\n";
  if (duplicates_.count() > 0)
    log_ << "warning: dropped " << duplicates_.count()
         << " repeated detections messages (same camera, seq and utime), e.g. "
         << duplicates_.examples().front() << "\n";
  return reason;
}

// Solves and writes OUTDIR; on failure publishes STATE_FAILED and keeps what a live session collected.
MapResult MapperNode::SolveAndWrite(std::string* verdicts) {
  MapResult result;
  try {
    result = mapper_.Solve();
    result.report.duplicates += static_cast<int>(duplicates_.count());
    for (const std::string& e : duplicates_.examples())
      if (result.report.duplicate_examples.size() < 40)
        result.report.duplicate_examples.push_back("repeated message: " + e);
    mapper_.SetProgressCallback(nullptr);
    if (tty_) log_ << "\r\033[K";
    *verdicts = WriteMapOutputs(options_.outdir, result);
    RecordSession(options_.outdir, options_.session);
  } catch (const std::exception& e) {
    if (tty_) log_ << "\n";
    PublishStatus(mapper_status_t::STATE_FAILED, e.what());
    mapper_.SetProgressCallback(nullptr);
    if (collected_events_ > 0) {  // live: what was collected is not lost
      const std::string kept = SaveCollected();
      log_ << (kept.empty()
                   ? "could not keep the collected detections either\n"
                   : "kept the " + std::to_string(collected_events_) + " collected detections messages in " +
                         kept + " (map them with --log " + kept + ")\n");
    }
    throw;
  }
  return result;
}

MapResult MapperNode::SolveWriteAndPublish() {
  using Clock = std::chrono::steady_clock;
  auto last_status = Clock::now() - std::chrono::seconds(10);
  mapper_.SetProgressCallback([&](const MapperProgress& p) {
    const auto now = Clock::now();
    const bool refining = p.stage == MapperProgress::kRefining;
    if (refining && std::chrono::duration<double>(now - last_status).count() < 0.2) return;
    last_status = now;
    const int8_t state = refining ? mapper_status_t::STATE_REFINING : mapper_status_t::STATE_INITIALISING;
    PublishStatus(state, p.message, p.iteration, p.cost, p.rms_px);
    if (refining && p.max_iterations > 0) {
      const int width = 30;
      const int filled = std::min(width, p.iteration * width / p.max_iterations);
      std::ostringstream bar;
      bar << "[" << std::string(filled, '#') << std::string(width - filled, '.') << "] " << p.message;
      if (tty_) log_ << "\r\033[K" << bar.str() << std::flush;
    } else if (!refining) {
      if (tty_) log_ << "\r\033[K";
      log_ << p.message << (tty_ ? "" : "\n") << std::flush;
    }
  });
  std::string verdicts;
  MapResult result = SolveAndWrite(&verdicts);
  const MapReport& r = result.report;
  std::ostringstream summary;
  summary << std::fixed << std::setprecision(3) << "mapped " << result.map.cameras.size() << " cameras, "
          << result.map.markers.size() << " markers, " << result.map.num_frames << " frames, "
          << result.map.num_observations << " observations: rms " << r.initial_rms_px << " px -> "
          << r.final_rms_px << " px in " << r.iterations << " iterations, " << r.total_seconds
          << " s (reference camera " << result.map.reference_camera << ", marker "
          << result.map.reference_marker << ")";
  log_ << summary.str() << "\n";
  for (const RejectedMarker& m : r.rejected_markers)
    log_ << "rejected marker " << m.id << " (" << m.observations << " observations): " << m.reason << "\n";
  if (!r.rejected_observations.empty())
    log_ << "rejected " << r.rejected_observations.size() << " observations (see report.json)\n";
  if (r.duplicates > duplicates_.count())
    log_ << "dropped " << r.duplicates - duplicates_.count()
         << " duplicate detections (same id twice in one frame)\n";
  for (const std::string& w : r.warnings) log_ << "warning: " << w << "\n";
  log_ << "wrote " << (std::filesystem::path(options_.outdir) / "map.yaml").string() << ", "
       << TrajectoryFileNames(result.map) << ", report.json, map_initial.yaml, residuals.csv"
       << (r.auto_bodies.ran ? ", objects.yaml (the objects: section found)" : "") << "\n"
       << verdicts;
  for (const MapObject& o : result.map.objects)
    log_ << "object " << o.name << (o.is_static ? " (static)" : "") << ": " << o.markers.size()
         << " markers, " << (o.is_static ? "" : std::to_string(o.num_frames) + " frames, ")
         << o.num_observations << " observations, rms " << o.rms_px << " px\n";
  if (options_.publish && output_) {
    const rig_map2_t msg = ToRigMap2Msg(result.map, NowUtime());
    output_->publish(kMapChannel, &msg);
    PublishStatus(mapper_status_t::STATE_DONE, summary.str(), r.iterations, 0.0, r.final_rms_px);
  }
  return result;
}

}  // namespace mcmt
