#include "mapper/node.h"

#include <unistd.h>

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
#include "mapper/out_folder.h"

namespace mcmt {

std::atomic<bool>& MapperNode::StopFlag() {
  static std::atomic<bool> flag{false};
  return flag;
}

MapperNode::MapperNode(lcm::LCM& input, lcm::LCM* output, Mapper& mapper, MapperNodeOptions options,
                       std::ostream& log)
    : input_(input), output_(output), mapper_(mapper), options_(std::move(options)), log_(log) {
  subscriptions_.push_back(input_.subscribe(kDetectionsChannelRegex, &MapperNode::OnDetections, this));
  if (!options_.from_log)
    subscriptions_.push_back(input_.subscribe(kMapperCommandChannel, &MapperNode::OnCommand, this));
  tty_ = (&log_ == &std::cerr) && isatty(STDERR_FILENO);
  CheckOutFolder(options_.outdir, options_.session, options_.force);  // before hours of collecting
}

MapperNode::~MapperNode() {
  for (lcm::Subscription* s : subscriptions_) input_.unsubscribe(s);
}

void MapperNode::OnDetections(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  detections_t msg;
  std::string error;
  if (!Decode(rbuf->data, rbuf->data_size, &msg, &error)) {
    ++bad_messages_;
    if (bad_by_channel_[channel]++ == 0)
      log_ << "warning: ignoring a message on " << channel << " that is not a detections_t: " << error
           << " (further ones on this channel are counted silently)\n";
    return;
  }
  if (first_utime_ == INT64_MIN) first_utime_ = msg.utime;
  last_utime_ = std::max(last_utime_, msg.utime);
  mapper_.Add(msg);
}

void MapperNode::OnCommand(const lcm::ReceiveBuffer*, const std::string&, const mapper_command_t* msg) {
  if (msg->command == "solve") {
    solve_requested_ = true;
  } else if (msg->command == "reset") {
    mapper_.Reset();
    first_utime_ = last_utime_ = INT64_MIN;
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
  const auto start = Clock::now();
  auto last_progress = start;
  std::string reason;
  std::unique_ptr<Progress> reading;  // a long log takes minutes: messages read and rate
  if (options_.from_log && &log_ == &std::cerr)
    reading = std::make_unique<Progress>("reading the log", 0, "messages");
  for (;;) {
    if (StopFlag().load()) {
      reason = "signal";
      break;
    }
    if (solve_requested_) {
      reason = "solve command";
      break;
    }
    if (options_.max_frames > 0 && mapper_.NumFramesApprox() >= options_.max_frames) {
      reason = std::to_string(options_.max_frames) + " frames";
      break;
    }
    if (options_.max_seconds > 0) {
      const double elapsed = options_.from_log
                                 ? (first_utime_ == INT64_MIN ? 0.0 : (last_utime_ - first_utime_) * 1e-6)
                                 : std::chrono::duration<double>(Clock::now() - start).count();
      if (elapsed >= options_.max_seconds) {
        reason = "time limit";
        break;
      }
    }
    if (options_.from_log) {
      if (input_.handle() != 0) {
        reason = "end of log";
        break;
      }
      if (reading) reading->Update(mapper_.NumMessages());
    } else {
      if (input_.handleTimeout(50) < 0) {
        // A signal (SIGINT/SIGTERM/SIGUSR1: solve) interrupts the wait: the loop's top decides.
        if (errno == EINTR || StopFlag().load()) continue;
        throw std::runtime_error(std::string("LCM receive failed: ") + std::strerror(errno));
      }
      const auto now = Clock::now();
      if (std::chrono::duration<double>(now - last_progress).count() >= options_.progress_period_s) {
        ShowProgress(false);
        last_progress = now;
      }
    }
  }
  if (reading) reading->Finish();
  if (!options_.from_log) ShowProgress(true);
  if (bad_messages_ > 0)
    log_ << "warning: ignored " << bad_messages_
         << " messages on detections channels that were not detections_t\n";
  return reason;
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
  MapResult result;
  try {
    result = mapper_.Solve();
  } catch (const std::exception& e) {
    if (tty_) log_ << "\n";
    PublishStatus(mapper_status_t::STATE_FAILED, e.what());
    mapper_.SetProgressCallback(nullptr);
    throw;
  }
  mapper_.SetProgressCallback(nullptr);
  if (tty_) log_ << "\r\033[K";
  const std::string verdicts = WriteMapOutputs(options_.outdir, result);
  RecordSession(options_.outdir, options_.session);
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
  if (r.duplicates > 0)
    log_ << "dropped " << r.duplicates << " duplicate detections (same id twice in one frame)\n";
  for (const std::string& w : r.warnings) log_ << "warning: " << w << "\n";
  log_ << "wrote " << (std::filesystem::path(options_.outdir) / "map.yaml").string()
       << ", trajectory.csv, report.json, map_initial.yaml, trajectory_initial.csv, residuals.csv\n"
       << verdicts;
  if (options_.publish && output_) {
    const rig_map_t msg = ToRigMapMsg(result.map, NowUtime());
    output_->publish(kMapChannel, &msg);
    PublishStatus(mapper_status_t::STATE_DONE, summary.str(), r.iterations, 0.0, r.final_rms_px);
  }
  return result;
}

}  // namespace mcmt
