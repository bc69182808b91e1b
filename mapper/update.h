// The offline update (`mcmt-mapper --config rig.yaml --map OLD/map.yaml --log new.lcmlog --out NEW/`):
// the stages of mapper/stages.h run from an old map instead of from scratch.
//
//   CollectObservations, EstimateHypotheses      as when mapping
//   LayoutFromMap                                the old map's marker layout (held fixed unless
//                                                --refine-layout; ids it lacks are left out)
//   FitViews, PlacementFromMap                   every camera at its old pose; rig cameras it lacks unplaced
//   CheckCameras                                 each camera's pose from the frames the others see
//                                                (mapper/epochs.h PoseAgainstOthers): moved when it differs
//                                                from the old pose by move_min_deg or move_min_mm (the most
//                                                moved first, then left out of the others' checks); added
//                                                cameras placed from the others the same way
//   InitialObjectPoses, MakeBundleProblem        with the cameras as checked
//   RefineWithRejection, FillMap                 only the moved and added cameras (and the object poses;
//                                                the markers with --refine-layout) vary
//
// A moved reference camera keeps the name: the map is re-expressed in the frame of its new pose.
#pragma once

#include <string>
#include <vector>

#include "mapper/stages.h"

namespace mcmt {

struct UpdateSettings {
  bool refine_layout = false;
  // Only these cameras may be found moved (mcmt-mapper --maintain: the camera the tracker suspects; a
  // check of every camera against the others can blame a neighbour of the moved one); empty: every camera.
  std::vector<std::string> only_cameras;
};

// The old map's layout over the observed markers (reference: the old reference marker, else the
// best-observed placed marker). Throws MapperError when no observed marker is in the old map.
MarkerLayout LayoutFromMap(const RigMap& old_map, const Observations& observations);

// Every camera of camera_names at its old pose (reference: the old reference camera); cameras the old map
// lacks unplaced. Throws MapperError when the old reference camera is not among camera_names.
CameraPlacement PlacementFromMap(const RigMap& old_map, const std::vector<std::string>& camera_names);

// Moves the cameras that moved (report->moved_cameras, seq -1; only those of only_cameras when it is not
// empty) and places the cameras the old map lacks that share frames with placed ones
// (report->added_cameras); the others stay where the old map has them. Returns, per camera, whether it is
// re-estimated.
std::vector<char> CheckCameras(const std::vector<ViewPose>& views, int num_frames,
                               const std::vector<std::string>& camera_names, const MapperOptions& options,
                               const std::vector<std::string>& only_cameras, CameraPlacement* cameras,
                               MapReport* report);

// The whole update on the mapper's messages.
MapResult SolveUpdate(const std::vector<StoredMessage>& messages,
                      const std::vector<std::string>& camera_names, const std::vector<CameraModel>& models,
                      const std::vector<std::string>& warnings, const MapperOptions& options,
                      const RigMap& old_map, const UpdateSettings& settings);

}  // namespace mcmt
