#include "core/options.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace mcmt {

OptionError::OptionError(const std::string& file, const std::string& key, const std::string& problem)
    : ConfigError((file.empty() ? "" : file + ": ") + key + ": " + problem), file_(file), key_(key) {}

std::string FormatOptionNumber(double v) {
  char buf[64];
  if (v == std::floor(v) && std::fabs(v) < 1e15) {  // integers in full: 3000, not 3e+03
    std::snprintf(buf, sizeof(buf), "%.0f", v);
    return buf;
  }
  for (int precision = 1; precision <= 17; ++precision) {
    std::snprintf(buf, sizeof(buf), "%.*g", precision, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  return buf;
}

NumberCheck AtLeast(double lo) {
  return {"must be >= " + FormatOptionNumber(lo), [lo](const double& v) { return v >= lo; }};
}

NumberCheck Above(double lo) {
  return {"must be > " + FormatOptionNumber(lo), [lo](const double& v) { return v > lo; }};
}

NumberCheck InRange(double lo, double hi, bool open_lo, bool open_hi) {
  const std::string text = std::string("must be in ") + (open_lo ? "(" : "[") + FormatOptionNumber(lo) +
                           ", " + FormatOptionNumber(hi) + (open_hi ? ")" : "]");
  return {text, [=](const double& v) {
            return (open_lo ? v > lo : v >= lo) && (open_hi ? v < hi : v <= hi) && !std::isnan(v);
          }};
}

TextCheck OneOf(std::vector<std::string> values) {
  std::string text = "expected one of ";
  for (size_t i = 0; i < values.size(); ++i) text += (i ? ", " : "") + values[i];
  return {text, [values](const std::string& v) {
            for (const std::string& x : values)
              if (x == v) return true;
            return false;
          }};
}

TextCheck NotEmpty() {
  return {"must not be empty", [](const std::string& v) { return !v.empty(); }};
}

const OptionTable<SyncOptions>& SyncOptionTable() {
  using O = SyncOptions;
  static const OptionTable<O>* table =
      &(*new OptionTable<O>("sync"))
           .Add("tolerance_ms", &O::tolerance_ms, "ms", "detections this close in utime form one frame",
                AtLeast(0))
           .Add("deadline_ms", &O::deadline_ms, "ms",
                "tracker: solve a frame at the latest this long after its first detection", Above(0))
           .Add("camera_timeout_s", &O::camera_timeout_s, "s",
                "tracker: a camera silent this long is not waited for", Above(0));
  return *table;
}

SyncOptions LoadSyncOptions(const RigConfig& rig) {
  SyncOptions o;
  SyncOptionTable().Load(rig.sync, &o);
  return o;
}

const OptionTable<LcmOptions>& LcmOptionTable() {
  static const OptionTable<LcmOptions>* table =
      &(*new OptionTable<LcmOptions>("lcm"))
           .Add("url", &LcmOptions::url, "LCM URL of every process of the rig (empty: LCM's default)");
  return *table;
}

}  // namespace mcmt
