// The corner accuracy and recall targets, measured on mcmt_sim renders of the paper's rig
// (5 cameras on a circle, 640x480, four-sided object with 4.5 cm markers, ~15-30 px), against the
// renderer's exact corners: mean signed offset along the edge normals within 0.05 px, median corner
// error under 0.15 px, with and without blur and noise; recall >= 98 % within 60 degrees and >= 85 %
// within 75 degrees for fully visible markers of 15 px and more; no wrong ids.
#include <gtest/gtest.h>

#include "tests/detector/sim_eval.h"

namespace mcmt {
namespace {

void Report(const char* what, const testing::SimEvalResult& r) {
  std::printf(
      "%s: recall60 %.3f (%d/%d) recall75 %.3f (%d/%d) wrong %d/%d median %.3f px mean offset %+.3f px\n",
      what, r.Recall60(), r.found60, r.visible60, r.Recall75(), r.found75, r.visible75, r.wrong_ids,
      r.detections, testing::MedianOf(r.corners.errors), testing::MeanOf(r.corners.offsets));
}

void ExpectAccurate(const testing::SimEvalResult& r) {
  ASSERT_GT(r.corners.errors.size(), 100u);
  EXPECT_LT(std::abs(testing::MeanOf(r.corners.offsets)), 0.05);
  EXPECT_LT(testing::MedianOf(r.corners.errors), 0.15);
  EXPECT_EQ(r.wrong_ids, 0);
}

void ExpectRecall(const testing::SimEvalResult& r) {
  ASSERT_GT(r.visible60, 50);
  EXPECT_GE(r.Recall60(), 0.98);
  EXPECT_GE(r.Recall75(), 0.85);
}

TEST(DetectorOnSim, PaperRigAt1m) {
  testing::SimEvalOptions o;
  o.radius = 1.0;
  const auto r = testing::EvaluateOnSim(o);
  Report("radius 1.0, noise 2", r);
  ExpectAccurate(r);
  ExpectRecall(r);
}

TEST(DetectorOnSim, PaperRigAt1_3mSmallMarkers) {
  testing::SimEvalOptions o;
  o.radius = 1.3;
  const auto r = testing::EvaluateOnSim(o);
  Report("radius 1.3, noise 2", r);
  EXPECT_LT(r.max_size_seen, 22.0);
  ExpectAccurate(r);
  ExpectRecall(r);
}

TEST(DetectorOnSim, BlurAndNoise) {
  testing::SimEvalOptions o;
  o.radius = 1.0;
  o.blur = 0.8;
  o.noise = 3.0;
  const auto r = testing::EvaluateOnSim(o);
  Report("radius 1.0, blur 0.8, noise 3", r);
  ExpectAccurate(r);
  ExpectRecall(r);
}

TEST(DetectorOnSim, NoNoiseNoBlur) {
  testing::SimEvalOptions o;
  o.radius = 0.9;
  o.noise = 0.0;
  const auto r = testing::EvaluateOnSim(o);
  Report("radius 0.9, no noise", r);
  ExpectAccurate(r);
  ExpectRecall(r);
}

TEST(DetectorOnSim, InvertedDict4x4AsCaliscope) {
  testing::SimEvalOptions o;
  o.dictionary = "DICT_4X4_1000";
  o.inverted = true;
  const auto r = testing::EvaluateOnSim(o);
  Report("DICT_4X4_1000 inverted", r);
  ExpectAccurate(r);
  ExpectRecall(r);
}

TEST(DetectorOnSim, RadTanDistortion) {
  testing::SimEvalOptions o;
  o.distortion = DistortionModel::kRadTan;
  const auto r = testing::EvaluateOnSim(o);
  Report("radtan", r);
  ExpectAccurate(r);
  ExpectRecall(r);
}

TEST(DetectorOnSim, FisheyeDistortion) {
  testing::SimEvalOptions o;
  o.distortion = DistortionModel::kFisheye;
  const auto r = testing::EvaluateOnSim(o);
  Report("fisheye", r);
  ExpectAccurate(r);
  ExpectRecall(r);
}

}  // namespace
}  // namespace mcmt
