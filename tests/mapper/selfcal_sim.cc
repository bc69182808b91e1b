#include "tests/mapper/selfcal_sim.h"

#include <algorithm>
#include <random>

#include "core/lcm_util.h"
#include "tests/support/mapper_sim.h"

namespace mcmt {
namespace testing {
SelfCalRun SimulateSelfCal(const SelfCalSession& session,
                           const std::map<std::string, sim::CameraClock>& clocks) {
  SelfCalRun run;
  sim::RigOptions ro;
  ro.num_cameras = 5;
  ro.seed = session.seed;
  ro.distortion = session.distortion;
  sim::ObjectOptions oo;
  oo.kind = session.object;
  oo.seed = session.seed;
  sim::TrajectoryOptions to;
  to.frames = session.frames;
  to.fps = session.fps;
  to.seed = session.seed;
  to.time_scale = session.speed;
  run.truth.cameras = sim::MakeRig(ro);
  const sim::SimObject object = sim::MakeObject(oo);
  run.truth.object = sim::ObjectKindNames()[static_cast<int>(session.object)];
  run.truth.markers = object.markers;
  run.truth.marker_size = object.Sizes().default_size;
  for (const auto& m : object.markers) run.truth.marker_sizes[m.id] = m.size;
  run.truth.fps = session.fps;
  run.truth.frames = sim::MakeTrajectory(to);
  run.truth.clocks = clocks;
  run.max_speed_m_s = sim::TrajectoryMaxSpeed(to);
  sim::DetectionSimOptions dso;
  dso.corner_noise_px = session.corner_noise_px;
  for (size_t c = 0; c < run.truth.cameras.size(); ++c) {
    const sim::SimCamera& camera = run.truth.cameras[c];
    const auto clock = clocks.find(camera.name);
    std::mt19937_64 rng(session.seed * 100 + c);
    for (const sim::SimFrame& f : run.truth.frames) {
      detections_t d;
      if (!sim::SimulateDetections(camera, object, f, dso, rng, &d)) continue;
      // The camera captured at the frame's time; its clock reads that time as ClockUtime.
      if (clock != clocks.end()) d.utime = sim::ClockUtime(clock->second, f.utime);
      run.detections.push_back(d);
    }
  }
  std::stable_sort(run.detections.begin(), run.detections.end(),
                   [](const detections_t& a, const detections_t& b) { return a.utime < b.utime; });
  return run;
}

void PerturbIntrinsics(const std::string& camera, const IntrinsicsError& e, SelfCalRun* run) {
  for (detections_t& d : run->detections) {
    if (d.camera != camera) continue;
    d.camera_model = ToCameraModelMsg(sim::PerturbedModel(FromCameraModelMsg(d.camera_model), e));
  }
}

void GiveIntrinsics(const std::string& camera, const CameraModel& model, SelfCalRun* run) {
  for (detections_t& d : run->detections)
    if (d.camera == camera) d.camera_model = ToCameraModelMsg(model);
}

MapperOptions SelfCalOptions(const sim::GroundTruth& truth) { return test::MapperOptionsFor(truth); }

MapResult MapDetections(const std::vector<detections_t>& detections, const MapperOptions& options) {
  return test::MapMessages(detections, options);
}

}  // namespace testing
}  // namespace mcmt
