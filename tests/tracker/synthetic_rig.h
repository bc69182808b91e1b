// A small self-contained synthetic rig for the tracker's tests and benchmark: cameras on a circle
// looking at the centre, a cube with one marker per face, a smooth trajectory, noisy detections.
// Ground truth in the tracker's own frames (rig = cam0, object = marker 0), so the map is exact.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/files.h"
#include "core/se3.h"
#include "mcmt/detections_t.hpp"

namespace mcmt {
namespace tracker_test {

struct SyntheticOptions {
  int cameras = 5;
  double radius = 1.0;        // camera circle, metres
  double height = 0.5;        // camera height above the centre
  double marker_size = 0.04;  // metres
  double cube_side = 0.06;    // metres
  int grid = 1;               // markers per face: grid columns x grid_rows rows (ids in order)
  int grid_rows = 0;          // 0: same as grid
  int frames = 150;
  double fps = 30.0;
  double noise_px = 0.1;   // Gaussian corner noise
  bool distortion = true;  // radtan on odd cameras
  uint64_t seed = 1;
};

struct SyntheticSession {
  RigMap map;                                    // the exact map (truth)
  std::vector<int64_t> utimes;                   // per frame
  std::vector<Rigid3> rig_from_object;           // truth per frame
  std::vector<std::vector<detections_t>> views;  // per frame, one per camera (possibly no marker)
};

SyntheticSession MakeSession(const SyntheticOptions& options);

// Detections of the object at rig_from_object in every camera (exact corners + noise).
std::vector<detections_t> Detect(const RigMap& map, const Rigid3& rig_from_object, int64_t utime, int64_t seq,
                                 double noise_px, std::mt19937_64* rng);

// Writes DIR/rig.yaml (+ DIR/camK.yml intrinsics) for the session's cameras; returns the rig path.
// extra_yaml is appended verbatim (e.g. a tracker: section).
std::string WriteRigFiles(const std::string& dir, const RigMap& map, const std::string& extra_yaml = "");
// Writes an LCM log of the session's detections (event timestamp = utime), cameras interleaved per frame.
void WriteLog(const std::string& path, const SyntheticSession& session, int kill_camera = -1,
              int kill_from_frame = 0);

// Translation (m) and rotation (rad) errors.
double TranslationError(const Rigid3& a, const Rigid3& b);
double RotationError(const Rigid3& a, const Rigid3& b);

std::string MakeTempDir(const std::string& name);

}  // namespace tracker_test
}  // namespace mcmt
