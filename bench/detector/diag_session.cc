// Per corner, the detections of a rendered session (mcmt-sim --video: rig.yaml, ground_truth.yaml and
// one video per camera) against the renderer's exact corners: every camera's recording detected as
// mcmt-detector would (DetectRecording: the rig's detector settings, the camera's intrinsics), each
// marker found matched with its true projection (the camera's pose at that frame: bumped cameras too).
// Prints one line per corner: camera, seq, id, corner, detected x y, true x y (px), the marker's side
// (px) and view angle (deg). Compare two detectors' outputs line by line (same session, same order).
//   diag_session SESSION_DIR [max frames per camera (all)]
#include <cstdio>
#include <cstdlib>
#include <string>

#include "core/config.h"
#include "detector/detector.h"
#include "sim/sim.h"

using namespace mcmt;

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: diag_session SESSION_DIR [max frames per camera]\n");
    return 2;
  }
  const std::string dir = argv[1];
  const int max_frames = argc > 2 ? std::atoi(argv[2]) : -1;
  const RigConfig rig = LoadRigConfig(dir + "/rig.yaml");
  const sim::GroundTruth truth = sim::ReadGroundTruth(dir + "/ground_truth.yaml");
  sim::SimObject object;
  object.name = truth.object;
  object.markers = truth.markers;
  std::printf("# camera seq id corner x y true_x true_y side_px angle_deg\n");
  for (const sim::SimCamera& camera : truth.cameras) {
    const std::vector<detections_t> all = DetectRecording(rig, camera.name, max_frames);
    for (const detections_t& d : all) {
      if (d.seq < 0 || d.seq >= static_cast<int64_t>(truth.frames.size())) continue;
      const sim::SimCamera at = sim::CameraAtFrame(camera, truth, d.seq);
      const std::vector<sim::MarkerView> views =
          sim::ProjectMarkers(at, object, truth.frames[d.seq].rig_from_object);
      for (const marker_t& m : d.markers)
        for (const sim::MarkerView& v : views) {
          if (v.id != m.id) continue;
          for (int k = 0; k < 4; ++k)
            std::printf("%s %lld %d %d %.4f %.4f %.4f %.4f %.1f %.1f\n", camera.name.c_str(),
                        static_cast<long long>(d.seq), m.id, k, m.corners[k][0], m.corners[k][1],
                        v.corners[k].x(), v.corners[k].y(), v.size_px, v.view_angle_deg);
        }
    }
  }
  return 0;
}
