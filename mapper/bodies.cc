// Several rigid bodies in one initialisation and one bundle adjustment (mapper/bodies.h), as named steps:
//   InitialiseBody (per body: observations, hypotheses, marker graph, views)
//   -> PlaceCameras (one camera graph over the views of every body)
//   -> InitialBodyPoses (per body; a static body's one pose)
//   -> JoinBodies (one problem: all markers, one pose slot per moving body and frame, one per static body)
//   -> the single-object refinement stages -> SplitBodies (map.objects, a trajectory per moving body)
//   -> ToRigFrame (rig_frame: a static body's frame).
#include "mapper/bodies.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <set>
#include <sstream>
#include <thread>

#include "core/medoid.h"
#include "mapper/bodies_auto.h"

namespace mcmt {

std::vector<MapperBody> BodiesFromRig(const RigConfig& rig) {
  std::vector<MapperBody> out;
  const std::vector<ObjectConfig>& objects = rig.objects.objects;
  if (objects.size() < 2 &&
      std::none_of(objects.begin(), objects.end(), [](const ObjectConfig& o) { return o.auto_ids; }))
    return out;
  for (const ObjectConfig& o : objects)
    out.push_back(
        {o.name, o.is_static, std::vector<int>(o.ids.begin(), o.ids.end()), o.other, o.sizes, o.auto_ids});
  return out;
}

std::vector<int> BodyIds(const std::vector<MapperBody>& bodies, size_t b,
                         const std::vector<StoredMessage>& messages) {
  std::set<int> claimed, seen;
  for (const MapperBody& body : bodies) claimed.insert(body.ids.begin(), body.ids.end());
  for (const StoredMessage& m : messages)
    for (const StoredMarker& mk : m.markers) seen.insert(mk.id);
  std::vector<int> out;
  for (int id : seen)
    if (bodies[b].other ? !claimed.count(id)
                        : std::find(bodies[b].ids.begin(), bodies[b].ids.end(), id) != bodies[b].ids.end())
      out.push_back(id);
  return out;
}

namespace {

using Clock = std::chrono::steady_clock;

// One body through the single-object stages.
struct BodyStages {
  MapperBody spec;
  MapperOptions options;  // the rig's, with the body's ids and sizes
  Observations observations;
  MarkerLayout layout;
  std::vector<ViewPose> views;
  ObjectPoses poses;
  bool left_out = false;
  int slot_begin = 0, marker_begin = 0;  // in the joint problem
};

// What a body's stage reports add to the map's report (ignored ids are counted over all bodies).
void MergeBodyReport(const MapReport& body, MapReport* report) {
  report->observations_total += body.observations_total;
  report->duplicates += body.duplicates;
  report->weak_frames += body.weak_frames;
  report->undecided_frames += body.undecided_frames;
  report->duplicate_examples.insert(report->duplicate_examples.end(), body.duplicate_examples.begin(),
                                    body.duplicate_examples.end());
  report->rejected_markers.insert(report->rejected_markers.end(), body.rejected_markers.begin(),
                                  body.rejected_markers.end());
  report->warnings.insert(report->warnings.end(), body.warnings.begin(), body.warnings.end());
}

// A body that cannot be mapped: an error naming it, or with allow_partial left out with a warning.
void LeaveOut(const std::string& why, const MapperOptions& o, BodyStages* body, MapReport* report) {
  if (!o.allow_partial) throw MapperError(why + "; use --allow-partial to map the other objects without it");
  body->left_out = true;
  report->warnings.push_back(why + ": left out (--allow-partial)");
}

std::string BodyName(const BodyStages& body) {
  return "object '" + body.spec.name + "'" + (body.spec.is_static ? " (static)" : "");
}

void InitialiseBody(const std::vector<StoredMessage>& messages, const std::vector<Frame>& frames,
                    const BodiesInputs& in, int threads, BodyStages* body, MapReport* report) {
  MapReport own;
  try {
    if (body->options.marker_ids.empty()) throw MapperError("no marker of its ids was detected");
    body->observations = CollectObservations(messages, frames, in.camera_names, body->options, &own);
    EstimateHypotheses(in.models, body->options.tau_e, threads, &body->observations);
    for (const Observation& ob : body->observations.obs) report->ambiguous_observations += ob.kept == 2;
    body->layout = BuildMarkerGraph(body->observations, body->options, threads, &own);
    body->views = FitViews(body->observations, body->layout, in.models, threads);
  } catch (const MapperError& e) {
    std::string ids = body->spec.other ? "other" : "";
    for (int id : body->spec.ids) ids += (ids.empty() ? "" : ", ") + std::to_string(id);
    LeaveOut(BodyName(*body) + " (ids " + ids + "): " + e.what(), body->options, body, report);
  }
  MergeBodyReport(own, report);
}

// One camera graph: views of different bodies in the same frame never pair (their groups differ).
CameraPlacement PlaceCameras(const std::vector<BodyStages>& bodies, int num_frames, const BodiesInputs& in,
                             const MapperOptions& o, int threads, MapReport* report) {
  std::vector<ViewPose> views;
  const Observations* any = nullptr;
  for (size_t b = 0; b < bodies.size(); ++b) {
    if (bodies[b].left_out) continue;
    any = any ? any : &bodies[b].observations;
    for (ViewPose v : bodies[b].views) {
      v.frame += static_cast<int>(b) * num_frames;
      views.push_back(std::move(v));
    }
  }
  if (!any) throw MapperError("no object was seen");
  return BuildCameraGraph(views, *any, in.camera_names, o, threads, report);
}

// A static body's pose: the medoid of its frames' poses; frames far from it are reported (it moved).
Rigid3 StaticPose(const BodyStages& body, const std::vector<Frame>& frames, MapReport* report) {
  std::vector<Rigid3> poses;
  std::vector<int> frame_of;
  for (size_t f = 0; f < body.poses.has_pose.size(); ++f)
    if (body.poses.has_pose[f]) poses.push_back(body.poses.rig_from_object[f]), frame_of.push_back(f);
  const Rigid3 pose = poses[MedoidIndex(poses, body.layout.ObjectScale())];
  std::vector<std::string> moved;
  for (size_t k = 0; k < poses.size(); ++k)
    if (TranslationDistance(poses[k], pose) > body.options.consistency_m ||
        RotationAngle(poses[k], pose) > body.options.consistency_deg * M_PI / 180.0)
      moved.push_back(std::to_string(frames[frame_of[k]].seq));
  if (moved.size() > 0.05 * poses.size()) {
    std::ostringstream why;
    why << BodyName(body) << " is declared static but its pose moves by more than "
        << body.options.consistency_m * 1000 << " mm or " << body.options.consistency_deg << " deg in "
        << moved.size() << " of " << poses.size() << " frames (seq " << JoinNames(moved, 8) << ")";
    report->warnings.push_back(why.str());
  }
  return pose;
}

void InitialBodyPoses(const std::vector<Frame>& frames, const CameraPlacement& cameras, int threads,
                      BodyStages* body, MapReport* report) {
  if (body->left_out) return;
  MapReport own;
  body->poses =
      InitialObjectPoses(body->observations, frames, body->layout, cameras, body->options, threads, &own);
  MergeBodyReport(own, report);
  if (std::none_of(body->poses.has_pose.begin(), body->poses.has_pose.end(), [](char c) { return c != 0; }))
    LeaveOut(BodyName(*body) + " never connects to the cameras: no placed camera sees it", body->options,
             body, report);
}

// The joint problem's inputs: all bodies' observations with markers and frames renumbered (frame = pose
// slot), their layouts side by side, and one pose per slot.
struct Joint {
  Observations observations;
  std::vector<Frame> slots;
  MarkerLayout layout;
  ObjectPoses poses;
  std::vector<int> references;  // every body's reference marker (joint index)
};

void AddBody(const std::vector<Frame>& frames, const Rigid3* static_pose, BodyStages* body, Joint* joint) {
  Joint& j = *joint;
  body->slot_begin = static_cast<int>(j.slots.size());
  body->marker_begin = j.observations.NumMarkers();
  if (static_pose) {
    size_t first = 0;
    while (!body->poses.has_pose[first]) ++first;
    j.slots.push_back(frames[first]);
    j.poses.rig_from_object.push_back(*static_pose);
    j.poses.has_pose.push_back(1);
  } else {
    j.slots.insert(j.slots.end(), frames.begin(), frames.end());
    j.poses.rig_from_object.insert(j.poses.rig_from_object.end(), body->poses.rig_from_object.begin(),
                                   body->poses.rig_from_object.end());
    j.poses.has_pose.insert(j.poses.has_pose.end(), body->poses.has_pose.begin(), body->poses.has_pose.end());
  }
  const Observations& own = body->observations;
  for (size_t i = 0; i < own.obs.size(); ++i) {
    Observation ob = own.obs[i];
    ob.frame = body->slot_begin + (static_pose ? 0 : ob.frame);
    ob.marker += body->marker_begin;
    j.observations.obs.push_back(ob);
    j.poses.usable.push_back(body->poses.usable[i]);
  }
  for (int id : own.marker_ids) {
    j.observations.marker_index[id] = j.observations.NumMarkers();
    j.observations.marker_ids.push_back(id);
  }
  const MarkerLayout& l = body->layout;
  j.layout.placed.insert(j.layout.placed.end(), l.placed.begin(), l.placed.end());
  j.layout.object_from_marker.insert(j.layout.object_from_marker.end(), l.object_from_marker.begin(),
                                     l.object_from_marker.end());
  j.layout.observations.insert(j.layout.observations.end(), l.observations.begin(), l.observations.end());
  j.references.push_back(body->marker_begin + l.reference);
  if (j.layout.reference < 0) j.layout.reference = j.references.back();
  if (j.observations.camera_messages.empty()) j.observations.camera_messages = own.camera_messages;
}

Joint JoinBodies(const std::vector<Frame>& frames, std::vector<BodyStages>* bodies, MapReport* report) {
  Joint joint;
  for (BodyStages& body : *bodies) {
    if (body.left_out) continue;
    if (body.spec.is_static) {
      const Rigid3 pose = StaticPose(body, frames, report);
      AddBody(frames, &pose, &body, &joint);
    } else {
      AddBody(frames, nullptr, &body, &joint);
    }
  }
  return joint;
}

// map.objects and a trajectory per body from the joint map (all markers, rows over all slots).
void SplitBodies(const std::vector<BodyStages>& bodies, const std::vector<int>& row_slots,
                 const std::vector<TrajectoryRow>& rows, RigMap* map,
                 std::vector<std::vector<TrajectoryRow>>* trajectories) {
  const std::vector<MapMarker> all = map->markers;
  map->objects.clear();
  trajectories->clear();
  for (const BodyStages& body : bodies) {
    if (body.left_out) continue;
    MapObject object;
    object.name = body.spec.name;
    object.is_static = body.spec.is_static;
    object.reference_marker = body.observations.marker_ids[body.layout.reference];
    double sq = 0;
    for (const MapMarker& m : all)
      if (body.observations.marker_index.count(m.id)) {
        object.markers.push_back(m);
        sq += m.rms_px * m.rms_px * m.observations;
        object.num_observations += m.observations;
      }
    object.rms_px = object.num_observations ? std::sqrt(sq / object.num_observations) : 0.0;
    std::vector<TrajectoryRow> own;
    const int slots = body.spec.is_static ? 1 : static_cast<int>(body.poses.has_pose.size());
    for (size_t r = 0; r < rows.size(); ++r)
      if (row_slots[r] >= body.slot_begin && row_slots[r] < body.slot_begin + slots) own.push_back(rows[r]);
    if (body.spec.is_static) {
      object.rig_from_object = own.empty() ? Rigid3::Identity() : own[0].rig_from_object;
      own.clear();
    }
    object.num_frames = static_cast<int>(own.size());
    map->objects.push_back(object);
    trajectories->push_back(std::move(own));
  }
  const MapObject& first = map->objects[FirstMovingObject(*map)];
  map->markers = first.markers;
  map->reference_marker = first.reference_marker;
}

// The initial map, then refinement as for one object; every body's reference marker is held (each
// layout's gauge).
MapperBundle RefineJoint(const Joint& j, const std::vector<BodyStages>& bodies, const ObservationNames& names,
                         const BodiesInputs& in, const MapperOptions& o, int threads,
                         CameraPlacement* cameras, MapResult* result) {
  MapReport& report = result->report;
  MapperBundle bundle =
      MakeBundleProblem(j.observations, names, j.layout, *cameras, j.poses, in.models, &report);
  for (int m : j.references) bundle.problem.marker_fixed[m] = 1;
  std::vector<TrajectoryRow> rows;
  std::vector<int> row_slots;
  FillMap(bundle, j.observations, names, j.layout, *cameras, o, &result->initial_map, &rows, &row_slots);
  SplitBodies(bodies, row_slots, rows, &result->initial_map, &result->initial_object_trajectories);
  report.initial_rms_px = result->initial_map.rms_px;
  if (o.refine) {
    const BundleSettings settings = BundleSettingsFor(o, threads);
    RefineWithRejection(j.observations, names, j.layout, o, settings, &bundle, &report);
    DropUnreliableCameras(j.observations, names, o, settings, cameras, &bundle, &report);
  }
  return bundle;
}

// rig_frame: every pose re-expressed in the static body's frame.
void ToRigFrame(const std::string& rig_frame, RigMap* map,
                std::vector<std::vector<TrajectoryRow>>* trajectories) {
  const MapObject* frame = map->FindObject(rig_frame);
  if (!frame) return;
  const Rigid3 new_from_rig = Inverse(frame->rig_from_object);
  for (MapCamera& c : map->cameras) c.rig_from_cam = Normalized(new_from_rig * c.rig_from_cam);
  for (MapObject& o : map->objects)
    if (o.is_static) o.rig_from_object = Normalized(new_from_rig * o.rig_from_object);
  for (auto& rows : *trajectories)
    for (TrajectoryRow& row : rows) MoveToRig(new_from_rig, &row);
  map->rig_frame = rig_frame;
}

// Ids detected that no body holds.
int IgnoredIds(const std::vector<StoredMessage>& messages, const std::vector<BodyStages>& bodies) {
  int n = 0;
  for (const StoredMessage& m : messages)
    for (const StoredMarker& mk : m.markers) {
      bool held = false;
      for (const BodyStages& b : bodies)
        held = held || std::binary_search(b.options.marker_ids.begin(), b.options.marker_ids.end(), mk.id);
      n += !held;
    }
  return n;
}

}  // namespace

// objects: auto / ids: auto: the bodies found, then mapped as if declared (the report says what was found
// and holds the objects: section).
MapResult SolveAutoBodies(const std::vector<StoredMessage>& messages, const BodiesInputs& in,
                          const MapperOptions& o) {
  const auto start = Clock::now();
  const int threads =
      o.threads > 0 ? o.threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  AutoBodies found = GroupIntoBodies(messages, o.bodies, in, o, threads);
  MapReport notes;
  MapperOptions resolved = o;
  resolved.bodies = ResolveAutoBodies(o.bodies, found, &notes);
  found.objects_yaml = ObjectsSectionYaml(resolved.bodies, o.rig_frame);
  std::string listed;
  for (const FoundBody& b : found.bodies)
    listed += (listed.empty() ? "" : "; ") + b.name + (b.is_static ? " (static)" : "") + ": ids " +
              DescribeIds(std::set<int>(b.ids.begin(), b.ids.end()));
  if (std::none_of(resolved.bodies.begin(), resolved.bodies.end(),
                   [](const MapperBody& b) { return !b.is_static; }))
    throw MapperError("objects: auto: no moving body among the ids seen (found: " +
                      (listed.empty() ? std::string("nothing") : listed) + ")");
  std::vector<std::string> warnings = in.warnings;
  warnings.insert(warnings.end(), notes.warnings.begin(), notes.warnings.end());
  warnings.push_back(
      "objects found (auto): " + (listed.empty() ? std::string("none") : listed) +
      (found.foreign.empty() ? "" : "; " + std::to_string(found.foreign.size()) + " foreign ids"));
  const BodiesInputs inputs{in.camera_names, in.models, warnings, in.progress};
  MapResult result = SolveBodies(messages, inputs, resolved);
  result.report.auto_bodies = std::move(found);
  const double grouping =
      std::chrono::duration<double>(Clock::now() - start).count() - result.report.total_seconds;
  result.report.stage_seconds.insert(result.report.stage_seconds.begin(), {"auto objects", grouping});
  result.report.total_seconds += grouping;
  return result;
}

std::string TrajectoryFileNames(const RigMap& map) {
  if (map.objects.empty()) return "trajectory.csv, trajectory_initial.csv";
  std::string out;
  for (const MapObject& o : map.objects)
    if (!o.is_static) out += (out.empty() ? "" : ", ") + ("trajectory_" + o.name + ".csv");
  return out + " (and trajectory_initial_<object>.csv)";
}

MapResult DiagnosticsView(const MapResult& result) {
  if (result.map.objects.empty()) return result;
  MapResult view;
  view.map = result.map.ObjectMap(FirstMovingObject(result.map));
  view.initial_map = result.initial_map.ObjectMap(FirstMovingObject(result.initial_map));
  view.trajectory = result.trajectory;
  view.initial_trajectory = result.initial_trajectory;
  view.report = result.report;
  for (detections_t d : result.detections) {
    std::vector<marker_t> own;
    for (const marker_t& m : d.markers)
      if (view.map.FindMarker(m.id)) own.push_back(m);
    d.markers = own;
    d.num_markers = static_cast<int32_t>(own.size());
    view.detections.push_back(std::move(d));
  }
  return view;
}

MapResult SolveBodies(const std::vector<StoredMessage>& messages, const BodiesInputs& in,
                      const MapperOptions& o) {
  const auto start = Clock::now();
  if (HasAutoBodies(o.bodies)) return SolveAutoBodies(messages, in, o);
  if (o.estimate_time_offsets)
    throw MapperError("mapper.time_offsets is not supported with several objects yet (objects:)");
  MapResult result;
  MapReport& report = result.report;
  report.warnings = in.warnings;
  report.detections_messages = static_cast<int>(messages.size());
  const int threads =
      o.threads > 0 ? o.threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  report.threads = threads;
  const std::vector<Frame> frames =
      AssembleFrames(messages, static_cast<int>(in.camera_names.size()), o.sync_tolerance_us());
  report.frames_assembled = static_cast<int>(frames.size());

  std::vector<BodyStages> bodies(o.bodies.size());
  MapperOptions joint_options = o;
  joint_options.sizes.overrides.clear();
  for (size_t b = 0; b < bodies.size(); ++b) {
    bodies[b].spec = o.bodies[b];
    bodies[b].options = o;
    bodies[b].options.marker_ids = BodyIds(o.bodies, b, messages);
    bodies[b].options.sizes = o.bodies[b].sizes;
    if (std::find(bodies[b].options.marker_ids.begin(), bodies[b].options.marker_ids.end(),
                  o.reference_marker) == bodies[b].options.marker_ids.end())
      bodies[b].options.reference_marker = -1;
    for (int id : bodies[b].options.marker_ids) joint_options.sizes.overrides[id] = o.bodies[b].sizes.Get(id);
    InitialiseBody(messages, frames, in, threads, &bodies[b], &report);
  }
  report.ignored_ids = IgnoredIds(messages, bodies);
  CameraPlacement cameras = PlaceCameras(bodies, static_cast<int>(frames.size()), in, o, threads, &report);
  for (BodyStages& body : bodies) InitialBodyPoses(frames, cameras, threads, &body, &report);
  if (std::all_of(bodies.begin(), bodies.end(), [](const BodyStages& b) { return b.left_out; }))
    throw MapperError("no object could be mapped");
  report.stage_seconds.emplace_back("initialisation",
                                    std::chrono::duration<double>(Clock::now() - start).count());

  Joint joint = JoinBodies(frames, &bodies, &report);
  const ObservationNames names{&joint.slots, &in.camera_names, &joint.observations.marker_ids};
  const MapperBundle bundle =
      RefineJoint(joint, bodies, names, in, joint_options, threads, &cameras, &result);
  std::vector<int> row_slots;
  std::vector<TrajectoryRow> rows;
  FillMap(bundle, joint.observations, names, joint.layout, cameras, joint_options, &result.map, &rows,
          &row_slots);
  SplitBodies(bodies, row_slots, rows, &result.map, &result.object_trajectories);
  ToRigFrame(o.rig_frame, &result.initial_map, &result.initial_object_trajectories);
  ToRigFrame(o.rig_frame, &result.map, &result.object_trajectories);
  result.trajectory = result.object_trajectories[FirstMovingObject(result.map)];
  result.initial_trajectory = result.initial_object_trajectories[FirstMovingObject(result.initial_map)];
  report.final_rms_px = result.map.rms_px;
  report.observations_used = result.map.num_observations;
  std::set<int64_t> used;
  for (const auto& own : result.object_trajectories)
    for (const TrajectoryRow& row : own) used.insert(row.utime);
  report.frames_used = static_cast<int>(used.size());
  report.total_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  report.stage_seconds.emplace_back("refine", report.total_seconds);
  return result;
}

}  // namespace mcmt
