// Which markers carry a condition's corner offset: renders the reference images test_detector_accuracy
// renders (markers 15-60 px at 0-75 deg, one detector over all images of a condition, as
// testing::MeasureReference) and prints, per marker found, its image, id, size, view angle, the mean
// signed offset of its corners along the edge normals (+: outward) and its largest corner error; then
// the condition's mean offset and median error.
//   diag_corners CONDITION_SUBSTRING [images (8)] [seed (11)] [min offset px to print (0)]
// With --modes: where fast mode's corners differ from the accurate mode's, on the images
// DetectorAccuracy.FastModeCornersAreTheAccurateModesOnReferenceRenders renders (each image detected
// twice by a fresh detector of each mode: fast mode's second frame is refined from its region search's
// candidates); per marker of the second frame whose corners differ by the given px or more: the
// difference and each mode's mean signed offset and largest corner error.
//   diag_corners --modes CONDITION_SUBSTRING [images (3)] [seed (31)] [min difference px (0.02)]
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>

#include "tests/detector/accuracy.h"

using namespace mcmt;
namespace mcmt {}

namespace {
// Mean signed offset (px, +: outward) and largest corner error (px) of a found marker.
void MarkerErrors(const testing::RenderedMarker& t, const marker_t& m, double* offset, double* worst) {
  testing::CornerErrors e;
  std::array<cv::Point2d, 4> got;
  for (int k = 0; k < 4; ++k) got[k] = {m.corners[k][0], m.corners[k][1]};
  testing::AddCornerErrors(t, got, &e);
  *offset = testing::MeanOf(e.offsets);
  *worst = 0;
  for (double x : e.errors) *worst = std::max(*worst, x);
}

const marker_t* Find(const std::vector<marker_t>& found, int id) {
  for (const marker_t& m : found)
    if (m.id == id) return &m;
  return nullptr;
}
}  // namespace

int main(int argc, char** argv) {
  const bool modes = argc > 1 && std::strcmp(argv[1], "--modes") == 0;
  if (modes) --argc, ++argv;
  if (argc < 2) {
    std::fprintf(
        stderr,
        "usage: diag_corners CONDITION [images (8)] [seed (11)] [min |offset| px (0)]\n"
        "       diag_corners --modes CONDITION [images (3)] [seed (31)] [min difference px (0.02)]\n");
    return 2;
  }
  const int images = argc > 2 ? std::atoi(argv[2]) : modes ? 3 : 8;
  const uint64_t seed = argc > 3 ? std::strtoull(argv[3], nullptr, 10) : modes ? 31 : 11;
  const double min_print = argc > 4 ? std::atof(argv[4]) : modes ? 0.02 : 0.0;
  cv::setNumThreads(1);
  auto dict = LoadDictionary("DICT_6X6_250");
  MarkerConfig mc;
  mc.dictionary = "DICT_6X6_250";
  DetectorOptions fast_options;
  fast_options.fast = true;
  for (const testing::Imaging& im : testing::ImagingCatalogue()) {
    if (!std::strstr(im.name.c_str(), argv[1])) continue;
    testing::ReferenceScene scene;
    if (!modes) scene.min_side_px = 15, scene.max_side_px = 60;
    MarkerDetector detector(mc, DetectorOptions());
    std::mt19937_64 rng(seed);
    testing::Accuracy all;
    for (int i = 0; i < images; ++i) {
      std::vector<testing::RenderedMarker> truth;
      const cv::Mat image = testing::RenderReference(*dict, scene, im, rng, &truth);
      if (modes) {
        MarkerDetector accurate(mc, DetectorOptions()), fast(mc, fast_options);
        accurate.Detect(image), fast.Detect(image);
        const std::vector<marker_t> a = accurate.Detect(image), f = fast.Detect(image);
        for (const auto& t : truth) {
          const marker_t *ma = Find(a, t.id), *mf = Find(f, t.id);
          if (!ma || !mf) continue;
          double diff = 0;
          for (int k = 0; k < 4; ++k)
            for (int c = 0; c < 2; ++c)
              diff = std::max(diff, std::abs(ma->corners[k][c] - mf->corners[k][c]));
          if (diff < min_print) continue;
          double oa, wa, of, wf;
          MarkerErrors(t, *ma, &oa, &wa);
          MarkerErrors(t, *mf, &of, &wf);
          std::printf(
              "%s image %d id %3d side %5.1f px angle %4.1f deg: fast - accurate %.3f px; accurate offset "
              "%+.3f max %.3f, fast offset %+.3f max %.3f\n",
              im.name.c_str(), i, t.id, t.side_px, t.view_angle_deg, diff, oa, wa, of, wf);
        }
        continue;
      }
      const std::vector<marker_t> found = detector.Detect(image);
      testing::Score(truth, found, &all);
      for (const auto& t : truth)
        for (const marker_t& m : found) {
          if (m.id != t.id) continue;
          double offset, worst;
          MarkerErrors(t, m, &offset, &worst);
          if (std::abs(offset) >= min_print)
            std::printf(
                "%s image %d id %3d side %5.1f px angle %4.1f deg: offset %+.3f px, max error %.3f px\n",
                im.name.c_str(), i, t.id, t.side_px, t.view_angle_deg, offset, worst);
        }
    }
    if (modes) continue;
    std::printf("%s: offset %+.4f px median %.4f px recall60 %.3f recall75 %.3f (%zu corners)\n",
                im.name.c_str(), all.MeanOffset(), all.MedianError(), all.Recall60(), all.Recall75(),
                all.corners.errors.size());
  }
  return 0;
}
