// The tracker on the simulator's sessions: the one way the tracker's tests and the tracker benchmark make
// a rig, an object on a trajectory and every camera's detections (sim::SimulateSession, sim/session.cc),
// with the exact map and the true poses in the tracker's own frames (sim::MapFromGroundTruth: rig frame =
// cam0's, object frame = the first marker's). Rig files: sim::WriteSessionRig; logs: sim::WriteMessagesLog.
#pragma once

#include <cstdint>
#include <vector>

#include "core/config.h"
#include "core/files.h"
#include "core/se3.h"
#include "mcmt/detections_t.hpp"
#include "sim/sim.h"

namespace mcmt {
namespace test {

// The tracker tests' session: sim's rig (5 cameras on a 1 m circle, 0.5 m above the object's motion,
// 640x480, 60 deg; radtan distortion, intrinsics 2 % apart), the cube with one 4 cm marker per face (a 6 cm
// cube; face_columns / face_rows for more), `frames` frames at 30 fps turning about the vertical at
// about 45 deg/s, markers detected up to 75 deg from frontal, corner noise `noise_px`; `seed` seeds the rig's
// spread, the trajectory and the detections.
sim::SessionOptions TrackerSession(int frames = 150, uint64_t seed = 1, double noise_px = 0.1);

struct TrackerSim {
  sim::Session session;              // session.views[f]: frame f's messages, one per camera, camera order
  RigMap map;                        // the exact map (the truth in the tracker's frames)
  std::vector<TrajectoryRow> truth;  // per frame: seq, utime, the true rig_from_object in the map's frames

  // Every camera's detections (sim::SimulateDetections with corner noise noise_px, drawn from `seed`) of the
  // object at rig_from_object, given in the map's frames, at frame `seq` / `utime`.
  std::vector<detections_t> DetectAt(const Rigid3& rig_from_object, int64_t seq, int64_t utime,
                                     double noise_px, uint64_t seed) const;
};

// The session of `options` (sim::SimulateSession) with its map and truth in the tracker's frames.
TrackerSim SimulateTracking(const sim::SessionOptions& options);

}  // namespace test
}  // namespace mcmt
