// What a session tells its user that is not the truth (issue 18): wrong intrinsics in the written rig and
// camera clocks that are off and drift.
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <stdexcept>

#include "sim/sim.h"

namespace mcmt {
namespace sim {

namespace {

std::vector<std::string> SplitCommas(const std::string& text) {
  std::vector<std::string> parts;
  std::stringstream in(text);
  for (std::string part; std::getline(in, part, ',');) parts.push_back(part);
  return parts;
}

// A finite number with |value| <= limit, else `bad` is called.
template <typename Bad>
double Number(const std::string& text, double limit, const Bad& bad, const std::string& what) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end || !std::isfinite(v) || !(std::fabs(v) <= limit)) bad(what);
  return v;
}

}  // namespace

CameraModel PerturbedModel(const CameraModel& truth, const IntrinsicsError& e) {
  CameraModel m = truth;
  m.fx *= 1 + e.focal_rel;
  m.fy *= 1 + e.focal_rel;
  m.cx += e.cx_px;
  m.cy += e.cy_px;
  if (!m.distortion.empty()) m.distortion[0] += e.k1;
  return m;
}

std::pair<std::string, IntrinsicsError> ParseIntrinsicsError(const std::string& text) {
  const std::vector<std::string> parts = SplitCommas(text);
  auto bad = [&](const std::string& why) {
    throw std::invalid_argument(
        "--intrinsics-error: expected CAM,FOCAL_PCT,CX_PX,CY_PX[,K1] (e.g. cam1,3,8,-6,0.03), " + why +
        ": '" + text + "'");
  };
  if ((parts.size() != 4 && parts.size() != 5) || parts[0].empty()) bad("got");
  IntrinsicsError e;
  e.focal_rel = 0.01 * Number(parts[1], 50.0, bad, "FOCAL_PCT must be -50..50");
  e.cx_px = Number(parts[2], 1000.0, bad, "CX_PX must be -1000..1000");
  e.cy_px = Number(parts[3], 1000.0, bad, "CY_PX must be -1000..1000");
  if (parts.size() == 5) e.k1 = Number(parts[4], 1.0, bad, "K1 must be -1..1");
  return {parts[0], e};
}

std::pair<std::string, CameraClock> ParseCameraClock(const std::string& text) {
  const std::vector<std::string> parts = SplitCommas(text);
  auto bad = [&](const std::string& why) {
    throw std::invalid_argument(
        "--clock: expected CAM,OFFSET_MS[,DRIFT_PPM] (e.g. cam2,12 or cam2,-8,200), " + why + ": '" + text +
        "'");
  };
  if ((parts.size() != 2 && parts.size() != 3) || parts[0].empty()) bad("got");
  CameraClock c;
  c.offset_ms = Number(parts[1], 10000.0, bad, "OFFSET_MS must be -10000..10000");
  if (parts.size() == 3) c.drift_ppm = Number(parts[2], 10000.0, bad, "DRIFT_PPM must be -10000..10000");
  return {parts[0], c};
}

int64_t ClockUtime(const CameraClock& clock, int64_t utime) {
  const double since_start_us = static_cast<double>(utime - kStartUtime);
  return utime + std::llround(1e3 * clock.offset_ms + 1e-6 * clock.drift_ppm * since_start_us);
}

}  // namespace sim
}  // namespace mcmt
