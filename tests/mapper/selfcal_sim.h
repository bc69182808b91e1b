// Sessions for the self-calibration tests and benchmark: the simulator's detections (in-process, the
// same generator as `mcmt-sim --detections-only`) of the paper's rig, with the intrinsics the mapper is
// given perturbed (sim::PerturbedModel: the corners stay true, as mcmt-sim --intrinsics-error) and
// per-camera clocks (sim::ClockUtime: a camera's utime = its true capture time + offset + drift, as
// mcmt-sim --clock).
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
  double speed = 1.0;  // the trajectory's time scale (sim::TrajectoryOptions::time_scale)
  uint64_t seed = 11;
  sim::ObjectKind object = sim::ObjectKind::kBox;
  DistortionModel distortion = DistortionModel::kRadTan;
};

struct SelfCalRun {
  sim::GroundTruth truth;
  std::vector<detections_t> detections;
  double max_speed_m_s = 0;  // of the object's centre
};

using sim::IntrinsicsError;

// Detections of the session; clocks per camera name (utime = sim::ClockUtime of the capture time).
SelfCalRun SimulateSelfCal(const SelfCalSession& session,
                           const std::map<std::string, sim::CameraClock>& clocks = {});
// The detections with the camera's given model replaced by the perturbed one.
void PerturbIntrinsics(const std::string& camera, const IntrinsicsError& error, SelfCalRun* run);
// The detections with the camera's given model replaced by `model` (e.g. rough intrinsics from a file).
void GiveIntrinsics(const std::string& camera, const CameraModel& model, SelfCalRun* run);
MapperOptions SelfCalOptions(const sim::GroundTruth& truth);
MapResult MapDetections(const std::vector<detections_t>& detections, const MapperOptions& options);

}  // namespace testing
}  // namespace mcmt
