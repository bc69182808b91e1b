#include "core/progress.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <iostream>

namespace mcmt {
namespace {

std::string Clock(double seconds) {
  const long s = std::lround(std::max(0.0, seconds));
  char text[32];
  if (s >= 3600)
    std::snprintf(text, sizeof(text), "%ld:%02ld:%02ld", s / 3600, (s / 60) % 60, s % 60);
  else
    std::snprintf(text, sizeof(text), "%ld:%02ld", s / 60, s % 60);
  return text;
}

}  // namespace

Progress::Progress(std::string label, int64_t total, std::string unit, Mode mode, double period_s,
                   std::ostream* out, int fd)
    : label_(std::move(label)),
      unit_(std::move(unit)),
      total_(total),
      terminal_(mode == Mode::kTerminal || (mode == Mode::kAuto && ::isatty(fd))),
      period_s_(terminal_ ? 0.2 : period_s),
      out_(out ? *out : std::cerr),
      start_(std::chrono::steady_clock::now()),
      last_(start_) {}

Progress::~Progress() { Finish(); }

std::string Progress::Format(const std::string& label, int64_t done, int64_t total, const std::string& unit,
                             double elapsed_s, bool bar, bool final_line) {
  const double rate = elapsed_s > 0 ? done / elapsed_s : 0.0;
  char rate_text[64];
  std::snprintf(rate_text, sizeof(rate_text), "%.1f %s/s", rate, unit.c_str());
  std::string s = label + (bar ? " " : ": ");
  if (total > 0) {
    const double fraction = std::min(1.0, static_cast<double>(done) / total);
    if (bar) {
      const int width = 24, filled = static_cast<int>(fraction * width);
      s += "[" + std::string(filled, '#') + std::string(width - filled, '.') + "] ";
    }
    char text[96];
    std::snprintf(text, sizeof(text), bar ? "%3.0f %% %lld/%lld %s" : "%.0f %% %lld/%lld %s", 100 * fraction,
                  static_cast<long long>(done), static_cast<long long>(total), unit.c_str());
    s += text;
  } else {
    s += std::to_string(done) + " " + unit;
  }
  s += (bar ? "  " : ", ") + std::string(rate_text);
  if (final_line) return s + (bar ? "  " : ", ") + "done in " + Clock(elapsed_s);
  if (total > 0 && rate > 0 && done < total) s += (bar ? "  ETA " : ", ETA ") + Clock((total - done) / rate);
  return s;
}

void Progress::Update(int64_t done) {
  done_ = done;
  if (finished_) return;
  const auto now = std::chrono::steady_clock::now();
  if (std::chrono::duration<double>(now - last_).count() < period_s_) return;
  last_ = now;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const std::string text = Format(label_, done_, total_, unit_, elapsed, terminal_, false);
  if (terminal_)
    out_ << "\r\033[K" << text << std::flush;
  else
    out_ << text << "\n" << std::flush;
}

void Progress::Finish() {
  if (finished_) return;
  finished_ = true;
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const std::string text = Format(label_, done_, total_, unit_, elapsed, terminal_, true);
  out_ << (terminal_ ? "\r\033[K" : "") << text << "\n" << std::flush;
}

}  // namespace mcmt
