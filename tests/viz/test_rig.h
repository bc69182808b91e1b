// A known rig for the viewer tests and benchmarks: cameras on a circle looking at a cube with
// markers on five faces that moves along a circle, in the reference camera's frame as the mapper
// would give it. No GoogleTest dependency (the benchmark uses it too).
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "core/files.h"
#include "core/math.h"
#include "core/se3.h"

namespace mcmt::viz::testing {

inline CameraModel TestCameraModel() {
  CameraModel m;
  m.width = 640;
  m.height = 480;
  m.fx = m.fy = 500;
  m.cx = 319.5;
  m.cy = 239.5;
  return m;
}

struct TestRig {
  RigMap map;
  std::vector<TrajectoryRow> trajectory;
  Rigid3 world_from_rig = Rigid3::Identity();
};

// num_cameras cameras on a circle of radius 2 m, 1.2 m high, looking at the origin; a 0.12 m cube
// (markers 0.09 m, ids 0..4, DICT_4X4_50) moving on a circle of radius 0.3 m for `frames` frames.
inline TestRig MakeTestRig(int num_cameras = 4, int frames = 12, double camera_rms_step = 0.4) {
  TestRig rig;
  std::vector<Rigid3> world_from_cam;
  for (int i = 0; i < num_cameras; ++i) {
    const double a = 2.0 * M_PI * i / num_cameras + 0.3;
    world_from_cam.push_back(
        LookAt(Eigen::Vector3d(2.0 * std::cos(a), 2.0 * std::sin(a), 1.2), Eigen::Vector3d(0, 0, 0.1)));
  }
  const Rigid3 rig_from_world = Inverse(world_from_cam[0]);
  rig.world_from_rig = world_from_cam[0];
  rig.map.dictionary = "DICT_4X4_50";
  rig.map.reference_camera = "cam0";
  rig.map.reference_marker = 0;
  for (int i = 0; i < num_cameras; ++i) {
    MapCamera c;
    c.name = "cam" + std::to_string(i);
    c.model = TestCameraModel();
    c.rig_from_cam = Normalized(rig_from_world * world_from_cam[i]);
    c.observations = 100;
    c.rms_px = 0.2 + camera_rms_step * i;
    c.max_px = 2 * c.rms_px;
    rig.map.cameras.push_back(c);
  }
  // Cube faces: outward normals; a marker's x axis on the face, y = z x x.
  const double half = 0.06;
  const std::array<Eigen::Vector3d, 5> normals = {Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(1, 0, 0),
                                                  Eigen::Vector3d(0, 1, 0), Eigen::Vector3d(-1, 0, 0),
                                                  Eigen::Vector3d(0, -1, 0)};
  std::vector<Rigid3> cube_from_marker;
  for (const auto& n : normals) {
    Eigen::Vector3d x = std::abs(n.z()) > 0.5 ? Eigen::Vector3d(1, 0, 0) : Eigen::Vector3d(0, 0, 1).cross(n);
    x.normalize();
    const Eigen::Vector3d y = n.cross(x);
    Rigid3 t = Rigid3::Identity();
    t.linear().col(0) = x;
    t.linear().col(1) = y;
    t.linear().col(2) = n;
    t.translation() = half * n;
    cube_from_marker.push_back(t);
  }
  const Rigid3 object_from_cube = Inverse(cube_from_marker[0]);
  for (int id = 0; id < 5; ++id) {
    MapMarker m;
    m.id = id;
    m.size = 0.09;
    m.object_from_marker = Normalized(object_from_cube * cube_from_marker[id]);
    m.observations = 50;
    m.rms_px = 0.1 + 0.3 * id;
    m.max_px = 2 * m.rms_px;
    rig.map.markers.push_back(m);
  }
  rig.map.rms_px = 0.5;
  rig.map.num_frames = frames;
  rig.map.num_observations = frames * 8;
  for (int k = 0; k < frames; ++k) {
    const double a = 2.0 * M_PI * k / std::max(frames, 1);
    Rigid3 world_from_cube = Rigid3::Identity();
    world_from_cube.linear() = Eigen::AngleAxisd(0.6 * a, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    world_from_cube.translation() = Eigen::Vector3d(0.3 * std::cos(a), 0.3 * std::sin(a), 0.15);
    TrajectoryRow row;
    row.utime = 1000000 + 33333 * k;
    row.seq = k;
    row.rig_from_object = Normalized(rig_from_world * world_from_cube * Inverse(object_from_cube));
    row.rms_px = 0.4;
    row.cameras = num_cameras;
    row.markers = 3;
    rig.trajectory.push_back(row);
  }
  return rig;
}

// A map with several bodies (version 2) on the same cameras: "tool" (MakeTestRig's cube, ids 0-4, on its
// circle), "patient" (the same cube shape at 0.8 scale, ids 10-14, on a circle of 0.12 m, 0.45 m high) and
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
  // The patient: on a smaller circle (0.12 m) higher up (0.45 m), half a turn ahead, turning as the tool.
  for (size_t k = 0; k < base.trajectory.size(); ++k) {
    const double a = 2.0 * M_PI * static_cast<double>(k) / std::max(frames, 1) + M_PI;
    Rigid3 world_from_patient = Rigid3::Identity();
    world_from_patient.linear() = Eigen::AngleAxisd(0.6 * a, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    world_from_patient.translation() = Eigen::Vector3d(0.12 * std::cos(a), 0.12 * std::sin(a), 0.45);
    TrajectoryRow p = base.trajectory[k];
    p.rig_from_object = Normalized(rig_from_world * world_from_patient);
    rig.bodies["patient"].push_back(p);
  }
  return rig;
}

}  // namespace mcmt::viz::testing
