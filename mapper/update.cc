// The offline update: the mapper's stages run from an old map (mapper/update.h has the steps).
#include "mapper/update.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <thread>

#include "mapper/epochs.h"

namespace mcmt {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kMinCheckFrames = 10;  // frames shared with the others to check or place a camera

// The most moved camera among those neither excluded nor unchecked (-1: none beyond the thresholds), at
// *pose; the excluded ones are left out of the others' checks.
int MostMovedCamera(const std::vector<ViewPose>& views, int num_frames, const CameraPlacement& cameras,
                    const MapperOptions& o, const std::vector<char>& excluded,
                    const std::vector<char>& unchecked, Rigid3* pose) {
  int best = -1;
  double best_excess = 1.0;
  for (size_t c = 0; c < cameras.rig_from_cam.size(); ++c) {
    if (!cameras.placed[c] || excluded[c] || unchecked[c]) continue;
    Rigid3 now;
    const int n = PoseAgainstOthers(static_cast<int>(c), cameras.rig_from_cam[c], views, num_frames, cameras,
                                    excluded, &now);
    if (n < kMinCheckFrames) continue;
    const double rotation_deg = RotationAngle(cameras.rig_from_cam[c], now) * 180.0 / kPi;
    const double translation_mm = 1000.0 * TranslationDistance(cameras.rig_from_cam[c], now);
    const double excess = std::max(rotation_deg / o.move_min_deg, translation_mm / o.move_min_mm);
    if (excess >= best_excess) {
      best_excess = excess;
      best = static_cast<int>(c);
      *pose = now;
    }
  }
  return best;
}

// The clocks: the messages were put on the old map's clocks (SolveUpdate), so each camera's clock is the
// old one plus what this solve found (nothing unless mapper.time_offsets); then the cameras of the old
// map the new map lacks (no detections, not in the rig) and markers it did not see, copied unchanged (a
// camera's offset at the new map's time reference).
void KeepWhatWasNotSeen(const RigMap& old_map, RigMap* map) {
  ComposeClocks(old_map, map);
  for (const MapCamera& c : old_map.cameras) {
    if (map->FindCamera(c.name)) continue;
    MapCamera copy = c;
    copy.observations = 0;
    copy.time_offset_us = c.ClockUs(map->time_reference_utime, old_map.time_reference_utime);
    map->cameras.push_back(copy);
  }
  for (const MapMarker& m : old_map.markers)
    if (!map->FindMarker(m.id)) {
      MapMarker copy = m;
      copy.observations = 0;
      map->markers.push_back(copy);
    }
  std::sort(map->markers.begin(), map->markers.end(),
            [](const MapMarker& a, const MapMarker& b) { return a.id < b.id; });
}

// The map and trajectory in the frame of the reference camera's new pose (a moved reference).
void Reexpress(const Rigid3& new_rig_from_old_rig, MapResult* result) {
  for (RigMap* map : {&result->map, &result->initial_map})
    for (MapCamera& c : map->cameras) c.rig_from_cam = Normalized(new_rig_from_old_rig * c.rig_from_cam);
  for (std::vector<TrajectoryRow>* rows : {&result->trajectory, &result->initial_trajectory})
    for (TrajectoryRow& r : *rows) MoveToRig(new_rig_from_old_rig, &r);
}

}  // namespace

MarkerLayout LayoutFromMap(const RigMap& old_map, const Observations& observations) {
  const int n = observations.NumMarkers();
  MarkerLayout layout;
  layout.placed.assign(n, false);
  layout.object_from_marker.assign(n, Rigid3::Identity());
  layout.observations.assign(n, 0);
  for (const Observation& ob : observations.obs) layout.observations[ob.marker] += ob.kept > 0;
  for (int m = 0; m < n; ++m) {
    const MapMarker* marker = old_map.FindMarker(observations.marker_ids[m]);
    if (!marker) continue;
    layout.placed[m] = true;
    layout.object_from_marker[m] = marker->object_from_marker;
    const bool old_reference = observations.marker_ids[m] == old_map.reference_marker;
    if (layout.reference < 0 || old_reference ||
        (observations.marker_ids[layout.reference] != old_map.reference_marker &&
         layout.observations[m] > layout.observations[layout.reference]))
      layout.reference = m;
  }
  if (layout.reference < 0)
    throw MapperError(
        "no marker of the old map was detected (its ids: " + std::to_string(old_map.markers.size()) +
        " markers, reference " + std::to_string(old_map.reference_marker) + ")");
  return layout;
}

CameraPlacement PlacementFromMap(const RigMap& old_map, const std::vector<std::string>& camera_names) {
  const int n = static_cast<int>(camera_names.size());
  CameraPlacement p;
  p.placed.assign(n, false);
  p.rig_from_cam.assign(n, Rigid3::Identity());
  p.views.assign(n, 0);
  p.fit_rms.assign(n, -1.0);
  for (int c = 0; c < n; ++c) {
    const MapCamera* camera = old_map.FindCamera(camera_names[c]);
    if (!camera) continue;
    p.placed[c] = true;
    p.rig_from_cam[c] = camera->rig_from_cam;
    if (camera_names[c] == old_map.reference_camera) p.reference = c;
  }
  if (p.reference < 0)
    throw MapperError("the old map's reference camera '" + old_map.reference_camera +
                      "' is not in the rig (" + JoinNames(camera_names) + ")");
  return p;
}

std::vector<char> CheckCameras(const std::vector<ViewPose>& views, int num_frames,
                               const std::vector<std::string>& camera_names, const MapperOptions& o,
                               const std::vector<std::string>& only_cameras, CameraPlacement* cameras,
                               MapReport* report) {
  const int n = static_cast<int>(camera_names.size());
  std::vector<char> reestimated(n, 0);
  std::vector<char> unchecked(n, 0);  // held where the old map has them
  for (int c = 0; c < n; ++c)
    unchecked[c] = !only_cameras.empty() &&
                   std::find(only_cameras.begin(), only_cameras.end(), camera_names[c]) == only_cameras.end();
  Rigid3 pose;
  for (int c; (c = MostMovedCamera(views, num_frames, *cameras, o, reestimated, unchecked, &pose)) >= 0;) {
    MovedCamera m;
    m.camera = camera_names[c];
    m.seq = -1;
    m.rig_from_cam_before = cameras->rig_from_cam[c];
    m.rotation_deg = RotationAngle(m.rig_from_cam_before, pose) * 180.0 / kPi;
    m.translation_mm = 1000.0 * TranslationDistance(m.rig_from_cam_before, pose);
    report->moved_cameras.push_back(m);
    cameras->rig_from_cam[c] = pose;
    reestimated[c] = 1;
  }
  const std::vector<char> none(n, 0);
  for (int c = 0; c < n; ++c) {
    if (cameras->placed[c] || cameras->views[c] == 0) continue;
    if (PoseAgainstOthers(c, Rigid3::Identity(), views, num_frames, *cameras, none, &pose) <
        kMinCheckFrames) {
      report->warnings.push_back(
          "camera '" + camera_names[c] +
          "' is not in the old map and shares too few frames with its cameras: left out");
      continue;
    }
    cameras->placed[c] = true;
    cameras->rig_from_cam[c] = pose;
    reestimated[c] = 1;
    report->added_cameras.push_back(camera_names[c]);
  }
  return reestimated;
}

MapResult SolveUpdate(const std::vector<StoredMessage>& messages,
                      const std::vector<std::string>& camera_names,
                      const std::vector<CameraModel>& given_models, const std::vector<std::string>& warnings,
                      const MapperOptions& options, const RigMap& old_map, const UpdateSettings& settings) {
  const auto start = std::chrono::steady_clock::now();
  MapperOptions o = options;
  o.intrinsics.refine = IntrinsicsRefinement::kNone;  // the old map's intrinsics stay
  MapResult result;
  MapReport& report = result.report;
  report.warnings = warnings;
  report.detections_messages = static_cast<int>(messages.size());
  const int threads = o.threads > 0 ? o.threads : std::max(1u, std::thread::hardware_concurrency());
  report.threads = threads;
  std::vector<CameraModel> models = given_models;
  for (size_t c = 0; c < models.size(); ++c)
    if (models[c].width == 0)
      if (const MapCamera* old = old_map.FindCamera(camera_names[c])) models[c] = old->model;

  // Frames on the old map's clocks (the tracker's way: RigMap::ReferenceUtime).
  std::vector<StoredMessage> on_clock = messages;
  for (StoredMessage& m : on_clock) m.utime = old_map.ReferenceUtime(camera_names[m.camera], m.utime);
  const std::vector<Frame> frames =
      AssembleFrames(on_clock, static_cast<int>(camera_names.size()), o.sync_tolerance_us());
  report.frames_assembled = static_cast<int>(frames.size());
  Observations observations = CollectObservations(on_clock, frames, camera_names, o, &report);
  EstimateHypotheses(models, o.tau_e, threads, &observations);
  const MarkerLayout layout = LayoutFromMap(old_map, observations);
  const std::vector<ViewPose> views = FitViews(observations, layout, models, threads);
  CameraPlacement cameras = PlacementFromMap(old_map, camera_names);
  for (const ViewPose& v : views) ++cameras.views[v.camera];
  const std::vector<char> reestimated = CheckCameras(views, static_cast<int>(frames.size()), camera_names, o,
                                                     settings.only_cameras, &cameras, &report);
  const ObjectPoses poses = InitialObjectPoses(observations, frames, layout, cameras, o, threads, &report);

  const ObservationNames names{&frames, &camera_names, &observations.marker_ids};
  MapperBundle bundle = MakeBundleProblem(observations, names, layout, cameras, poses, models, &report);
  for (size_t c = 0; c < reestimated.size(); ++c) bundle.problem.camera_fixed[c] = !reestimated[c];
  if (!settings.refine_layout) bundle.problem.marker_fixed.assign(layout.placed.size(), 1);
  FillMap(bundle, observations, names, layout, cameras, o, &result.initial_map, &result.initial_trajectory);
  report.initial_rms_px = result.initial_map.rms_px;
  if (o.refine)
    RefineWithRejection(observations, names, layout, o, BundleSettingsFor(o, threads), &bundle, &report);
  std::vector<int> row_frames;
  FillMap(bundle, observations, names, layout, cameras, o, &result.map, &result.trajectory, &row_frames);
  result.membership = MembershipOf(frames, row_frames, messages.size());
  for (RigMap* map : {&result.map, &result.initial_map}) KeepWhatWasNotSeen(old_map, map);
  for (MovedCamera& m : report.moved_cameras) {  // against the solved pose, in the old map's frame
    const Rigid3& after = result.map.FindCamera(m.camera)->rig_from_cam;
    m.rotation_deg = RotationAngle(m.rig_from_cam_before, after) * 180.0 / kPi;
    m.translation_mm = 1000.0 * TranslationDistance(m.rig_from_cam_before, after);
    report.warnings.push_back("camera '" + m.camera + "' moved since the old map: turned " +
                              Fixed(m.rotation_deg, 3) + " deg, shifted " + Fixed(m.translation_mm, 2) +
                              " mm; re-estimated");
  }
  if (reestimated[cameras.reference])
    Reexpress(Inverse(result.map.FindCamera(old_map.reference_camera)->rig_from_cam), &result);
  report.final_rms_px = result.map.rms_px;
  report.frames_used = result.map.num_frames;
  report.observations_used = result.map.num_observations;
  for (const std::string& c : report.added_cameras)
    report.warnings.push_back("camera '" + c + "' is not in the old map: added");
  report.total_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace mcmt
