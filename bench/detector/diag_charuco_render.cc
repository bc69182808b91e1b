// The caliscope board's small steep markers on renders (issue 15, bench/results/2026-12-05-cam1bias.md):
// each marker's size error (perimeter / true perimeter - 1), its mean outward offset (the sides' widths)
// and its skew error (how much farther from square its corner angles are than the true ones), per band
// of side and view angle. A size error with no offset is a skew error.
// Default: the board's neighbourhood. An inverted 4x4 marker (bright border, a dark one-cell margin, the
// bright neighbouring square beyond), drawn as the negative of a print with a one-cell margin on a
// black surface, through the camera, detected with the gamma given.
//   diag_charuco_render [images per band (20)] [blur sigma px (0.9)] [gamma (1.85)]
//                       [detector gamma (= gamma)] [defocus radius px (0)]
//                       [unsharp amount (0; sigma 1 px, on encoded values)] [JPEG quality (0)]
// Or condition N of the reference catalogue (ImagingCatalogue) as bench_imaging_maps renders it
// (DICT_6X6_250, not inverted, gamma fitted):
//   diag_charuco_render cN [images per band (20)]
#include <cstdio>
#include <cstdlib>

#include "tests/detector/accuracy.h"

using namespace mcmt;

namespace {

struct Band {
  double min_side_px, max_side_px, min_angle_deg, max_angle_deg;
};
constexpr Band kBands[] = {{15, 20, 0, 30},  {15, 20, 55, 70}, {20, 28, 0, 30},
                           {20, 28, 55, 70}, {30, 45, 0, 30},  {30, 45, 55, 70}};

// One detection against its truth: size error %, mean outward offset px, skew error deg.
struct MarkerError {
  double size_pct = 0, offset_px = 0, skew_deg = 0;
};

MarkerError ErrorOf(const marker_t& m, const testing::RenderedMarker& t) {
  std::array<cv::Point2d, 4> got;
  for (int k = 0; k < 4; ++k) got[k] = {m.corners[k][0], m.corners[k][1]};
  MarkerError e;
  for (int k = 0; k < 4; ++k) {
    const int next = (k + 1) % 4;
    // offset: the mean over the 4 sides of their ends' displacement along the true outward normal
    const cv::Point2d n = testing::OutwardNormal(t, k);
    e.offset_px += 0.125 * (n.dot(got[k] - t.corners[k]) + n.dot(got[next] - t.corners[next]));
  }
  e.size_pct = 100 * (testing::QuadPerimeter(got) / testing::QuadPerimeter(t.corners) - 1);
  e.skew_deg = testing::QuadSkewDeg(got) - testing::QuadSkewDeg(t.corners);
  return e;
}

// `images` renders per band of `im` (the negative of each render when `negative`), detected with the
// dictionary, polarity and gamma given; one line per band.
void Report(const testing::Imaging& im, const std::string& dictionary, bool inverted, bool negative,
            double gamma, int images) {
  auto dict = LoadDictionary(dictionary);
  MarkerConfig mc;
  mc.dictionary = dictionary, mc.inverted = inverted;
  DetectorOptions o;
  o.inverted = inverted, o.gamma = gamma;
  for (const Band& b : kBands) {
    MarkerDetector detector(mc, o);
    testing::ReferenceScene scene;
    scene.min_side_px = b.min_side_px, scene.max_side_px = b.max_side_px;
    scene.min_angle_deg = b.min_angle_deg, scene.max_angle_deg = b.max_angle_deg;
    scene.markers = 8;
    std::mt19937_64 rng(7 + static_cast<uint64_t>(b.min_side_px + b.min_angle_deg));
    MarkerError sum;
    double size_sq = 0;
    int n = 0, truths = 0;
    for (int i = 0; i < images; ++i) {
      std::vector<testing::RenderedMarker> truth;
      cv::Mat linear = testing::RenderReferenceLinear(*dict, scene, im, rng, &truth);
      if (negative) linear = im.exposure * (im.ink + im.paper) - linear;
      const cv::Mat image = testing::reference::CameraPipeline(linear, im, rng);
      truths += static_cast<int>(truth.size());
      for (const marker_t& m : detector.Detect(image))
        for (const testing::RenderedMarker& t : truth) {
          if (t.id != m.id) continue;
          const MarkerError e = ErrorOf(m, t);
          sum.size_pct += e.size_pct, sum.offset_px += e.offset_px, sum.skew_deg += e.skew_deg;
          size_sq += e.size_pct * e.size_pct, ++n;
        }
    }
    const int d = std::max(n, 1);
    const double mean = sum.size_pct / d, sd = std::sqrt(std::max(0.0, size_sq / d - mean * mean));
    std::printf(
        "sides %2.0f-%2.0f px, view %2.0f-%2.0f deg: %3d of %3d markers, size %+.3f %% (sd %.3f, se %.3f), "
        "offset %+.4f px, skew error %+.3f deg\n",
        b.min_side_px, b.max_side_px, b.min_angle_deg, b.max_angle_deg, n, truths, mean, sd,
        sd / std::sqrt(d), sum.offset_px / d, sum.skew_deg / d);
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc > 1 && argv[1][0] == 'c') {
    const testing::Imaging im = testing::ImagingCatalogue().at(std::atoi(argv[1] + 1));
    Report(im, "DICT_6X6_250", false, false, 0.0, argc > 2 ? std::atoi(argv[2]) : 20);
    return 0;
  }
  testing::Imaging im;
  im.margin_cells = 1.0, im.surface = im.ink;
  im.blur_sigma = argc > 2 ? std::atof(argv[2]) : 0.9;
  im.gamma = argc > 3 ? std::atof(argv[3]) : 1.85;
  im.defocus_radius = argc > 5 ? std::atof(argv[5]) : 0.0;
  im.sharpen = argc > 6 ? std::atof(argv[6]) : 0.0;
  im.jpeg_quality = argc > 7 ? std::atoi(argv[7]) : 0;
  Report(im, "DICT_4X4_1000", true, true, argc > 4 ? std::atof(argv[4]) : im.gamma,
         argc > 1 ? std::atoi(argv[1]) : 20);
  return 0;
}
