// Sessions for the self-calibration tests and benchmark: the simulator's detections (in-process, the
// same generator as `mcmt-sim --detections-only`) of the paper's rig, with the intrinsics the mapper is
// given perturbed (the corners stay true) and per-camera clock offsets (a camera's utime = its true
// capture time + offset).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "mapper/mapper.h"
#include "sim/eval.h"
#include "sim/sim.h"

namespace mcmt {
namespace testing {

struct SelfCalSession {
  int frames = 300;
  double fps = 30.0;
  double corner_noise_px = 0.2;
  double speed = 1.0;  // trajectory time scale: 2 moves twice as fast along the same path
  uint64_t seed = 11;
  sim::ObjectKind object = sim::ObjectKind::kBox;
  DistortionModel distortion = DistortionModel::kRadTan;
};

struct SelfCalRun {
  sim::GroundTruth truth;
  std::vector<detections_t> detections;
  double max_speed_m_s = 0;  // of the object's centre
};

// Perturbation of one camera's given intrinsics.
struct IntrinsicsError {
  double focal_rel = 0;  // fx, fy *= 1 + focal_rel
  double cx_px = 0, cy_px = 0;
  double k1 = 0;
};

// Detections of the session; offsets_us per camera name (utime = capture time + offset).
SelfCalRun SimulateSelfCal(const SelfCalSession& session,
                           const std::map<std::string, int64_t>& offsets_us = {});
// The detections with the camera's given model replaced by the perturbed one.
void PerturbIntrinsics(const std::string& camera, const IntrinsicsError& error, SelfCalRun* run);
// The detections with the camera's given model replaced by `model` (e.g. rough intrinsics from a file).
void GiveIntrinsics(const std::string& camera, const CameraModel& model, SelfCalRun* run);
MapperOptions SelfCalOptions(const sim::GroundTruth& truth);
MapResult MapDetections(const std::vector<detections_t>& detections, const MapperOptions& options);

}  // namespace testing
}  // namespace mcmt
