// A small, self-contained synthetic scene for the mapper's tests and benchmark: cameras on a circle
// looking at the centre, a rigid object with markers on its sides moving in front of them, detections
// with corner noise (and optionally false ids, dropped frames, duplicates), plus error measures after
// rigid alignment to the ground truth.
#pragma once

#include <random>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/files.h"
#include "core/se3.h"
#include "mapper/mapper.h"
#include "mcmt/detections_t.hpp"

namespace mcmt {
namespace testing {

struct SynthOptions {
  int cameras = 5;
  double radius = 1.0;
  double camera_height = 0.4;
  int frames = 100;
  double marker_size = 0.04;
  int markers_per_side = 1;  // object: a square prism with markers on its 4 sides (+ top when > 1)
  int sides = 4;             // 4: four_sided, 5: pentagon-like
  double side_half_width = 0.05;
  double noise_px = 0.1;
  double false_rate = 0.0;   // probability per camera frame of one false detection (random id, quad)
  int static_false_id = -1;  // >= 0: a marker fixed in the room (not on the object) with this id
  double drop_rate = 0.0;    // probability that a camera frame is not published
  double radtan_k1 = 0.0;    // distortion of every camera
  uint64_t seed = 1;
  int64_t frame_period_us = 33333;
  int64_t camera_jitter_us = 0;  // each camera's utime offset within a frame (< sync tolerance)
};

struct SynthScene {
  std::vector<std::string> names;
  std::vector<CameraModel> models;
  std::vector<Rigid3> rig_from_cam;  // ground truth (world frame)
  std::vector<int> ids;
  std::vector<Rigid3> object_from_marker;  // ground truth (body frame)
  std::vector<Rigid3> rig_from_object;     // per frame
  std::vector<int64_t> utimes;
  std::vector<detections_t> detections;  // in time order, cameras interleaved
  int false_detections = 0;
  std::vector<int> false_ids;
};

SynthScene MakeScene(const SynthOptions& options);

// Options for the mapper matching the scene (cameras, sizes).
MapperOptions SceneMapperOptions(const SynthScene& scene, double marker_size = 0.04);

struct MapErrors {
  double camera_position_m = 0;     // max over cameras, after rigid alignment of the camera centres
  double camera_rotation_deg = 0;   // max, after that alignment
  double configuration_m = 0;       // max marker corner error after rigid alignment of all corners
  double object_translation_m = 0;  // mean over frames, after the rig alignment
  double object_rotation_deg = 0;   // mean over frames
  double object_translation_max_m = 0;
  int cameras_compared = 0;
  int markers_compared = 0;
  int frames_compared = 0;
};

// Compares a map + trajectory (rows matched by utime) with the scene's ground truth.
MapErrors CompareToTruth(const SynthScene& scene, const RigMap& map,
                         const std::vector<TrajectoryRow>& trajectory, double marker_size = 0.04);

// Writes DIR/rig.yaml (+ camK.yml intrinsics) for the scene, `extra` appended; returns the rig path.
std::string WriteSceneRig(const std::string& dir, const SynthScene& scene, double marker_size = 0.04,
                          const std::string& extra = "");
// Writes the scene's detections as an LCM log (channels MCMT_DETECTIONS_<CAM>); with add_foreign, one
// message of another type on MCMT_DETECTIONS_CAM0. Returns false when the log cannot be written.
bool WriteSceneLog(const std::string& path, const SynthScene& scene, bool add_foreign = false);

}  // namespace testing
}  // namespace mcmt
