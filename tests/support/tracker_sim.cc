#include "tests/support/tracker_sim.h"

#include <random>

#include "sim/eval.h"

namespace mcmt {
namespace test {

sim::SessionOptions TrackerSession(int frames, uint64_t seed, double noise_px) {
  sim::SessionOptions o;
  o.rig.distortion = DistortionModel::kRadTan;
  o.rig.intrinsics_spread = 0.02;
  o.rig.seed = seed;
  o.object.kind = sim::ObjectKind::kCube;
  o.object.seed = seed;
  o.trajectory.frames = frames;
  o.trajectory.seed = seed;
  o.trajectory.turns = 0.125 * frames / o.trajectory.fps;  // 45 deg/s
  o.detections.corner_noise_px = noise_px;
  o.detections.max_view_angle_deg = 75.0;
  return o;
}

TrackerSim SimulateTracking(const sim::SessionOptions& options) {
  TrackerSim s;
  s.session = sim::SimulateSession(options);
  s.map = sim::MapFromGroundTruth(s.session.Truth(), 0, 0, &s.truth);
  return s;
}

std::vector<detections_t> TrackerSim::DetectAt(const Rigid3& rig_from_object, int64_t seq, int64_t utime,
                                               double noise_px, uint64_t seed) const {
  // The map's frames are cam0's and the first marker's (MapFromGroundTruth(truth, 0, 0)).
  const Rigid3 sim_rig_from_rig = session.cameras.at(0).rig_from_cam;
  const Rigid3 object_from_sim_object = Inverse(session.object().markers.at(0).object_from_marker);
  sim::SimFrame frame;
  frame.seq = seq;
  frame.utime = utime;
  frame.rig_from_object = sim_rig_from_rig * rig_from_object * object_from_sim_object;
  sim::DetectionSimOptions o;
  o.corner_noise_px = noise_px;
  o.dictionary = session.dictionary;
  std::mt19937_64 rng(seed);
  std::vector<detections_t> out;
  for (const sim::SimCamera& camera : session.cameras) {
    detections_t d;
    if (sim::SimulateDetections(camera, session.object(), frame, o, rng, &d)) out.push_back(d);
  }
  return out;
}

}  // namespace test
}  // namespace mcmt
