// detector.tone auto (detector/tone.h): a camera's gamma and sharpening estimated from its own decoded
// markers, on reference renders (tests/detector/reference_renderer.h) of known gamma and sharpening.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "tests/detector/accuracy.h"

namespace mcmt {
namespace {

testing::Imaging Camera(double gamma, double sharpen, bool linear) {
  testing::Imaging im;
  im.name = "tone", im.blur_sigma = 0.7, im.gamma = gamma, im.sharpen = sharpen, im.sharpen_linear = linear;
  im.shot_noise = 0.08;
  return im;
}

// Tolerances: gamma 0.15, amount 0.12, sigma 0.25 px, and the order of sharpening and encoding.
void ExpectTone(const ToneEstimate& e, double gamma, double amount, bool linear,
                double amount_tolerance = 0.12) {
  SCOPED_TRACE(e.Describe());
  ASSERT_TRUE(e.ok);
  EXPECT_NEAR(e.gamma, gamma, 0.15);
  EXPECT_NEAR(e.unsharp_amount, amount, amount_tolerance);
  if (amount > 0) {
    EXPECT_NEAR(e.unsharp_sigma, 1.0, 0.25);
    EXPECT_EQ(e.unsharp_linear, linear);
  }
}

TEST(DetectorTone, EstimatesSharpeningOfEncodedValues) {
  ExpectTone(testing::EstimateToneOnReference(Camera(2.2, 0.6, false), 48, 21), 2.2, 0.6, false);
}

TEST(DetectorTone, EstimatesSharpeningOfLinearLight) {
  ExpectTone(testing::EstimateToneOnReference(Camera(2.0, 0.5, true), 48, 22), 2.0, 0.5, true);
}

TEST(DetectorTone, EstimatesNoSharpeningAndLinearImages) {
  ExpectTone(testing::EstimateToneOnReference(Camera(1.0, 0.0, false), 48, 23), 1.0, 0.0, false);
}

// The catalogue's webcam: gamma 2.2, sharpening 0.6 of encoded values, JPEG 75, shading, a 0.6-cell
// margin. JPEG's ringing at the edges reads as more sharpening: amount 0.90 (0.64 without the JPEG,
// 0.86-0.87 with a 1-cell margin or without shading), hence the tolerance 0.35 for the amount here.
TEST(DetectorTone, EstimatesTheWebcamCondition) {
  const testing::Imaging im = testing::CatalogueCondition("webcam");
  ExpectTone(testing::EstimateToneOnReference(im, 48, 24), im.gamma, im.sharpen, false, 0.35);
}

// tone_frames bounds the collection: with tone_markers out of reach the estimate is made after
// tone_frames frames from what they gave (6 markers an image, at most 4 kept a frame), and with fewer than
// kToneMinMarkers the given tone stays and collecting stops, so a recording's first pass (PrimeTone) ends
// there instead of reading the whole recording (the bug: it read on until tone_markers, i.e. to the end).
void DetectFrames(MarkerDetector* detector, const testing::ReferenceScene& scene, const testing::Imaging& im,
                  int frames, uint64_t seed) {
  auto dict = LoadDictionary("DICT_6X6_250");
  std::mt19937_64 rng(seed);
  for (int i = 0; i < frames; ++i) {
    std::vector<testing::RenderedMarker> truth;
    detector->Detect(testing::RenderReference(*dict, scene, im, rng, &truth));
  }
}

// A tone-auto detector of DICT_6X6_250 with these tone_markers and tone_frames, and its scene.
MarkerDetector ToneAutoDetector(int tone_markers, int tone_frames) {
  MarkerConfig mc;
  mc.dictionary = "DICT_6X6_250";
  DetectorOptions options;
  options.tone = "auto", options.tone_markers = tone_markers, options.tone_frames = tone_frames;
  return MarkerDetector(mc, options);
}
testing::ReferenceScene ToneScene() {
  testing::ReferenceScene scene;
  scene.min_side_px = 25, scene.max_side_px = 60, scene.max_angle_deg = 60;
  return scene;
}

TEST(DetectorTone, EstimatesAfterToneFramesFromTheMarkersTheyGave) {
  MarkerDetector detector = ToneAutoDetector(1000, 4);
  const testing::ReferenceScene scene = ToneScene();
  DetectFrames(&detector, scene, Camera(2.2, 0.6, false), 3, 25);
  EXPECT_TRUE(detector.ToneEstimating());
  DetectFrames(&detector, scene, Camera(2.2, 0.6, false), 1, 26);
  EXPECT_FALSE(detector.ToneEstimating());
  ExpectTone(detector.tone(), 2.2, 0.6, false, 0.2);
}

TEST(DetectorTone, KeepsTheGivenToneWhenToneFramesGiveTooFewMarkers) {
  MarkerDetector detector = ToneAutoDetector(60, 5);
  testing::ReferenceScene scene = ToneScene();
  scene.markers = 1;
  DetectFrames(&detector, scene, Camera(2.2, 0.6, false), 5, 27);
  EXPECT_FALSE(detector.ToneEstimating());
  EXPECT_FALSE(detector.tone().ok);
  EXPECT_EQ(detector.options().gamma, 0.0);  // the given tone: none
}

}  // namespace
}  // namespace mcmt
