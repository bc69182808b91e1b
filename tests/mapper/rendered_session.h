// The paper's rig rendered and detected in memory, frame by frame (no files, no LCM): the sessions of
// bench_imaging_maps and MapperRenderedViews. 5 cameras on a circle of `radius` m at half its height,
// 640x480, an object (by default the four-sided one with 4 cm markers; DICT_6X6_250), a trajectory scaled
// with the radius.
#pragma once

#include <vector>

#include "core/lcm_util.h"
#include "detector/detector.h"
#include "mapper/mapper.h"
#include "sim/eval.h"
#include "sim/sim.h"

namespace mcmt::testing {

struct RenderedMapSession {
  std::vector<sim::SimCamera> cameras;
  sim::SimObject object;
  std::vector<sim::SimFrame> trajectory;
  MarkerConfig markers;

  // The mapper's options for this object (sizes, dictionary, ids); everything else default.
  MapperOptions Mapping() const {
    MapperOptions mo;
    mo.sizes = object.Sizes();
    mo.dictionary = markers.dictionary;
    mo.marker_ids = markers.ids;
    return mo;
  }
  sim::GroundTruth Truth() const {
    sim::GroundTruth truth;
    truth.cameras = cameras;
    truth.markers = object.markers;
    truth.frames = trajectory;
    truth.marker_size = markers.size;
    return truth;
  }
  // Camera `c`'s message for `frame`: its image rendered by `renderer` and detected by `detector`.
  detections_t Detect(const sim::Renderer& renderer, size_t c, const sim::SimFrame& frame,
                      MarkerDetector* detector) const {
    return Detect(renderer.Render(cameras[c], static_cast<int>(c), frame.seq, frame.rig_from_object), c,
                  frame, detector);
  }
  // Camera `c`'s message for `frame` from its image rendered elsewhere (tests/mapper/reference_rig_view.h).
  detections_t Detect(const cv::Mat& image, size_t c, const sim::SimFrame& frame,
                      MarkerDetector* detector) const {
    detections_t d;
    d.utime = frame.utime;
    d.seq = frame.seq;
    d.camera = cameras[c].name;
    d.dictionary = markers.dictionary;
    d.camera_model = ToCameraModelMsg(cameras[c].model);
    d.markers = detector->Detect(image);
    d.num_markers = static_cast<int32_t>(d.markers.size());
    return d;
  }
};

// `object`: the body and its markers (default: the four-sided object with 4 cm markers); the markers' size
// in `markers` is its first marker's.
inline RenderedMapSession MakeRenderedMapSession(double radius, int frames,
                                                 const sim::ObjectOptions& object = sim::ObjectOptions()) {
  RenderedMapSession s;
  sim::RigOptions ro;
  ro.radius = radius;
  ro.camera_height = 0.5 * radius;
  s.cameras = sim::MakeRig(ro);
  s.object = sim::MakeObject(object);
  sim::TrajectoryOptions to;
  to.frames = frames;
  to.position_radius = 0.15 * radius, to.vertical_range = 0.08 * radius;
  s.trajectory = sim::MakeTrajectory(to);
  s.markers.dictionary = "DICT_6X6_250";
  s.markers.size = s.object.markers.front().size;
  for (const auto& m : s.object.markers) s.markers.ids.push_back(m.id);
  return s;
}

}  // namespace mcmt::testing
