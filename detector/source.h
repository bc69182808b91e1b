// Frame sources of mcmt-detector: an image folder, a video file, or a live device, with capture times.
//
// - Image folder: every file OpenCV can read (png, jpg, jpeg, bmp, tif, tiff, pgm, ppm, pnm, webp, jp2,
//   exr, hdr), in natural order ("2.png" before "10.png"). When every file name holds a number (its last
//   group of digits) and the numbers are distinct, that number is the frame index; else the position.
// - Video file: any container OpenCV's FFmpeg backend decodes; frame index = position in the file.
// - Live: a V4L2 device index ("0") or path ("/dev/video0"), or a GStreamer pipeline (a string holding
//   '!', ending in appsink). utime = wall clock at capture; a device that stops delivering frames is
//   reopened every second with a warning.
//
// Times of recorded frames (utime, microseconds): all cameras with the same frame index get the same
// utime, start_utime + round(index * 1e6 / fps), unless a timestamps CSV gives per-frame times:
// - "frame_index,time_s" (header optional): utime = round(time_s * 1e6);
// - caliscope's "sync_index,cam_id[,frame_index],frame_time": frame k of camera c is the k-th row of
//   cam_id c in sync_index order. utime = round(1e6 * frame_time) of the earliest camera of the same
//   sync_index (caliscope_time = "sync", default: one shared time per synchronised frame, as the
//   detections_t contract says) or of the camera's own row (caliscope_time = "camera").
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>
#include <string>
#include <vector>

namespace mcmt {

// Default first utime of recordings (1e12 us), the same as mcmt-sim's, so that detectors started
// separately agree.
constexpr int64_t kDefaultStartUtime = 1000000000000LL;

struct SourceOptions {
  std::string source;           // folder, video file, device index/path or GStreamer pipeline
  std::string timestamps_path;  // optional CSV
  std::string camera;           // name (for messages; its trailing number is the caliscope cam_id
                                // when the source file name has none)
  double fps = 0.0;             // frames per second of recordings; 0: the video's own, else 30
  int64_t start_utime = kDefaultStartUtime;
  std::string caliscope_time = "sync";  // "sync" or "camera" (see above)
  bool loop = false;                    // recordings: start again at the end (seq and utime keep increasing)
  // Image size of the calibration (0: unchecked). After the first frame (which the caller checks), a frame
  // of another size is refused with a warning naming camera, frame and sizes, and counted in skipped().
  int width = 0, height = 0;
};

struct Frame {
  cv::Mat image;
  int64_t index = 0;  // frame index (seq): file number / position, + loops * (last index + 1)
  int64_t utime = 0;
};

// Per-frame times from a CSV (either layout above). Throws std::runtime_error naming the file and line.
class FrameTimes {
 public:
  FrameTimes() = default;
  // cam_id: the caliscope camera id to take (ignored for the frame_index,time_s layout).
  static FrameTimes Load(const std::string& path, int cam_id, const std::string& caliscope_time);
  bool empty() const { return utimes_.empty(); }
  // Time of frame `index`; beyond the table, extrapolated with the mean interval.
  int64_t Utime(int64_t index) const;
  size_t size() const { return utimes_.size(); }
  bool caliscope() const { return caliscope_; }

 private:
  std::map<int64_t, int64_t> utimes_;
  double interval_us_ = 0.0;
  bool caliscope_ = false;
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  // Opens the source; throws std::runtime_error ("camera cam0: ...: <file>") when it is missing or
  // unreadable.
  static std::unique_ptr<FrameSource> Open(const SourceOptions& options);

  // Next frame; false at the end of a recording (live sources return false only when stopped).
  // Unreadable frames, frames that do not decode in a video, and frames of another size than
  // options.width x height (after the first) are skipped, counted and warned about.
  virtual bool Read(Frame* frame) = 0;
  // Recordings: the utime of the frame Read returns next, INT64_MIN when not known beforehand (live
  // sources, videos) or at the end.
  virtual int64_t NextUtime() const { return INT64_MIN; }
  // Passes over the next frame, decoding no more than the format needs (an image folder reads no
  // file; a video decodes it, as its later frames need); false at the end.
  virtual bool Skip() {
    Frame frame;
    return Read(&frame);
  }
  virtual bool live() const = 0;
  virtual double fps() const = 0;  // recording's frame rate (live: the device's, 0 if unknown)
  virtual std::string description() const = 0;
  // Number of frames of a recording (-1 live/unknown).
  virtual int64_t size() const { return -1; }
  int64_t skipped() const { return skipped_; }
  // Live: asks a blocking reconnect loop to give up (e.g. from a signal handler flag).
  void RequestStop() { stop_ = true; }

 protected:
  // False (counted, warned) when a frame after the first is not width x height.
  bool SizeAccepted(const SourceOptions& options, const cv::Mat& image, int64_t index);
  int64_t skipped_ = 0;
  bool first_frame_seen_ = false;
  volatile bool stop_ = false;
};

// Image files of a folder in natural order (exposed for tests).
std::vector<std::string> ListImagesNaturalOrder(const std::string& folder);
// Natural-order comparison ("img2" < "img10").
bool NaturalLess(const std::string& a, const std::string& b);

}  // namespace mcmt
