// The corner accuracy and recall targets, measured on mcmt_sim renders of the paper's rig
// (5 cameras on a circle, 640x480, four-sided object with 4.5 cm markers, ~15-30 px), against the
// renderer's exact corners: mean signed offset along the edge normals within 0.05 px, median corner
// error under 0.15 px, with and without blur and noise; recall >= 98 % within 60 degrees and >= 85 %
// within 75 degrees for fully visible markers of 15 px and more; no wrong ids.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>

#include "detector/detector.h"
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

// The corners have the same bits on every machine: which of the C library's variants of its math
// functions runs must not move them. glibc picks FMA code for exp, sin, cos and atan2 where the CPU has
// FMA, and on a few arguments in a thousand its last bit differs from the plain code's; FitLine's
// direction came from atan2 / sin / cos and moved corners by up to 3e-12 px between machines (now
// PrincipalDirection2d: +, -, *, /, sqrt). The test runs itself twice, the second time with glibc's FMA
// and AVX2 code switched off (GLIBC_TUNABLES), and compares the corners of bench_detector's frames (sharp
// and blurred, 640x480, accurate mode; blurred once more with a given gamma and sharpening) bit for bit. Each
// run also writes a hash of the bits of three million libm values, which must differ between the runs, or the
// switch had no effect here and the test is skipped.
std::string CornerAndLibmBits() {
  std::ostringstream out;
  uint64_t libm_hash = 0;  // the bits of every value, so that one last bit changes it
  for (int i = 1; i <= 1000000; ++i) {
    const double x = i * 1e-5;
    for (const double v : {std::atan2(x, 1.5 - x), std::sin(x), std::exp(-x)}) {
      uint64_t bits;
      std::memcpy(&bits, &v, sizeof(bits));
      libm_hash = (libm_hash ^ bits) * 1099511628211ull;
    }
  }
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "libm %016llx\n", static_cast<unsigned long long>(libm_hash));
  out << buffer;
  // Sharp and blurred frames; the second blurred run with a camera's tone given (gamma, sharpening undone).
  for (const double blur_px : {0.0, 1.0, -1.0}) {
    const testing::DetectorBenchScene scene = testing::MakeDetectorBenchScene(20, std::abs(blur_px));
    const sim::SimCamera camera = scene.Cameras(1, 640, 480)[0];
    DetectorOptions options;
    if (blur_px < 0) options.gamma = 2.2, options.unsharp_amount = 0.5, options.unsharp_sigma = 1.1;
    MarkerDetector detector(scene.markers, options);
    detector.SetCamera(camera.model);
    for (const auto& frame : scene.trajectory)
      for (const auto& m :
           detector.Detect(scene.renderer->Render(camera, 0, frame.seq, frame.rig_from_object))) {
        out << m.id;
        for (int k = 0; k < 4; ++k) {
          std::snprintf(buffer, sizeof(buffer), " %a %a", m.corners[k][0], m.corners[k][1]);
          out << buffer;
        }
        out << "\n";
      }
  }
  return out.str();
}

std::string RunSelf(const std::string& environment, const std::string& output) {
  char self[4096];
  const ssize_t length = readlink("/proc/self/exe", self, sizeof(self) - 1);
  if (length <= 0) return "";
  self[length] = 0;
  const std::string command = environment + " MCMT_TEST_CORNER_BITS=" + output + " " + self +
                              " --gtest_filter=DetectorOnSim.CornersDoNotDependOnTheCLibrarysMathVariants"
                              " > /dev/null 2>&1";
  if (std::system(command.c_str()) != 0) return "";
  std::ifstream in(output);
  std::stringstream content;
  content << in.rdbuf();
  return content.str();
}

TEST(DetectorOnSim, CornersDoNotDependOnTheCLibrarysMathVariants) {
  if (const char* output = std::getenv("MCMT_TEST_CORNER_BITS")) {  // the child run
    std::ofstream(output) << CornerAndLibmBits();
    return;
  }
  const std::string dir = ::testing::TempDir();
  const std::string plain = RunSelf("", dir + "/corner_bits_default.txt");
  const std::string no_fma = RunSelf("GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2_Usable,-FMA_Usable,-AVX2,-FMA",
                                     dir + "/corner_bits_no_fma.txt");
  ASSERT_FALSE(plain.empty()) << "the test's own run in " << dir << " failed";
  ASSERT_FALSE(no_fma.empty()) << "the test's own run with GLIBC_TUNABLES in " << dir << " failed";
  const size_t libm_end = plain.find('\n');
  if (plain.substr(0, libm_end) == no_fma.substr(0, no_fma.find('\n')))
    GTEST_SKIP() << "GLIBC_TUNABLES does not change the C library's math here (no FMA on this CPU, or "
                    "another C library): nothing to compare";
  const std::string corners = plain.substr(libm_end + 1),
                    corners_no_fma = no_fma.substr(no_fma.find('\n') + 1);
  EXPECT_GT(std::count(corners.begin(), corners.end(), '\n'), 100);
  EXPECT_EQ(corners, corners_no_fma) << "corners (id, then x y of each corner in %a) differ between the "
                                        "C library's FMA and plain math code";
}

}  // namespace
}  // namespace mcmt
