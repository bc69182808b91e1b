// An mcmt map of a TagSLAM session (../shared/data/tagslam_test) against TagSLAM's own result
// (reference.bag: rig->camN, perch->tag_N), as test_import_realdata compares them, plus the scale of the
// tag layout: the least-squares ratio of all tag-centre distances, mcmt's over TagSLAM's.
//   diag_tagslam REFERENCE_BAG MAP_YAML...
#include <cstdio>

#include "core/files.h"
#include "tests/support/tagslam.h"

using namespace mcmt;

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: diag_tagslam REFERENCE_BAG MAP_YAML...\n");
    return 2;
  }
  const test::TagslamResult ts = test::ReadTagslam(argv[1]);
  for (int a = 2; a < argc; ++a) {
    const RigMap map = ReadMap(argv[a]);
    double worst_mm = 0, worst_deg = 0;
    for (const MapCamera& c : map.cameras) {
      if (!ts.rig_from_cam.count(c.name)) continue;
      worst_mm = std::max(worst_mm, 1000 * TranslationDistance(c.rig_from_cam, ts.rig_from_cam.at(c.name)));
      worst_deg = std::max(worst_deg, RotationAngle(c.rig_from_cam, ts.rig_from_cam.at(c.name)) * 180 / M_PI);
    }
    std::vector<Eigen::Vector3d> ours, theirs;
    for (const MapMarker& m : map.markers)
      if (ts.perch_from_tag.count(m.id))
        ours.push_back(m.object_from_marker.translation()),
            theirs.push_back(ts.perch_from_tag.at(m.id).translation());
    double dot = 0, sq = 0;
    for (size_t i = 0; i < ours.size(); ++i)
      for (size_t j = i + 1; j < ours.size(); ++j) {
        const double t = (theirs[i] - theirs[j]).norm();
        dot += (ours[i] - ours[j]).norm() * t, sq += t * t;
      }
    std::printf(
        "%s: rms %.3f px, cameras max %.2f mm / %.3f deg from TagSLAM's, tag layout scale %+.3f %% "
        "(%zu tags)\n",
        argv[a], map.rms_px, worst_mm, worst_deg, sq > 0 ? 100 * (dot / sq - 1) : 0.0, ours.size());
  }
  return 0;
}
