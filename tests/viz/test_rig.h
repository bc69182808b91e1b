// A known rig for the viewer tests and benchmarks, from sim/: cameras on a circle looking at a cube with
// markers on five faces moving in front of them, in the reference camera's frame as the mapper would give
// it. No GoogleTest dependency (the benchmark uses it too).
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "core/files.h"
#include "core/se3.h"
#include "sim/eval.h"
#include "sim/sim.h"

namespace mcmt::viz::testing {

struct TestRig {
  RigMap map;
  std::vector<TrajectoryRow> trajectory;
  Rigid3 world_from_rig = Rigid3::Identity();
};

// num_cameras cameras of sim::MakeRig on a circle of radius 2 m, 1.2 m high, looking at (0, 0, 0.1), the
// circle turned by 0.3 rad about the vertical; sim's cube of 0.09 m markers without its bottom marker (ids
// 0..4: top, +x, +y, -x, -y; DICT_4X4_50) on sim::MakeTrajectory for `frames` frames (0: none). The map and
// trajectory are the truth in the reference camera's and marker's frames (sim::MapFromGroundTruth), with
// made-up statistics.
inline TestRig MakeTestRig(int num_cameras = 4, int frames = 12, double camera_rms_step = 0.4) {
  sim::RigOptions ro;
  ro.num_cameras = num_cameras;
  ro.radius = 2.0;
  ro.camera_height = 1.2;
  ro.look_at_height = 0.1;
  ro.hfov_deg = 2 * std::atan(320.0 / 500.0) * 180 / M_PI;  // fx 500 px at 640 px
  sim::GroundTruth truth;
  truth.dictionary = "DICT_4X4_50";
  truth.cameras = sim::MakeRig(ro);
  Rigid3 world_from_circle = Rigid3::Identity();
  world_from_circle.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  for (sim::SimCamera& c : truth.cameras) c.rig_from_cam = world_from_circle * c.rig_from_cam;
  sim::ObjectOptions oo;
  oo.kind = sim::ObjectKind::kCube;
  oo.marker_size = 0.09;
  const std::vector<sim::SimMarker> cube = sim::MakeObject(oo).markers;  // +x, -x, +y, -y, +z, -z
  for (int k : {4, 0, 2, 1, 3}) {  // top first (the reference), then the sides; not the bottom
    truth.markers.push_back(cube[k]);
    truth.markers.back().id = static_cast<int>(truth.markers.size()) - 1;
  }
  if (frames > 0) {
    sim::TrajectoryOptions to;
    to.frames = frames;
    to.position_radius = 0.3;
    to.vertical_range = 0.05;
    to.look_at_height = 0.15;
    to.time_scale = std::max(1.0, 300.0 / frames);  // a 10 s motion whatever the number of frames
    truth.frames = sim::MakeTrajectory(to);
  }
  TestRig rig;
  rig.world_from_rig = truth.cameras[0].rig_from_cam;
  rig.map = sim::MapFromGroundTruth(truth, 0, 0, &rig.trajectory);
  for (size_t i = 0; i < rig.map.cameras.size(); ++i) {
    MapCamera& c = rig.map.cameras[i];
    c.rig_from_cam = Normalized(c.rig_from_cam);
    c.observations = 100;
    c.rms_px = 0.2 + camera_rms_step * i;
    c.max_px = 2 * c.rms_px;
  }
  for (MapMarker& m : rig.map.markers) {
    m.object_from_marker = Normalized(m.object_from_marker);
    m.observations = 50;
    m.rms_px = 0.1 + 0.3 * m.id;
    m.max_px = 2 * m.rms_px;
  }
  rig.map.rms_px = 0.5;
  rig.map.num_frames = frames;
  rig.map.num_observations = frames * 8;
  for (TrajectoryRow& row : rig.trajectory) {
    row.rig_from_object = Normalized(row.rig_from_object);
    row.rms_px = 0.4;
    row.cameras = num_cameras;
    row.markers = 3;
  }
  return rig;
}

// A map with several bodies (version 2) on the same cameras: "tool" (MakeTestRig's cube, ids 0-4, on its
// trajectory), "patient" (the same cube shape at 0.8 scale, ids 10-14, on a circle of 0.1 m around
// (0.5, 0, 0.2)) and
// the static "floor" (8 markers of 0.1 m, ids 20-27, facing up on a ring of radius 0.9 m at z = 0,
// around the others). trajectory: the tool's; bodies["patient"]: the patient's, same utimes.
struct BodiesTestRig {
  RigMap map;
  std::vector<TrajectoryRow> trajectory;
  std::map<std::string, std::vector<TrajectoryRow>> bodies;
  Rigid3 world_from_rig = Rigid3::Identity();
};

inline BodiesTestRig MakeBodiesTestRig(int frames = 24) {
  const TestRig base = MakeTestRig(4, frames);
  BodiesTestRig rig;
  rig.map = base.map;
  rig.world_from_rig = base.world_from_rig;
  const Rigid3 rig_from_world = Inverse(base.world_from_rig);
  MapObject tool;
  tool.name = "tool";
  tool.markers = base.map.markers;
  MapObject patient;
  patient.name = "patient";
  patient.reference_marker = 10;
  for (MapMarker m : base.map.markers) {
    m.id += 10;
    m.size *= 0.8;
    m.object_from_marker.translation() *= 0.8;
    patient.markers.push_back(m);
  }
  MapObject floor;
  floor.name = "floor";
  floor.is_static = true;
  floor.reference_marker = 20;
  for (int k = 0; k < 8; ++k) {
    const double a = 2.0 * M_PI * k / 8;
    MapMarker m;
    m.id = 20 + k;
    m.size = 0.1;
    m.object_from_marker.translation() = Eigen::Vector3d(0.9 * std::cos(a), 0.9 * std::sin(a), 0.0);
    m.object_from_marker.linear() = Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    m.rms_px = 0.3;
    floor.markers.push_back(m);
  }
  floor.rig_from_object = rig_from_world;  // the floor's frame is the world frame
  rig.map.objects = {tool, patient, floor};
  rig.map.version = kMapVersionBodies;
  rig.trajectory = base.trajectory;
  // The patient: on a small circle (0.1 m) beside the tool's path (centre x = 0.5 m, 0.2 m high), turning.
  for (size_t k = 0; k < base.trajectory.size(); ++k) {
    const double a = 2.0 * M_PI * static_cast<double>(k) / std::max(frames, 1) + M_PI;
    Rigid3 world_from_patient = Rigid3::Identity();
    world_from_patient.linear() = Eigen::AngleAxisd(0.6 * a, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    world_from_patient.translation() = Eigen::Vector3d(0.5 + 0.1 * std::cos(a), 0.1 * std::sin(a), 0.2);
    TrajectoryRow p = base.trajectory[k];
    p.rig_from_object = Normalized(rig_from_world * world_from_patient);
    rig.bodies["patient"].push_back(p);
  }
  return rig;
}

}  // namespace mcmt::viz::testing
