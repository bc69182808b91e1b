// Where fast mode's corners differ from the accurate mode's on reference renders: renders the images
// DetectorAccuracy.FastModeCornersAreTheAccurateModesOnReferenceRenders renders (seed 31, 3 images per
// condition, each image detected twice by a fresh detector of each mode: fast mode's second frame is
// refined from its region search's candidates) and prints, per marker of the second frame whose corners
// differ by more than the given px, its id, size, view angle, the difference, and each mode's mean
// signed offset (+: outward) and largest corner error against the truth.
//   diag_modes CONDITION_SUBSTRING [images (3)] [seed (31)] [min difference px (0.02)]
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "tests/detector/accuracy.h"

using namespace mcmt;

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: diag_modes CONDITION [images (3)] [seed (31)] [min difference px (0.02)]\n");
    return 2;
  }
  const int images = argc > 2 ? std::atoi(argv[2]) : 3;
  const uint64_t seed = argc > 3 ? std::strtoull(argv[3], nullptr, 10) : 31;
  const double min_print = argc > 4 ? std::atof(argv[4]) : 0.02;
  cv::setNumThreads(1);
  auto dict = LoadDictionary("DICT_6X6_250");
  MarkerConfig mc;
  mc.dictionary = "DICT_6X6_250";
  for (const testing::Imaging& im : testing::ImagingCatalogue()) {
    if (!std::strstr(im.name.c_str(), argv[1])) continue;
    testing::ReferenceScene scene;
    std::mt19937_64 rng(seed);
    for (int i = 0; i < images; ++i) {
      std::vector<testing::RenderedMarker> truth;
      const cv::Mat image = testing::RenderReference(*dict, scene, im, rng, &truth);
      DetectorOptions fast_options;
      fast_options.fast = true;
      MarkerDetector accurate(mc, DetectorOptions()), fast(mc, fast_options);
      accurate.Detect(image), fast.Detect(image);
      const std::vector<marker_t> a = accurate.Detect(image), f = fast.Detect(image);
      auto score = [&](const testing::RenderedMarker& t, const marker_t& m, double* offset, double* worst) {
        testing::CornerErrors e;
        std::array<cv::Point2d, 4> got;
        for (int k = 0; k < 4; ++k) got[k] = {m.corners[k][0], m.corners[k][1]};
        testing::AddCornerErrors(t, got, &e);
        *offset = testing::MeanOf(e.offsets);
        *worst = 0;
        for (double x : e.errors) *worst = std::max(*worst, x);
      };
      for (const auto& t : truth) {
        const marker_t *ma = nullptr, *mf = nullptr;
        for (const marker_t& m : a) ma = m.id == t.id ? &m : ma;
        for (const marker_t& m : f) mf = m.id == t.id ? &m : mf;
        if (!ma || !mf) continue;
        double diff = 0;
        for (int k = 0; k < 4; ++k)
          for (int c = 0; c < 2; ++c) diff = std::max(diff, std::abs(ma->corners[k][c] - mf->corners[k][c]));
        if (diff < min_print) continue;
        double oa, wa, of, wf;
        score(t, *ma, &oa, &wa);
        score(t, *mf, &of, &wf);
        std::printf(
            "%s image %d id %3d side %5.1f px angle %4.1f deg: fast - accurate %.3f px; accurate offset "
            "%+.3f "
            "max %.3f, fast offset %+.3f max %.3f\n",
            im.name.c_str(), i, t.id, t.side_px, t.view_angle_deg, diff, oa, wa, of, wf);
      }
    }
  }
  return 0;
}
