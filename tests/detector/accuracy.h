// Corner accuracy of a detector on images with known corners: recall by view angle, wrong ids, corner
// errors and signed offsets along the edge normals. Used by the accuracy-matrix test and the benchmark.
#pragma once

#include <functional>
#include <random>
#include <string>
#include <vector>

#include "core/dictionary.h"
#include "detector/detector.h"
#include "tests/detector/reference_renderer.h"
#include "tests/detector/synthetic.h"

namespace mcmt::testing {

struct Accuracy {
  int visible60 = 0, found60 = 0, visible75 = 0, found75 = 0;  // markers >= 20 px
  int detections = 0, wrong_ids = 0;
  int visible_small = 0, found_small = 0;  // markers below 20 px, <= 75 deg
  CornerErrors corners;
  double Recall60() const { return visible60 ? double(found60) / visible60 : 1.0; }
  double Recall75() const { return visible75 ? double(found75) / visible75 : 1.0; }
  double RecallSmall() const { return visible_small ? double(found_small) / visible_small : 1.0; }
  double MeanOffset() const { return MeanOf(corners.offsets); }
  double MedianError() const { return MedianOf(corners.errors); }
  void Add(const Accuracy& o) {
    visible60 += o.visible60, found60 += o.found60, visible75 += o.visible75, found75 += o.found75;
    detections += o.detections, wrong_ids += o.wrong_ids;
    visible_small += o.visible_small, found_small += o.found_small;
    corners.errors.insert(corners.errors.end(), o.corners.errors.begin(), o.corners.errors.end());
    corners.offsets.insert(corners.offsets.end(), o.corners.offsets.begin(), o.corners.offsets.end());
  }
};

// Markers found in `found` (id, corners) scored against `truth`.
inline void Score(const std::vector<RenderedMarker>& truth, const std::vector<marker_t>& found, Accuracy* a) {
  for (const marker_t& m : found) {
    ++a->detections;
    bool known = false;
    for (const auto& t : truth) known = known || t.id == m.id;
    a->wrong_ids += !known;
  }
  for (const auto& t : truth) {
    if (t.view_angle_deg > 75) continue;
    const bool counted = t.side_px >= 20, in60 = t.view_angle_deg <= 60;
    a->visible75 += counted, a->visible60 += counted && in60;
    a->visible_small += !counted;
    for (const marker_t& m : found) {
      if (m.id != t.id) continue;
      a->found75 += counted, a->found60 += counted && in60;
      a->found_small += !counted;
      AddCornerErrors(t, CornersOf(m), &a->corners);
    }
  }
}

// Stock OpenCV ArUco (default parameters, as a new user calls it) as marker_t.
inline std::vector<marker_t> StockDetect(const cv::Mat& image, const cv::Ptr<cv::aruco::Dictionary>& dict,
                                         bool inverted) {
  auto params = cv::aruco::DetectorParameters::create();
  params->detectInvertedMarker = inverted;
  std::vector<std::vector<cv::Point2f>> corners;
  std::vector<int> ids;
  cv::aruco::detectMarkers(image, dict, corners, ids, params);
  std::vector<marker_t> out(ids.size());
  for (size_t i = 0; i < ids.size(); ++i) {
    out[i].id = ids[i];
    for (int k = 0; k < 4; ++k)
      out[i].corners[k][0] = corners[i][k].x, out[i].corners[k][1] = corners[i][k].y;
  }
  return out;
}

// mcmt's detector (`options`) of `dictionary` for reference renders of `imaging`: an inverted print's
// markers searched as such (markers.inverted, and `inverted` as a rig config defaults it).
inline MarkerDetector ReferenceDetector(const Imaging& imaging, DetectorOptions options = DetectorOptions(),
                                        const std::string& dictionary = "DICT_6X6_250") {
  MarkerConfig mc;
  mc.dictionary = dictionary;
  mc.inverted = imaging.inverted;
  options.inverted = imaging.inverted;
  return MarkerDetector(mc, options);
}

// `images` reference renders of `scene` under `imaging`, detected by mcmt (options) and, when `stock`
// is non-null, by stock OpenCV; `found` (optional) collects mcmt's markers of every image.
inline Accuracy MeasureReference(const std::string& dictionary, const ReferenceScene& scene,
                                 const Imaging& imaging, const DetectorOptions& options, int images,
                                 uint64_t seed, Accuracy* stock = nullptr,
                                 std::vector<marker_t>* found = nullptr) {
  auto dict = LoadDictionary(dictionary);
  MarkerDetector detector = ReferenceDetector(imaging, options, dictionary);
  std::mt19937_64 rng(seed);
  Accuracy a;
  for (int i = 0; i < images; ++i) {
    std::vector<RenderedMarker> truth;
    const cv::Mat image = RenderReference(*dict, scene, imaging, rng, &truth);
    const std::vector<marker_t> markers = detector.Detect(image);
    Score(truth, markers, &a);
    if (found) found->insert(found->end(), markers.begin(), markers.end());
    if (stock) Score(truth, StockDetect(image, dict, imaging.inverted), stock);
  }
  return a;
}

// The estimate a detector with tone auto (detector/tone.h) makes from its first `markers` markers
// (at most 4 a frame) on reference renders of `imaging` (6 markers each, 25-60 px, 0-60 deg, from `seed`).
inline ToneEstimate EstimateToneOnReference(const Imaging& imaging, int markers, uint64_t seed) {
  auto dict = LoadDictionary("DICT_6X6_250");
  DetectorOptions options;
  options.tone = "auto";
  options.tone_markers = markers;
  options.tone_frames = 10 * markers;
  MarkerDetector detector = ReferenceDetector(imaging, options);
  ReferenceScene scene;
  scene.min_side_px = 25, scene.max_side_px = 60, scene.max_angle_deg = 60;
  std::mt19937_64 rng(seed);
  for (int i = 0; i < 10 * markers && !detector.tone().ok; ++i) {
    std::vector<RenderedMarker> truth;
    detector.Detect(RenderReference(*dict, scene, imaging, rng, &truth));
  }
  return detector.tone();
}

// bench_accuracy's matrix: marker side bands x view angle bands, each cell of each condition of
// ImagingCatalogue() rendered from its own seed (the same whichever conditions a run selects).
constexpr double kBenchSides[3][2] = {{15, 25}, {25, 40}, {40, 60}};
constexpr double kBenchAngles[3][2] = {{0, 40}, {40, 60}, {60, 75}};
inline ReferenceScene BenchScene(int side_band, int angle_band) {
  ReferenceScene scene;
  scene.min_side_px = kBenchSides[side_band][0], scene.max_side_px = kBenchSides[side_band][1];
  scene.min_angle_deg = kBenchAngles[angle_band][0], scene.max_angle_deg = kBenchAngles[angle_band][1];
  return scene;
}
inline uint64_t BenchSeed(int condition, int side_band, int angle_band) {
  return 2 + 9 * condition + 3 * side_band + angle_band;
}
// Small markers (10-15 px: cells below 2 px with DICT_6X6_250), a band of their own beside the matrix
// (its seeds apart from BenchSeed's, so the matrix's renders stay as they were).
constexpr double kSmallSides[2] = {10, 15};
inline ReferenceScene SmallScene(int angle_band) {
  ReferenceScene scene = BenchScene(0, angle_band);
  scene.min_side_px = kSmallSides[0], scene.max_side_px = kSmallSides[1];
  scene.markers = 8;
  return scene;
}
inline uint64_t SmallSeed(int condition, int angle_band) { return 1000 + 3 * condition + angle_band; }

}  // namespace mcmt::testing
