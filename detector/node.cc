#include "detector/node.h"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <thread>

#include "core/lcm_util.h"
#include "core/progress.h"

namespace mcmt {
namespace {

using Clock = std::chrono::steady_clock;

double MsSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// Realtime pacing of a recording: frame k is due at the start + (utime_k - utime_0). The start is the
// shared --start-wall-utime when given (in steady-clock terms; a detector ready only after it paces
// from it all the same: its first frames go out at once and it catches up, instead of lagging the other
// cameras by its start-up delay for the whole run), else when the first frame is read.
class RealtimePace {
 public:
  explicit RealtimePace(long long start_wall_utime) : start_wall_utime_(start_wall_utime) {}
  Clock::time_point Due(int64_t utime) {
    if (!started_) {
      started_ = true;
      first_utime_ = utime;
      start_ = Clock::now();
      if (start_wall_utime_ > 0) start_ += std::chrono::microseconds(start_wall_utime_ - NowUtime());
    }
    return start_ + std::chrono::microseconds(utime - first_utime_);
  }
  bool started() const { return started_; }
  // Sleeps until `due`; false when stopped first.
  static bool WaitUntil(Clock::time_point due, const StopToken& stop) {
    while (!stop.stop_requested() && Clock::now() < due)
      std::this_thread::sleep_for(
          std::min<Clock::duration>(due - Clock::now(), std::chrono::milliseconds(50)));
    return !stop.stop_requested();
  }

 private:
  long long start_wall_utime_;
  bool started_ = false;
  int64_t first_utime_ = 0;
  Clock::time_point start_;
};

// tone "auto" on a recording: a first pass over it until the estimate is made (from its first frames'
// markers, tone_frames at most), which `pipeline` then uses on every frame, the first ones too, so that a
// recording's detections are the same whichever process reads it (DetectRecording, mcmt-detector at any
// rate). Live sources estimate on the way, from the frames after the estimate.
void PrimeTone(const RigConfig& rig, DetectorNodeOptions options, CameraPipeline* pipeline) {
  if (pipeline->detector().options().tone != "auto" || pipeline->source().live()) return;
  options.loop = false;  // a recording too short for the estimate ends the pass
  CameraPipeline first(rig, options);
  detections_t d;
  while (first.detector().ToneEstimating() && first.Next(&d)) {
  }
  if (first.detector().tone().ok) pipeline->detector().UseTone(first.detector().tone());
}

}  // namespace

CameraPipeline::CameraPipeline(const RigConfig& rig, const DetectorNodeOptions& options) {
  const CameraConfig* cam = rig.FindCamera(options.camera);
  if (!cam) {
    std::string names;
    for (const auto& c : rig.cameras) names += (names.empty() ? "" : ", ") + c.name;
    throw std::runtime_error("camera '" + options.camera + "' is not in " + rig.path + " (cameras: " + names +
                             ")");
  }
  camera_ = *cam;
  DetectorOptions detector_options = DetectorOptions::FromConfig(rig);
  try {
    detector_ = std::make_unique<MarkerDetector>(rig.markers, detector_options);
  } catch (const std::exception& e) {
    throw std::runtime_error("camera " + camera_.name + ": " + rig.path +
                             ": markers.dictionary: " + e.what());
  }
  detector_->SetCamera(camera_.model);
  SourceOptions so;
  so.source = options.source.empty() ? camera_.source : options.source;
  if (!options.source.empty()) {
    // A relative --source is relative to the working directory.
    std::error_code ec;
    if (std::filesystem::exists(so.source, ec)) so.source = std::filesystem::absolute(so.source).string();
  }
  so.timestamps_path = camera_.timestamps_path;
  so.camera = camera_.name;
  so.fps = options.fps;
  so.start_utime = options.start_utime;
  so.caliscope_time = options.caliscope_time;
  so.width = camera_.model.width;  // every frame's size is checked (the first one below)
  so.height = camera_.model.height;
  so.loop = options.loop;
  source_name_ = so.source;
  source_ = FrameSource::Open(so);
  dictionary_name_ = rig.markers.dictionary;
  model_msg_ = ToCameraModelMsg(camera_.model);
  // Recordings: read the first frame now, so that a size mismatch fails before anything is published.
  if (!source_->live()) {
    if (source_->Read(&pending_)) {
      has_pending_ = true;
      CheckSize(pending_);
    }
  }
}

void CameraPipeline::CheckSize(const Frame& frame) {
  if (size_checked_) return;
  {
    if (frame.image.cols != camera_.model.width || frame.image.rows != camera_.model.height)
      throw std::runtime_error("camera " + camera_.name + ": intrinsics " + camera_.intrinsics_path +
                               " are for " + std::to_string(camera_.model.width) + "x" +
                               std::to_string(camera_.model.height) + " images but the frames of " +
                               source_name_ + " are " + std::to_string(frame.image.cols) + "x" +
                               std::to_string(frame.image.rows));
    size_checked_ = true;
  }
}

bool CameraPipeline::Next(detections_t* d, cv::Mat* image_out) {
  Frame frame;
  if (!Read(&frame)) return false;
  Detect(frame, d, image_out);
  return true;
}

bool CameraPipeline::Read(Frame* frame) {
  if (has_pending_) {
    *frame = pending_;
    pending_ = Frame();
    has_pending_ = false;
  } else if (!source_->Read(frame)) {
    return false;
  }
  CheckSize(*frame);
  return true;
}

int64_t CameraPipeline::NextUtime() const { return has_pending_ ? pending_.utime : source_->NextUtime(); }

bool CameraPipeline::Skip() {
  if (!has_pending_) return source_->Skip();
  pending_ = Frame();
  has_pending_ = false;
  return true;
}

void CameraPipeline::Detect(const Frame& frame, detections_t* d, cv::Mat* image_out) {
  const auto t0 = Clock::now();
  std::vector<marker_t> markers = detector_->Detect(frame.image);
  d->detection_ms = MsSince(t0);
  d->utime = frame.utime;
  d->seq = frame.index;
  d->camera = camera_.name;
  d->dictionary = dictionary_name_;
  d->camera_model = model_msg_;
  d->markers = std::move(markers);
  d->num_markers = static_cast<int32_t>(d->markers.size());
  if (image_out) *image_out = frame.image;
}

std::vector<detections_t> DetectRecording(const RigConfig& rig, const std::string& camera, int max_frames) {
  DetectorNodeOptions options;
  options.camera = camera;
  options.LoadFromConfig(rig);
  CameraPipeline pipeline(rig, options);
  if (pipeline.source().live())
    throw std::runtime_error("camera " + camera + ": DetectRecording needs a recorded source, not " +
                             pipeline.source().description());
  PrimeTone(rig, options, &pipeline);
  std::vector<detections_t> out;
  detections_t d;
  while ((max_frames < 0 || static_cast<int>(out.size()) < max_frames) && pipeline.Next(&d)) out.push_back(d);
  return out;
}

std::vector<uint8_t> EncodeJpegWithComment(const cv::Mat& image, int quality, const std::string& comment) {
  std::vector<uint8_t> jpeg;
  if (!cv::imencode(".jpg", image, jpeg, {cv::IMWRITE_JPEG_QUALITY, quality}))
    throw std::runtime_error("cannot encode JPEG");
  const std::string text = comment.substr(0, 60000);
  const size_t length = text.size() + 2;
  std::vector<uint8_t> out;
  out.reserve(jpeg.size() + length + 2);
  out.insert(out.end(), jpeg.begin(), jpeg.begin() + 2);  // SOI
  out.push_back(0xFF);
  out.push_back(0xFE);
  out.push_back(static_cast<uint8_t>(length >> 8));
  out.push_back(static_cast<uint8_t>(length & 0xFF));
  out.insert(out.end(), text.begin(), text.end());
  out.insert(out.end(), jpeg.begin() + 2, jpeg.end());
  return out;
}

DetectorNode::DetectorNode(const RigConfig& rig, const DetectorNodeOptions& options, lcm::LCM& lcm)
    : options_(options), lcm_(lcm), pipeline_(rig, options) {
  if (options_.rate != "max" && options_.rate != "realtime")
    throw std::runtime_error("--rate: expected max or realtime, got '" + options_.rate + "'");
  PrimeTone(rig, options_, &pipeline_);
  channel_ = DetectionsChannel(options_.camera);
  image_channel_ = ImageChannel(options_.camera);
}

void DetectorNode::PublishImage(const cv::Mat& image, const detections_t& d) {
  const int64_t min_gap = static_cast<int64_t>(1e6 / options_.image_rate_hz);
  if (last_image_utime_ != INT64_MIN && d.utime - last_image_utime_ < min_gap && d.utime >= last_image_utime_)
    return;
  last_image_utime_ = d.utime;
  cv::Mat scaled = image;
  if (options_.image_scale < 1.0)
    cv::resize(image, scaled, cv::Size(), options_.image_scale, options_.image_scale, cv::INTER_AREA);
  const std::string comment = "mcmt-image camera=" + options_.camera + " seq=" + std::to_string(d.seq) +
                              " utime=" + std::to_string(d.utime);
  const std::vector<uint8_t> jpeg = EncodeJpegWithComment(scaled, options_.image_quality, comment);
  lcm_.publish(image_channel_, jpeg.data(), static_cast<unsigned int>(jpeg.size()));
  ++stats_.images;
}

void DetectorNode::DropLate(int64_t utime) {
  if (stats_.late++ == 0)
    std::cerr << "mcmt-detector: camera " << options_.camera << ": the frame of utime " << utime
              << " is more than detector.max_lag_ms (" << options_.max_lag_ms
              << ") past its time at the recording's pace: dropped undetected, as a live camera drops what "
                 "a slow detector cannot take (this machine cannot keep up; further ones are counted as late "
                 "in the status lines)"
              << std::endl;
}

void DetectorNode::Run(const StopToken& stop) {
  FrameSource& source = pipeline_.source();
  if (!options_.quiet)
    std::cout << "camera " << options_.camera << ": " << source.description() << " -> " << channel_
              << (options_.images ? " (+ " + image_channel_ + ")" : "") << std::endl;
  const bool realtime = options_.rate == "realtime" && !source.live();
  RealtimePace pace(options_.start_wall_utime);
  auto status_start = Clock::now();
  int64_t status_frames = 0, status_markers = 0;
  double status_ms = 0, status_max_ms = 0;
  detections_t d;
  Frame frame;
  cv::Mat image;
  std::unique_ptr<Progress> progress;  // recordings: a bar on a terminal, a line every 5 s otherwise
  if (!options_.quiet && !source.live())
    progress = std::make_unique<Progress>("camera " + options_.camera, std::max<int64_t>(0, source.size()));
  while (!stop.stop_requested() && (options_.max_frames < 0 || stats_.frames < options_.max_frames)) {
    if (realtime && options_.max_lag_ms > 0 && pace.started()) {
      // Frames already too late are passed over unread where the source knows their times beforehand.
      int64_t next = pipeline_.NextUtime();
      while (next != INT64_MIN && MsSince(pace.Due(next)) > options_.max_lag_ms && pipeline_.Skip()) {
        DropLate(next);
        next = pipeline_.NextUtime();
      }
    }
    if (!pipeline_.Read(&frame)) break;
    Clock::time_point due;
    if (realtime) {
      due = pace.Due(frame.utime);
      if (options_.max_lag_ms > 0 && MsSince(due) > options_.max_lag_ms) {
        DropLate(frame.utime);
        continue;
      }
    }
    pipeline_.Detect(frame, &d, options_.images ? &image : nullptr);
    if (realtime && !RealtimePace::WaitUntil(due, stop)) break;
    const std::vector<uint8_t> bytes = Encode(d);
    lcm_.publish(channel_, bytes.data(), static_cast<unsigned int>(bytes.size()));
    if (options_.images) PublishImage(image, d);
    ++stats_.frames;
    if (progress) progress->Update(stats_.frames + stats_.late);
    stats_.markers += d.num_markers;
    stats_.detection_ms_total += d.detection_ms;
    ++status_frames;
    status_markers += d.num_markers;
    status_ms += d.detection_ms;
    status_max_ms = std::max(status_max_ms, d.detection_ms);
    const double elapsed = MsSince(status_start) / 1000.0;
    if (!options_.quiet && options_.status_period_s > 0 && elapsed >= options_.status_period_s) {
      char line[256];
      std::snprintf(line, sizeof(line),
                    "camera %s: %lld frames, %.1f fps, %.2f markers/frame, detection %.2f ms (max %.2f), "
                    "skipped %lld, late %lld",
                    options_.camera.c_str(), static_cast<long long>(stats_.frames), status_frames / elapsed,
                    static_cast<double>(status_markers) / status_frames, status_ms / status_frames,
                    status_max_ms, static_cast<long long>(source.skipped()),
                    static_cast<long long>(stats_.late));
      if (progress && progress->terminal()) std::cerr << "\r\033[K" << std::flush;  // the bar redraws after
      std::cout << line << std::endl;
      status_start = Clock::now();
      status_frames = status_markers = 0;
      status_ms = status_max_ms = 0;
    }
  }
  stats_.skipped = source.skipped();
  if (progress) progress->Finish();
  if (!options_.quiet) {
    const MarkerDetector& detector = pipeline_.detector();
    const long long dropped = detector.stats().dropped;
    const long long kept = detector.stats().refine_failures - dropped;
    std::string unrefined_text;
    if (kept > 0) unrefined_text += "; " + std::to_string(kept) + " with cornerSubPix corners";
    if (dropped > 0) unrefined_text += "; " + std::to_string(dropped) + " more dropped (no clean edge fit)";
    char line[320];
    std::snprintf(
        line, sizeof(line),
        "camera %s: done: %lld frames, %lld markers (%.2f/frame%s), mean detection %.2f ms, skipped "
        "%lld, late %lld%s",
        options_.camera.c_str(), static_cast<long long>(stats_.frames),
        static_cast<long long>(stats_.markers),
        stats_.frames ? static_cast<double>(stats_.markers) / stats_.frames : 0.0, unrefined_text.c_str(),
        stats_.frames ? stats_.detection_ms_total / stats_.frames : 0.0,
        static_cast<long long>(stats_.skipped), static_cast<long long>(stats_.late),
        stop.stop_requested() ? " (stopped)" : "");
    std::cout << line << std::endl;
    if (detector.options().tone == "auto")
      std::cout << "camera " << options_.camera << ": tone auto: " << detector.tone().Describe() << std::endl;
  }
}

}  // namespace mcmt
