// caliscope's real sessions (../shared/data/caliscope) for tests: detections with each camera's own
// frame times.
#pragma once

#include <string>
#include <vector>

#include "core/config.h"
#include "detector/detector.h"

namespace mcmt {
namespace test {

// Every camera's detections of `rig`'s recordings, each with its own frame times (detector.caliscope_time:
// camera; the default "sync" gives one shared time per sync index), camera after camera. Detected once
// per test program: the first call's rig is the one used.
inline const std::vector<detections_t>& CaliscopeCameraTimeDetections(const RigConfig& rig) {
  static const std::vector<detections_t> all = [&] {
    RigConfig copy = rig;
    YAML::Node detector = copy.detector.node();
    detector["caliscope_time"] = "camera";
    std::vector<detections_t> out;
    for (const CameraConfig& c : copy.cameras) {
      std::vector<detections_t> d = DetectRecording(copy, c.name);
      out.insert(out.end(), d.begin(), d.end());
    }
    return out;
  }();
  return all;
}

}  // namespace test
}  // namespace mcmt
