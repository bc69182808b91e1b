// Detector evaluation on mcmt_sim renders: recall of fully visible markers by view angle, wrong ids,
// corner errors and signed offsets along the edge normals against the renderer's exact corners.
#pragma once

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "detector/detector.h"
#include "sim/sim.h"
#include "tests/detector/synthetic.h"

namespace mcmt::testing {

struct SimEvalOptions {
  int cameras = 5;
  double radius = 1.0;
  int frames = 20;
  int width = 640, height = 480;
  double marker_size = 0.045;
  sim::ObjectKind object = sim::ObjectKind::kFourSided;
  std::string dictionary = "DICT_6X6_250";
  DistortionModel distortion = DistortionModel::kNone;
  double noise = 2.0, blur = 0.0;
  bool inverted = false;
  double min_size_px = 15.0;    // markers smaller than this are not counted
  uint64_t random_imaging = 0;  // > 0: sim::RandomImaging with this seed (a condition per camera)
  uint64_t seed = 3;
  DetectorOptions detector;
};

struct SimEvalResult {
  int visible60 = 0, found60 = 0, visible75 = 0, found75 = 0;
  int detections = 0, wrong_ids = 0;
  CornerErrors corners;
  std::vector<double>
      axis_angles;  // per corner: the smaller angle of its two sides to an image axis, degrees
  double min_size_seen = 1e9, max_size_seen = 0;
  double Recall60() const { return visible60 ? double(found60) / visible60 : 0; }
  double Recall75() const { return visible75 ? double(found75) / visible75 : 0; }
};

// Whether a marker view is in issue 15's domain for corner targets: fully visible, at least min_size_px on
// its longest side, at most 75 degrees from the view axis (refinement may give up beyond).
inline bool InCornerTargetDomain(const sim::MarkerView& v, double min_size_px = 15.0) {
  return v.fully_visible && v.size_px >= min_size_px && v.view_angle_deg <= 75;
}

inline SimEvalResult EvaluateOnSim(const SimEvalOptions& o) {
  sim::RigOptions rig;
  rig.num_cameras = o.cameras;
  rig.radius = o.radius;
  rig.width = o.width;
  rig.height = o.height;
  rig.distortion = o.distortion;
  const std::vector<sim::SimCamera> cameras = sim::MakeRig(rig);
  sim::ObjectOptions oo;
  oo.kind = o.object;
  oo.marker_size = o.marker_size;
  const sim::SimObject object = sim::MakeObject(oo);
  sim::TrajectoryOptions to;
  to.frames = o.frames;
  to.seed = o.seed;
  to.fps = 3.0;  // far apart poses
  const std::vector<sim::SimFrame> frames = sim::MakeTrajectory(to);
  sim::RenderOptions ro;
  ro.noise_sigma = o.noise;
  ro.blur_sigma = o.blur;
  ro.inverted = o.inverted;
  ro.seed = o.seed;
  if (o.random_imaging > 0) ro = sim::RandomImaging(ro, o.cameras, o.random_imaging);
  sim::Renderer renderer(object, o.dictionary, ro);
  MarkerConfig mc;
  mc.dictionary = o.dictionary;
  mc.inverted = o.inverted;
  for (const auto& m : object.markers) mc.ids.push_back(m.id);  // as mcmt-sim's rig.yaml whitelists
  DetectorOptions dopt = o.detector;
  dopt.inverted = o.inverted;
  SimEvalResult r;
  for (size_t c = 0; c < cameras.size(); ++c) {
    MarkerDetector detector(mc, dopt);
    detector.SetCamera(cameras[c].model);
    for (const sim::SimFrame& f : frames) {
      const cv::Mat image = renderer.Render(cameras[c], static_cast<int>(c), f.seq, f.rig_from_object);
      const std::vector<marker_t> found = detector.Detect(image);
      const std::vector<sim::MarkerView> views = sim::ProjectMarkers(cameras[c], object, f.rig_from_object);
      for (const marker_t& m : found) {
        ++r.detections;
        bool ok = false;
        for (const auto& v : views) ok = ok || (v.id == m.id && v.in_front && v.front_facing);
        if (!ok) ++r.wrong_ids;
      }
      for (const auto& v : views) {
        if (!InCornerTargetDomain(v, o.min_size_px)) continue;
        const marker_t* hit = nullptr;
        for (const marker_t& m : found)
          if (m.id == v.id) hit = &m;
        r.min_size_seen = std::min(r.min_size_seen, v.size_px);
        r.max_size_seen = std::max(r.max_size_seen, v.size_px);
        const bool in60 = v.view_angle_deg <= 60;
        ++r.visible75;
        r.visible60 += in60;
        if (!hit) continue;
        ++r.found75;
        r.found60 += in60;
        RenderedMarker truth;
        const std::array<cv::Point2d, 4> got = CornersOf(*hit);
        for (int k = 0; k < 4; ++k) truth.corners[k] = cv::Point2d(v.corners[k].x(), v.corners[k].y());
        AddCornerErrors(truth, got, &r.corners);
        for (int k = 0; k < 4; ++k) {
          double best = 90;
          for (int side : {(k + 3) % 4, k}) {
            const cv::Point2d d = truth.corners[(side + 1) % 4] - truth.corners[side];
            double a = std::fmod(std::abs(std::atan2(d.y, d.x)) * 180 / M_PI, 90.0);
            best = std::min({best, a, 90 - a});
          }
          r.axis_angles.push_back(best);
        }
      }
    }
  }
  return r;
}

// bench_detector's sequences (also the fast-vs-accurate test's): the box object with 5 cm DICT_6X6_250
// markers on a 30 fps trajectory of `frames`, rendered with noise 2, seen by cameras 1 m away.
struct DetectorBenchScene {
  sim::SimObject object;
  std::vector<sim::SimFrame> trajectory;
  std::unique_ptr<sim::Renderer> renderer;
  MarkerConfig markers;  // the dictionary and the object's ids
  // The rig's cameras (at least 3, as bench_detector always made) at width x height.
  std::vector<sim::SimCamera> Cameras(int num_cameras, int width, int height) const {
    sim::RigOptions rig;
    rig.num_cameras = std::max(num_cameras, 3);
    rig.radius = 1.0;
    rig.width = width;
    rig.height = height;
    return sim::MakeRig(rig);
  }
};
// blur_sigma_px: Gaussian optics blur of every image (0: sharp, as the speed table).
inline DetectorBenchScene MakeDetectorBenchScene(int frames, double blur_sigma_px = 0.0) {
  DetectorBenchScene scene;
  sim::ObjectOptions oo;
  oo.kind = sim::ObjectKind::kBox;
  oo.marker_size = 0.05;
  scene.object = sim::MakeObject(oo);
  sim::TrajectoryOptions to;
  to.frames = frames;
  to.fps = 30;
  scene.trajectory = sim::MakeTrajectory(to);
  sim::RenderOptions ro;
  ro.noise_sigma = 2.0;
  ro.blur_sigma = blur_sigma_px;
  scene.renderer = std::make_unique<sim::Renderer>(scene.object, "DICT_6X6_250", ro);
  scene.markers.dictionary = "DICT_6X6_250";
  for (const auto& m : scene.object.markers) scene.markers.ids.push_back(m.id);
  return scene;
}

}  // namespace mcmt::testing
