#include "tests/support/mapper_sim.h"

#include <Eigen/Geometry>

namespace mcmt {
namespace test {

sim::SessionOptions MapperSession(int frames, uint64_t seed, double noise_px) {
  sim::SessionOptions o;
  o.rig.seed = seed;
  o.rig.intrinsics_spread = 0.02;
  o.object.seed = seed;
  o.trajectory.frames = frames;
  o.trajectory.seed = seed;
  o.detections.corner_noise_px = noise_px;
  return o;
}

sim::SceneBody RoomMarker(int id, double size, const std::vector<sim::SimFrame>& like) {
  sim::SimObject room;
  room.name = "room";
  Rigid3 rig_from_marker = Rigid3::Identity();
  rig_from_marker.linear() =
      Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), Eigen::Vector3d(0.2, 0.3, 1.0))
          .toRotationMatrix();
  rig_from_marker.translation() = Eigen::Vector3d(0.25, -0.1, -0.15);
  room.markers.push_back({id, size, rig_from_marker});
  room.radius = size;
  return sim::StaticBody("room", room, Rigid3::Identity(), like);
}

MapperOptions MapperOptionsFor(const sim::GroundTruth& truth, const std::vector<std::string>& cameras) {
  MapperOptions o;
  if (cameras.empty())
    for (const auto& c : truth.cameras) o.cameras.push_back(c.name);
  else
    o.cameras = cameras;
  o.sizes.default_size = truth.marker_size;
  for (const auto& [id, size] : truth.marker_sizes)
    if (size != truth.marker_size) o.sizes.overrides[id] = size;
  o.dictionary = truth.dictionary;
  return o;
}

MapResult MapMessages(const std::vector<detections_t>& messages, const MapperOptions& options) {
  Mapper mapper(options);
  for (const detections_t& d : messages) mapper.Add(d);
  return mapper.Solve();
}

std::vector<detections_t> Filter(const std::vector<detections_t>& messages,
                                 const std::function<bool(const detections_t&)>& keep) {
  std::vector<detections_t> out;
  for (const detections_t& d : messages)
    if (keep(d)) out.push_back(d);
  return out;
}

}  // namespace test
}  // namespace mcmt
