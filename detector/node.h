// DetectorNode: one camera's frames -> detections_t on MCMT_DETECTIONS_<CAMERA> (the mcmt-detector
// process, with an injected lcm::LCM).
//
// Optional images on MCMT_IMAGE_<CAMERA> (off by default, rate-limited): the payload is a plain JPEG
// file (starts with FF D8), not an LCM type; right after the SOI marker a COM segment holds
// "mcmt-image camera=<name> seq=<seq> utime=<utime>" so that a recorded image can be matched with its
// detections. Any JPEG decoder reads it (cv::imdecode, a file written from the bytes).
#pragma once

#include <atomic>
#include <cstdint>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <string>

#include "core/config.h"
#include "core/stop.h"
#include "detector/detector.h"
#include "detector/source.h"
#include "mcmt/detections_t.hpp"

namespace mcmt {

struct DetectorNodeOptions {
  std::string camera;          // name in the rig YAML
  std::string source;          // overrides the camera's source when not empty
  std::string rate = "max";    // "max": as fast as possible; "realtime": at the recording's frame rate
  bool loop = false;           // recordings: start again at the end
  long long max_frames = -1;   // stop after this many frames (< 0: no limit)
  bool images = false;         // publish MCMT_IMAGE_<CAMERA> JPEGs
  double image_rate_hz = 2.0;  // at most this many images per second (message time)
  int image_quality = 80;      // JPEG quality
  double image_scale = 1.0;    // images downscaled by this factor (0 < s <= 1)
  long long start_utime = kDefaultStartUtime;  // utime of frame 0 of recordings without timestamps
  // realtime pacing: wall clock (us since the epoch) at which the first frame is published; later frames
  // follow at their utime offsets. Several detectors given the same value publish each frame together,
  // as synchronised cameras would. 0: publish the first frame as soon as it is ready.
  long long start_wall_utime = 0;
  double fps = 0.0;                     // recordings: frame rate (0: the video's own, image folders 30)
  std::string caliscope_time = "sync";  // see detector/source.h
  double status_period_s = 5.0;         // status line period (wall time); <= 0: none
  // realtime pacing: a frame already this late (ms past its due time) when the detector gets to it is
  // dropped undetected, as a live camera drops the frames a slow detector cannot take, so the messages
  // stay within this of the rig's pace however loaded the machine. 0: every frame, however late.
  double max_lag_ms = 0.0;
  bool quiet = false;  // no status lines

  // Reads the process settings of the rig YAML `detector:` section (fps, images, image_rate,
  // image_quality, image_scale, status_period_s, caliscope_time, max_lag_ms; declared in
  // detector/options.cc) over the defaults above. Throws OptionError naming the file and key.
  void LoadFromConfig(const RigConfig& rig);
};
// The process keys of the `detector:` section (DetectorOptionTable has the detector's).
const OptionTable<DetectorNodeOptions>& DetectorNodeOptionTable();

// The camera's detector and source, opened and checked (shared by DetectorNode and DetectRecording).
class CameraPipeline {
 public:
  // Throws std::runtime_error / ConfigError naming the camera and the file: unknown camera, missing or
  // unreadable source, unknown dictionary, bad detector settings.
  CameraPipeline(const RigConfig& rig, const DetectorNodeOptions& options);
  // Next frame's detections; false at the end. Throws when the frame size differs from the
  // intrinsics' (naming camera, intrinsics file and source). = Read + Detect.
  bool Next(detections_t* detections, cv::Mat* image = nullptr);
  // The next frame, size-checked, not detected yet (a paced node may drop it unseen); false at the end.
  bool Read(Frame* frame);
  // The next frame's utime when the source knows it beforehand (FrameSource::NextUtime), and passing
  // over it unread (FrameSource::Skip).
  int64_t NextUtime() const;
  bool Skip();
  // The frame's detections (and its image when `image` is given).
  void Detect(const Frame& frame, detections_t* detections, cv::Mat* image = nullptr);
  FrameSource& source() { return *source_; }
  MarkerDetector& detector() { return *detector_; }
  const CameraConfig& camera() const { return camera_; }

 private:
  CameraConfig camera_;
  std::string source_name_;
  std::string dictionary_name_;
  camera_model_t model_msg_;
  std::unique_ptr<FrameSource> source_;
  std::unique_ptr<MarkerDetector> detector_;
  bool size_checked_ = false;
  Frame pending_;
  bool has_pending_ = false;
  void CheckSize(const Frame& frame);
};

struct DetectorNodeStats {
  int64_t frames = 0;  // published
  int64_t markers = 0;
  int64_t images = 0;   // published JPEGs
  int64_t skipped = 0;  // unreadable frames
  int64_t late = 0;     // frames dropped undetected, later than max_lag_ms (realtime pacing)
  double detection_ms_total = 0.0;
};

class DetectorNode {
 public:
  DetectorNode(const RigConfig& rig, const DetectorNodeOptions& options, lcm::LCM& lcm);
  // Publishes until the recording ends (after publishing everything), max_frames, or `stop` becomes
  // true. Returns normally in all three cases; throws on fatal errors (frame size mismatch...).
  void Run(const StopToken& stop);
  const DetectorNodeStats& stats() const { return stats_; }
  std::string channel() const { return channel_; }

 private:
  void PublishImage(const cv::Mat& image, const detections_t& detections);
  void DropLate(int64_t utime);  // counts the frame, warns once
  DetectorNodeOptions options_;
  lcm::LCM& lcm_;
  CameraPipeline pipeline_;
  std::string channel_, image_channel_;
  DetectorNodeStats stats_;
  int64_t last_image_utime_ = INT64_MIN;
};

// JPEG bytes of an image with a COM segment holding `comment` after the SOI marker.
std::vector<uint8_t> EncodeJpegWithComment(const cv::Mat& image, int quality, const std::string& comment);

}  // namespace mcmt
