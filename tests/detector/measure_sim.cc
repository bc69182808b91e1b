// Manual measurement tool (not a test): detector accuracy on sim renders for a few settings.
#include <cstdio>
#include <cstdlib>

#include "tests/detector/sim_eval.h"
using namespace mcmt;
int main(int argc, char** argv) {
  testing::SimEvalOptions o;
  o.radius = argc > 1 ? atof(argv[1]) : 1.0;
  o.blur = argc > 2 ? atof(argv[2]) : 0.0;
  o.noise = argc > 3 ? atof(argv[3]) : 2.0;
  if (argc > 4) o.dictionary = argv[4];
  if (argc > 5) o.detector.corner_refinement = argv[5];
  o.frames = argc > 6 ? atoi(argv[6]) : 20;
  if (argc > 7) o.distortion = DistortionModelFromName(argv[7]);
  if (getenv("MCMT_OBJECT")) o.object = sim::ObjectKindFromName(getenv("MCMT_OBJECT"));
  if (getenv("MCMT_MARKER_SIZE")) o.marker_size = atof(getenv("MCMT_MARKER_SIZE"));
  if (getenv("MCMT_DROP_UNREFINED")) o.detector.drop_unrefined = true;
  if (getenv("MCMT_MIN_SIZE")) o.min_size_px = atof(getenv("MCMT_MIN_SIZE"));
  if (getenv("MCMT_MARGIN")) o.detector.perspective_ignored_margin = atof(getenv("MCMT_MARGIN"));
  if (getenv("MCMT_PPC")) o.detector.perspective_pixels_per_cell = atoi(getenv("MCMT_PPC"));
  if (getenv("MCMT_WMIN")) o.detector.adaptive_window_min = atoi(getenv("MCMT_WMIN"));
  if (getenv("MCMT_WMAX")) o.detector.adaptive_window_max = atoi(getenv("MCMT_WMAX"));
  if (getenv("MCMT_POLY")) o.detector.polygonal_approx_rate = atof(getenv("MCMT_POLY"));
  if (getenv("MCMT_GAMMA")) o.detector.gamma = atof(getenv("MCMT_GAMMA"));
  if (getenv("MCMT_SMOOTH")) o.detector.sharp_smoothing = atof(getenv("MCMT_SMOOTH"));
  if (getenv("MCMT_ECR")) o.detector.error_correction_rate = atof(getenv("MCMT_ECR"));
  auto r = testing::EvaluateOnSim(o);
  for (double lim : {2.0, 5.0, 90.0}) {
    std::vector<double> e;
    for (size_t i = 0; i < r.axis_angles.size(); ++i)
      if (r.axis_angles[i] <= lim && (lim > 5 ? r.axis_angles[i] > 5 : true))
        e.push_back(r.corners.errors[i]);
    printf("corners with sides within %.0f deg of an axis: %zu median %.3f\n", lim, e.size(),
           testing::MedianOf(e));
  }
  printf(
      "radius %.2f blur %.1f noise %.1f %s %s: recall60 %.3f (%d/%d) recall75 %.3f (%d/%d) wrong %d/%d "
      "median %.3f mean offset %+.3f sizes %.1f..%.1f\n",
      o.radius, o.blur, o.noise, o.dictionary.c_str(), o.detector.corner_refinement.c_str(), r.Recall60(),
      r.found60, r.visible60, r.Recall75(), r.found75, r.visible75, r.wrong_ids, r.detections,
      testing::MedianOf(r.corners.errors), testing::MeanOf(r.corners.offsets), r.min_size_seen,
      r.max_size_seen);
}
