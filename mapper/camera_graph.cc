// Stages: each camera frame's pose relative to the object, then the camera graph (the paper's step 2;
// same-marker candidates are the paper's, other placed markers of the frame add candidates through
// object_from_marker).
#include <cmath>
#include <limits>
#include <sstream>

#include "core/math.h"
#include "core/rigid_pose.h"
#include "mapper/parallel.h"
#include "mapper/stages.h"

namespace mcmt {
namespace {

// One view: the candidates of a lone marker, or one pose fitted to the corners of all its placed markers
// from the best of a few hypothesis-derived starts (far more precise than one square at grazing angles).
bool FitView(const Observations& observations, std::pair<int, int> range, const MarkerLayout& layout,
             const std::vector<Rigid3>& marker_from_object, const std::vector<CameraModel>& models,
             double object_scale, ViewPose* view) {
  const std::vector<Observation>& obs = observations.obs;
  view->frame = obs[range.first].frame;
  view->camera = obs[range.first].camera;
  std::vector<Rigid3> cands;
  std::vector<PosePoint> points;  // world = the camera, body = the object
  int used_markers = 0;
  for (int i = range.first; i < range.second; ++i) {
    if (!layout.placed[obs[i].marker] || obs[i].kept == 0) continue;
    ++used_markers;
    for (int h = 0; h < obs[i].kept; ++h)
      cands.push_back(observations.poses[i].hypotheses[h].cam_from_marker *
                      marker_from_object[obs[i].marker]);
    const MarkerCorners3d corners = MarkerCornersInMarker(obs[i].side);
    for (int c = 0; c < 4; ++c)
      points.push_back({&models[view->camera], nullptr, layout.object_from_marker[obs[i].marker] * corners[c],
                        obs[i].corners[c]});
  }
  if (cands.empty()) return false;
  if (used_markers == 1) {
    view->cam_from_object = cands;
    return true;
  }
  std::vector<Rigid3> starts = {cands[MedoidIndex(cands, object_scale)]};
  for (size_t c = 0; c < cands.size() && starts.size() < 4; c += 2) starts.push_back(cands[c]);
  double best = std::numeric_limits<double>::infinity();
  Rigid3 best_pose = starts[0];
  RigidPoseOptions options;
  options.max_iterations = 15;
  for (Rigid3 start : starts) {
    RefineRigidPose(points, options, &start);
    const double e = std::sqrt(PoseSquaredError(points, start) / points.size());
    if (e < best) {
      best = e;
      best_pose = start;
    }
  }
  view->cam_from_object.push_back(best_pose);
  view->fit_rms = best;
  return true;
}

std::vector<GraphItem> CameraItems(const std::vector<ViewPose>& views) {
  std::vector<GraphItem> items;
  items.reserve(views.size());
  for (const ViewPose& v : views) {
    GraphItem item;
    item.group = v.frame;
    item.node = v.camera;
    item.node_from_common = v.cam_from_object;
    for (const Rigid3& p : v.cam_from_object) item.common_from_node.push_back(Inverse(p));
    items.push_back(std::move(item));
  }
  return items;
}

int ReferenceCamera(const CameraPlacement& placement, const std::vector<std::string>& names,
                    const MapperOptions& o) {
  const int n = static_cast<int>(names.size());
  int reference = -1;
  if (!o.reference_camera.empty()) {
    const auto it = std::find(names.begin(), names.end(), o.reference_camera);
    if (it == names.end() || placement.views[it - names.begin()] == 0)
      throw MapperError("reference camera '" + o.reference_camera +
                        "' (mapper.reference_camera) never saw the object");
    reference = static_cast<int>(it - names.begin());
  } else {
    reference = BestConnectedNode(n, placement.edges);
    if (reference < 0)
      for (int c = 0; c < n; ++c)
        if (placement.views[c] > 0 && (reference < 0 || placement.views[c] > placement.views[reference]))
          reference = c;
  }
  if (reference < 0) throw MapperError("no camera saw a marker of the object");
  return reference;
}

std::string WhyNotPlaced(int c, const CameraPlacement& placement, const Observations& observations,
                         const std::vector<std::string>& names, const std::vector<std::string>& placed_names,
                         const MapperOptions& o) {
  const std::string& name = names[c];
  std::ostringstream msg;
  if (observations.camera_messages[c] == 0) {
    msg << "camera '" << name << "' sent no detections";
  } else if (placement.views[c] == 0) {
    msg << "camera '" << name << "' never saw a marker of the object (" << observations.camera_messages[c]
        << " frames)";
  } else {
    msg << "camera '" << name << "' cannot be placed: in none of the " << placement.views[c]
        << " frames where it sees the object does a camera connected to the reference '"
        << names[placement.reference] << "' (" << JoinNames(placed_names) << ") see it too (sync tolerance "
        << o.sync_tolerance_ms << " ms); record frames where '" << name
        << "' and one of those cameras see the object at the same time";
  }
  return msg.str();
}

void ReportUnplacedCameras(const CameraPlacement& placement, const Observations& observations,
                           const std::vector<std::string>& names, const MapperOptions& o, MapReport* report) {
  std::vector<std::string> placed_names, problems, dropped;
  for (size_t c = 0; c < names.size(); ++c)
    if (placement.placed[c]) placed_names.push_back(names[c]);
  for (size_t c = 0; c < names.size(); ++c) {
    if (placement.placed[c]) continue;
    problems.push_back(WhyNotPlaced(static_cast<int>(c), placement, observations, names, placed_names, o));
    dropped.push_back(names[c]);
    report->dropped_cameras.push_back(names[c]);
  }
  if (problems.empty()) return;
  if (!o.allow_partial) {
    std::string all = problems[0];
    if (problems.size() > 1)
      all += " (and " + std::to_string(problems.size() - 1) +
             " more cameras: " + JoinNames(std::vector<std::string>(dropped.begin() + 1, dropped.end())) +
             ")";
    throw MapperError(all + "; use --allow-partial to map the connected cameras only");
  }
  for (const std::string& p : problems) report->warnings.push_back(p + ": left out (--allow-partial)");
}

}  // namespace

std::vector<ViewPose> FitViews(const Observations& observations, const MarkerLayout& layout,
                               const std::vector<CameraModel>& models, int threads) {
  const double object_scale = layout.ObjectScale();
  std::vector<Rigid3> marker_from_object(layout.object_from_marker.size());
  for (size_t m = 0; m < marker_from_object.size(); ++m)
    marker_from_object[m] = Inverse(layout.object_from_marker[m]);
  const int n = static_cast<int>(observations.views.size());
  std::vector<ViewPose> views(n);
  std::vector<char> ok(n, 0);
  ParallelFor(n, threads, [&](int k) {
    ok[k] = FitView(observations, observations.views[k], layout, marker_from_object, models, object_scale,
                    &views[k]);
  });
  std::vector<ViewPose> kept;
  kept.reserve(views.size());
  for (int k = 0; k < n; ++k)
    if (ok[k]) kept.push_back(std::move(views[k]));
  return kept;
}

CameraPlacement BuildCameraGraph(const std::vector<ViewPose>& views, const Observations& observations,
                                 const std::vector<std::string>& camera_names, const MapperOptions& o,
                                 int threads, MapReport* report) {
  const int n = static_cast<int>(camera_names.size());
  CameraPlacement placement;
  // Median fit of each camera's multi-marker views: a camera whose views do not fit the marker layout has
  // wrong intrinsics or images (e.g. rotated frames), which no initialisation can fix.
  placement.fit_rms.assign(n, -1.0);
  placement.views.assign(n, 0);
  std::vector<std::vector<double>> fits(n);
  std::vector<double> depths;
  for (const ViewPose& v : views) {
    if (v.fit_rms >= 0) fits[v.camera].push_back(v.fit_rms);
    depths.push_back(v.cam_from_object[0].translation().norm());
    ++placement.views[v.camera];
  }
  for (int c = 0; c < n; ++c)
    if (!fits[c].empty()) placement.fit_rms[c] = Median(fits[c]);
  EdgeOptions edge_options;
  edge_options.max_events = o.max_pair_events;
  edge_options.medoid.point_scale = std::max(0.1, Median(depths));
  edge_options.tau_n = o.tau_n;
  edge_options.consistency = ConsistencyFor(o);
  placement.edges = BuildGraphEdges(CameraItems(views), n, edge_options, threads);
  placement.reference = ReferenceCamera(placement, camera_names, o);
  placement.placed = ComponentOf(n, placement.reference, placement.edges);
  ReportUnplacedCameras(placement, observations, camera_names, o, report);
  placement.rig_from_cam =
      PosesFromTree(n, placement.reference, MinimumSpanningTree(n, placement.edges)).root_from_node;
  return placement;
}

}  // namespace mcmt
