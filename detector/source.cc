#include "detector/source.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "core/detections_csv.h"

namespace mcmt {
namespace fs = std::filesystem;

namespace {

int64_t WallUtime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// The last group of digits of a string, -1 if none.
long long LastNumber(const std::string& s) {
  int end = static_cast<int>(s.size()) - 1;
  while (end >= 0 && !std::isdigit(static_cast<unsigned char>(s[end]))) --end;
  if (end < 0) return -1;
  int begin = end;
  while (begin > 0 && std::isdigit(static_cast<unsigned char>(s[begin - 1]))) --begin;
  const std::string digits = s.substr(begin, end - begin + 1);
  if (digits.size() > 17) return -1;
  return std::stoll(digits);
}

bool ParseDouble(const std::string& s, double* v) {
  try {
    size_t pos = 0;
    *v = std::stod(s, &pos);
    return pos == s.size() && std::isfinite(*v);
  } catch (...) {
    return false;
  }
}

class FolderSource : public FrameSource {
 public:
  FolderSource(const SourceOptions& o, const FrameTimes& times) : options_(o), times_(times) {
    files_ = ListImagesNaturalOrder(o.source);
    if (files_.empty())
      throw std::runtime_error("camera " + o.camera + ": no image files in folder " + o.source);
    std::set<long long> numbers;
    for (const auto& f : files_) {
      const long long n = LastNumber(fs::path(f).stem().string());
      if (n < 0) break;
      numbers.insert(n);
    }
    const bool numbered = numbers.size() == files_.size();
    for (size_t i = 0; i < files_.size(); ++i)
      indices_.push_back(numbered ? LastNumber(fs::path(files_[i]).stem().string())
                                  : static_cast<int64_t>(i));
    period_ = *std::max_element(indices_.begin(), indices_.end()) + 1;
    fps_ = o.fps > 0 ? o.fps : 30.0;
  }
  int64_t NextUtime() const override {
    if (next_ >= files_.size() && !options_.loop) return INT64_MIN;
    return next_ >= files_.size() ? UtimeOf(0, loops_ + 1) : UtimeOf(next_, loops_);
  }
  bool Skip() override {
    if (!Wrap()) return false;
    ++next_;
    return true;
  }
  bool Read(Frame* frame) override {
    while (true) {
      if (!Wrap()) return false;
      const size_t i = next_++;
      cv::Mat image = cv::imread(files_[i], cv::IMREAD_UNCHANGED);
      if (image.empty()) {
        ++skipped_;
        std::cerr << "warning: camera " << options_.camera << ": cannot read image " << files_[i]
                  << ", skipped" << std::endl;
        continue;
      }
      if (image.depth() != CV_8U) {
        double lo, hi;
        cv::minMaxLoc(image.reshape(1), &lo, &hi);
        image.convertTo(image, CV_8U, hi > 0 ? 255.0 / hi : 1.0);
      }
      if (!SizeAccepted(options_, image, indices_[i])) continue;
      frame->image = image;
      frame->index = indices_[i] + loops_ * period_;
      frame->utime = UtimeOf(i, loops_);
      return true;
    }
  }
  bool live() const override { return false; }
  double fps() const override { return fps_; }
  int64_t size() const override { return static_cast<int64_t>(files_.size()); }
  std::string description() const override {
    return "image folder " + options_.source + " (" + std::to_string(files_.size()) + " images)";
  }

 private:
  int64_t LoopSpanUs() const { return times_.Utime(period_) - times_.Utime(0); }
  // At the end: false, or back to the first file when looping.
  bool Wrap() {
    if (next_ < files_.size()) return true;
    if (!options_.loop) return false;
    next_ = 0;
    ++loops_;
    return true;
  }
  int64_t UtimeOf(size_t i, int64_t loops) const {
    return times_.empty() ? options_.start_utime + std::llround((indices_[i] + loops * period_) * 1e6 / fps_)
                          : times_.Utime(indices_[i]) + loops * LoopSpanUs();
  }
  SourceOptions options_;
  FrameTimes times_;
  std::vector<std::string> files_;
  std::vector<int64_t> indices_;
  int64_t period_ = 0;
  size_t next_ = 0;
  int64_t loops_ = 0;
  double fps_ = 30.0;
};

class VideoSource : public FrameSource {
 public:
  VideoSource(const SourceOptions& o, const FrameTimes& times) : options_(o), times_(times) {
    Open();
    const double container_fps = capture_.get(cv::CAP_PROP_FPS);
    fps_ = o.fps > 0 ? o.fps : (container_fps > 0 && container_fps < 1000 ? container_fps : 30.0);
    frames_ = static_cast<int64_t>(capture_.get(cv::CAP_PROP_FRAME_COUNT));
  }
  bool Read(Frame* frame) override {
    while (true) {
      cv::Mat image;
      bool ok = capture_.read(image);
      if ((!ok || image.empty()) && SkipDamagedFrame()) continue;
      if (!ok || image.empty()) {
        // End of the file (or a frame that does not decode at the very end).
        if (position_ < frames_ - 2 && !options_.loop)
          std::cerr << "warning: camera " << options_.camera << ": video " << options_.source
                    << " ends at frame " << position_ << " of the " << frames_ << " its container announces"
                    << std::endl;
        if (position_ == 0)
          throw std::runtime_error("camera " + options_.camera + ": no frame decodes in video " +
                                   options_.source);
        if (!options_.loop) return false;
        period_ = std::max(period_, position_);
        position_ = 0;
        ++loops_;
        Open();
        continue;
      }
      const int64_t index = position_++;
      failures_in_a_row_ = 0;
      if (!SizeAccepted(options_, image, index)) continue;
      frame->image = image;
      frame->index = index + loops_ * period_;
      frame->utime = times_.empty()
                         ? options_.start_utime + std::llround(frame->index * 1e6 / fps_)
                         : times_.Utime(index) + loops_ * (times_.Utime(period_) - times_.Utime(0));
      return true;
    }
  }
  bool live() const override { return false; }
  double fps() const override { return fps_; }
  int64_t size() const override { return frames_; }
  std::string description() const override {
    return "video " + options_.source + " (" + std::to_string(frames_) + " frames at " +
           std::to_string(fps_) + " fps)";
  }

 private:
  // A frame that does not decode before the end the container announces: skipped (counted, warned) and
  // the next one tried; false at the real end or after 10 failures in a row.
  bool SkipDamagedFrame() {
    if (frames_ <= 0 || position_ >= frames_ - 2 || ++failures_in_a_row_ > 10) return false;
    ++skipped_;
    std::cerr << "warning: camera " << options_.camera << ": frame " << position_ << " of video "
              << options_.source << " does not decode, skipped" << std::endl;
    ++position_;
    return true;
  }
  void Open() {
    capture_.release();
    if (!capture_.open(options_.source, cv::CAP_FFMPEG) || !capture_.isOpened())
      throw std::runtime_error("camera " + options_.camera + ": cannot decode video " + options_.source);
  }
  SourceOptions options_;
  FrameTimes times_;
  cv::VideoCapture capture_;
  double fps_ = 30.0;
  int64_t frames_ = -1;
  int64_t failures_in_a_row_ = 0;
  int64_t position_ = 0;
  int64_t period_ = 0;
  int64_t loops_ = 0;
};

class LiveSource : public FrameSource {
 public:
  explicit LiveSource(const SourceOptions& o) : options_(o) {
    if (!Open())
      throw std::runtime_error("camera " + options_.camera + ": cannot open live source " + options_.source);
  }
  bool Read(Frame* frame) override {
    while (!stop_) {
      cv::Mat image;
      if (capture_.isOpened() && capture_.read(image) && !image.empty()) {
        failures_ = 0;
        const int64_t index = index_++;
        if (!SizeAccepted(options_, image, index)) continue;
        frame->utime = WallUtime();
        frame->image = image;
        frame->index = index;
        return true;
      }
      ++failures_;
      if (failures_ == 1)
        std::cerr << "warning: camera " << options_.camera << ": live source " << options_.source
                  << " delivers no frames; retrying every second" << std::endl;
      for (int i = 0; i < 10 && !stop_; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(100));
      if (!stop_ && Open())
        std::cerr << "camera " << options_.camera << ": live source " << options_.source << " reopened"
                  << std::endl;
    }
    return false;
  }
  bool live() const override { return true; }
  double fps() const override {
    const double f = capture_.get(cv::CAP_PROP_FPS);
    return f > 0 && f < 1000 ? f : 0.0;
  }
  std::string description() const override { return "live source " + options_.source; }

 private:
  bool Open() {
    capture_.release();
    const std::string& s = options_.source;
    bool digits = !s.empty() && std::all_of(s.begin(), s.end(), [](char c) {
      return std::isdigit(static_cast<unsigned char>(c));
    });
    if (digits) return capture_.open(std::stoi(s), cv::CAP_V4L2) && capture_.isOpened();
    if (s.find('!') != std::string::npos) return capture_.open(s, cv::CAP_GSTREAMER) && capture_.isOpened();
    return capture_.open(s, cv::CAP_V4L2) && capture_.isOpened();
  }
  SourceOptions options_;
  cv::VideoCapture capture_;
  int64_t index_ = 0;
  int failures_ = 0;
};

}  // namespace

bool NaturalLess(const std::string& a, const std::string& b) {
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    const bool da = std::isdigit(static_cast<unsigned char>(a[i])),
               db = std::isdigit(static_cast<unsigned char>(b[j]));
    if (da && db) {
      size_t ie = i, je = j;
      while (ie < a.size() && std::isdigit(static_cast<unsigned char>(a[ie]))) ++ie;
      while (je < b.size() && std::isdigit(static_cast<unsigned char>(b[je]))) ++je;
      std::string na = a.substr(i, ie - i), nb = b.substr(j, je - j);
      na.erase(0, std::min(na.find_first_not_of('0'), na.size()));
      nb.erase(0, std::min(nb.find_first_not_of('0'), nb.size()));
      if (na.size() != nb.size()) return na.size() < nb.size();
      if (na != nb) return na < nb;
      i = ie, j = je;
    } else {
      if (a[i] != b[j]) return a[i] < b[j];
      ++i, ++j;
    }
  }
  if ((a.size() - i) != (b.size() - j)) return a.size() - i < b.size() - j;
  return a < b;
}

std::vector<std::string> ListImagesNaturalOrder(const std::string& folder) {
  static const std::set<std::string> kExtensions = {".png",  ".jpg", ".jpeg", ".bmp", ".tif",
                                                    ".tiff", ".pgm", ".ppm",  ".pnm", ".pbm",
                                                    ".webp", ".jp2", ".exr",  ".hdr"};
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(folder)) {
    if (!entry.is_regular_file()) continue;
    if (kExtensions.count(Lower(entry.path().extension().string())))
      names.push_back(entry.path().filename().string());
  }
  std::sort(names.begin(), names.end(), NaturalLess);
  for (auto& n : names) n = (fs::path(folder) / n).string();
  return names;
}

FrameTimes FrameTimes::Load(const std::string& path, int cam_id, const std::string& caliscope_time) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open timestamps file");
  std::string line;
  std::vector<std::vector<std::string>> rows;
  std::vector<int> line_numbers;
  std::vector<std::string> header;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.find_first_not_of(" \t\r") == std::string::npos || line[0] == '#') continue;
    auto cells = SplitCsv(line);
    double v;
    if (rows.empty() && header.empty() && !ParseDouble(cells[0], &v)) {
      header = cells;
      continue;
    }
    rows.push_back(cells);
    line_numbers.push_back(number);
  }
  FrameTimes t;
  auto fail = [&](int line_no, const std::string& what) {
    throw std::runtime_error(path + ":" + std::to_string(line_no) + ": " + what);
  };
  const bool caliscope = !header.empty() && header[0] == "sync_index";
  if (caliscope) {
    // sync_index,cam_id[,frame_index],frame_time
    const int time_col = static_cast<int>(header.size()) - 1;
    if (header.size() < 3 || header[1] != "cam_id" || header[time_col] != "frame_time")
      throw std::runtime_error(path + ": expected columns sync_index,cam_id[,frame_index],frame_time");
    std::map<long long, std::map<int, double>> by_sync;  // sync_index -> cam -> time
    for (size_t r = 0; r < rows.size(); ++r) {
      if (static_cast<int>(rows[r].size()) != time_col + 1)
        fail(line_numbers[r], "expected " + std::to_string(time_col + 1) + " columns");
      double sync, cam, time;
      if (!ParseDouble(rows[r][0], &sync) || !ParseDouble(rows[r][1], &cam) ||
          !ParseDouble(rows[r][time_col], &time))
        fail(line_numbers[r], "not a number");
      by_sync[static_cast<long long>(sync)][static_cast<int>(cam)] = time;
    }
    int64_t k = 0;
    for (const auto& [sync, cams] : by_sync) {
      auto it = cams.find(cam_id);
      if (it == cams.end()) continue;
      double time = it->second;
      if (caliscope_time == "sync") {
        for (const auto& [c, tm] : cams) time = std::min(time, tm);
      }
      t.utimes_[k++] = std::llround(time * 1e6);
    }
    if (t.utimes_.empty()) throw std::runtime_error(path + ": no rows for cam_id " + std::to_string(cam_id));
    t.caliscope_ = true;
  } else {
    for (size_t r = 0; r < rows.size(); ++r) {
      if (rows[r].size() != 2) fail(line_numbers[r], "expected frame_index,time_s");
      double index, time;
      if (!ParseDouble(rows[r][0], &index) || !ParseDouble(rows[r][1], &time))
        fail(line_numbers[r], "not a number");
      t.utimes_[static_cast<int64_t>(index)] = std::llround(time * 1e6);
    }
    if (t.utimes_.empty()) throw std::runtime_error(path + ": no rows");
  }
  if (t.utimes_.size() >= 2) {
    const auto first = *t.utimes_.begin(), last = *t.utimes_.rbegin();
    t.interval_us_ =
        static_cast<double>(last.second - first.second) / static_cast<double>(last.first - first.first);
  }
  if (!(t.interval_us_ > 0)) t.interval_us_ = 1e6 / 30.0;
  return t;
}

int64_t FrameTimes::Utime(int64_t index) const {
  auto it = utimes_.find(index);
  if (it != utimes_.end()) return it->second;
  // Nearest known frame below (or the first), extrapolated.
  auto up = utimes_.upper_bound(index);
  const auto& base = up == utimes_.begin() ? *up : *std::prev(up);
  return base.second + std::llround((index - base.first) * interval_us_);
}

bool FrameSource::SizeAccepted(const SourceOptions& options, const cv::Mat& image, int64_t index) {
  const bool first = !first_frame_seen_;
  first_frame_seen_ = true;
  if (first || options.width <= 0 || (image.cols == options.width && image.rows == options.height))
    return true;
  ++skipped_;
  std::cerr << "warning: camera " << options.camera << ": frame " << index << " of " << options.source
            << " is " << image.cols << "x" << image.rows << ", the calibration is for " << options.width
            << "x" << options.height << ": refused" << std::endl;
  return false;
}

std::unique_ptr<FrameSource> FrameSource::Open(const SourceOptions& o) {
  if (o.source.empty())
    throw std::runtime_error("camera " + o.camera + ": no source (set cameras[].source or --source)");
  if (o.caliscope_time != "sync" && o.caliscope_time != "camera")
    throw std::runtime_error("caliscope_time: expected sync or camera, got '" + o.caliscope_time + "'");
  std::error_code ec;
  const bool exists = fs::exists(o.source, ec);
  const bool digits = std::all_of(o.source.begin(), o.source.end(),
                                  [](char c) { return std::isdigit(static_cast<unsigned char>(c)); });
  const bool live = digits || o.source.rfind("/dev/", 0) == 0 || o.source.find('!') != std::string::npos;
  FrameTimes times;
  if (!o.timestamps_path.empty() && !live) {
    // caliscope camera id: the number in the video's name (cam_2.mp4), else in the camera's name.
    long long cam_id = LastNumber(fs::path(o.source).stem().string());
    if (cam_id < 0) cam_id = LastNumber(o.camera);
    try {
      times = FrameTimes::Load(o.timestamps_path, static_cast<int>(std::max(0LL, cam_id)), o.caliscope_time);
    } catch (const std::exception& e) {
      throw std::runtime_error("camera " + o.camera + ": " + e.what());
    }
  }
  if (live) return std::make_unique<LiveSource>(o);
  if (!exists) throw std::runtime_error("camera " + o.camera + ": source not found: " + o.source);
  if (fs::is_directory(o.source, ec)) return std::make_unique<FolderSource>(o, times);
  {
    std::ifstream probe(o.source, std::ios::binary);
    if (!probe) throw std::runtime_error("camera " + o.camera + ": cannot read source " + o.source);
  }
  return std::make_unique<VideoSource>(o, times);
}

}  // namespace mcmt
