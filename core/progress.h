// Progress of a long job (a replay, a recorded video, a long log, a rendering), on stderr by default.
// On a terminal: one line redrawn in place, "label [#####.....]  42 % 1234/2938 frames  118 frames/s
// ETA 0:14", at most 5 times a second. Not on a terminal (a file, a pipe, a CI log): a plain line
// "label: 42 % 1234/2938 frames, 118 frames/s, ETA 0:14" every `period_s` seconds. Finish() prints the
// final count, rate and elapsed time in both modes. With an unknown total (0) there is no bar and no ETA.
#pragma once

#include <chrono>
#include <cstdint>
#include <iosfwd>
#include <string>

namespace mcmt {

class Progress {
 public:
  enum class Mode { kAuto, kTerminal, kPlain };  // kAuto: kTerminal when `fd` is a terminal

  Progress(std::string label, int64_t total, std::string unit = "frames", Mode mode = Mode::kAuto,
           double period_s = 5.0, std::ostream* out = nullptr, int fd = 2);
  ~Progress();  // Finish() if not done yet
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  void Update(int64_t done);  // cheap when nothing is due
  void SetTotal(int64_t total) { total_ = total; }
  void Finish();
  bool terminal() const { return terminal_; }

  // The text of one report (no newline, no escape codes): for tests and for Update/Finish.
  static std::string Format(const std::string& label, int64_t done, int64_t total, const std::string& unit,
                            double elapsed_s, bool bar, bool final_line);

 private:
  std::string label_, unit_;
  int64_t total_, done_ = 0;
  bool terminal_;
  double period_s_;
  std::ostream& out_;
  std::chrono::steady_clock::time_point start_, last_;
  bool finished_ = false;
};

}  // namespace mcmt
