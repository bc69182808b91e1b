// Several rigid bodies in one map (the rig's objects: list): every body's observations go through the
// stages of mapper/stages.h on their own (observations, hypotheses, marker graph, fitted views), the
// cameras are placed by one camera graph joining the views of all bodies (a camera that sees only the room
// is placed), each body gets its initial poses (one for a static body: the medoid of its per-frame poses),
// and one bundle adjustment refines everything: camera poses, every body's layout (its reference marker
// fixed), a pose per frame of each moving body and one pose per static body.
//
// The joint problem reuses the single-object bundle: its "markers" are all bodies' markers and its
// "frames" are pose slots, one per (moving body, frame) and one per static body.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "mapper/mapper.h"
#include "mapper/stages.h"

namespace mcmt {

// The bodies the mapper options carry (MapperOptions::bodies, from the rig's objects:).
std::vector<MapperBody> BodiesFromRig(const RigConfig& rig);

// The ids of body `b` among the ids seen in `messages` (explicit ids, or for `other` every seen id no
// body claims), sorted.
std::vector<int> BodyIds(const std::vector<MapperBody>& bodies, size_t b,
                         const std::vector<StoredMessage>& messages);

// What one pass of the method reads besides the messages (SolvePass in mapper/mapper.cc takes it too).
struct BodiesInputs {
  const std::vector<std::string>& camera_names;
  const std::vector<CameraModel>& models;
  const std::vector<std::string>& warnings;
  const std::function<void(const MapperProgress&)>& progress;
};

// The whole method for several bodies. Throws MapperError naming a body that is never seen or never
// connects to the cameras (with allow_partial it is left out with a warning).
MapResult SolveBodies(const std::vector<StoredMessage>& messages, const BodiesInputs& inputs,
                      const MapperOptions& options);

// objects: auto / ids: auto (mapper/bodies_auto.h): the bodies found among the ids no object claims, then
// SolveBodies on them; report.auto_bodies says what was found. Called by SolveBodies.
MapResult SolveAutoBodies(const std::vector<StoredMessage>& messages, const BodiesInputs& inputs,
                          const MapperOptions& options);

// The files a map's trajectories go to: "trajectory.csv, trajectory_initial.csv" for one object,
// "trajectory_<body>.csv, ..." (and their trajectory_initial_<body>.csv) for the moving bodies of several.
std::string TrajectoryFileNames(const RigMap& map);

// What the per-camera diagnostics (mapper/diagnostics.h) look at with several bodies: the first moving
// body alone (its map, its trajectory, the detections of its ids). `result` itself for one object.
MapResult DiagnosticsView(const MapResult& result);

}  // namespace mcmt
