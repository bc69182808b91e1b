// One marker of the catalogue test (test_detector_accuracy's ImagingCatalogueOnReferenceRenders: markers
// 15-60 px, 8 images from seed 11, one detector over them): its true corners, mcmt's, and
// RefineMarkerCorners started from the truth, from mcmt's corners and from OpenCV's candidate, and
// cv::cornerSubPix from the truth.
//   diag_id123 [condition ("no margin, grey surface")] [id (123)] [images (8)] [seed (11)]
#include <cstdio>
#include <cstdlib>
#include <opencv2/imgproc.hpp>

#include "tests/detector/accuracy.h"

using namespace mcmt;

namespace {
void Print(const char* what, const testing::RenderedMarker& t, const std::array<cv::Point2d, 4>& c) {
  testing::CornerErrors e;
  testing::AddCornerErrors(t, c, &e);
  std::printf("%-22s", what);
  for (int k = 0; k < 4; ++k)
    std::printf(" (%7.2f,%7.2f) off %+.2f err %.2f |", c[k].x, c[k].y, e.offsets[k], e.errors[k]);
  std::printf("\n");
}
}  // namespace

int main(int argc, char** argv) {
  // --truth IMAGES: the true corners of bench_accuracy's matrix renders (condition index, id, x0 y0 .. x3 y3
  // per line), to score its MCMT_CORNER_DUMP (bench/results/2026-12-07-id123-gross.py).
  if (argc > 2 && std::string(argv[1]) == "--truth") {
    const int images = std::atoi(argv[2]);
    auto dict = LoadDictionary("DICT_6X6_250");
    const std::vector<testing::Imaging> catalogue = testing::ImagingCatalogue();
    for (size_t c = 0; c < catalogue.size(); ++c)
      for (int s = 0; s < 3; ++s)
        for (int g = 0; g < 3; ++g) {
          std::mt19937_64 rng(testing::BenchSeed(static_cast<int>(c), s, g));
          for (int i = 0; i < images; ++i) {
            std::vector<testing::RenderedMarker> truth;
            testing::RenderReference(*dict, testing::BenchScene(s, g), catalogue[c], rng, &truth);
            for (const testing::RenderedMarker& t : truth) {
              std::printf("%zu %d %d %d %d %.1f %.1f", c, s, g, i, t.id, t.side_px, t.view_angle_deg);
              for (int k = 0; k < 4; ++k) std::printf(" %.6f %.6f", t.corners[k].x, t.corners[k].y);
              std::printf("\n");
            }
          }
        }
    return 0;
  }
  const std::string name = argc > 1 ? argv[1] : "no margin, grey surface";
  const int id = argc > 2 ? std::atoi(argv[2]) : 123;
  const int images = argc > 3 ? std::atoi(argv[3]) : 8;
  const uint64_t seed = argc > 4 ? std::strtoull(argv[4], nullptr, 10) : 11;
  const testing::Imaging im = testing::CatalogueCondition(name);
  testing::ReferenceScene scene;
  scene.min_side_px = 15, scene.max_side_px = 60;
  auto dict = LoadDictionary("DICT_6X6_250");
  const int cells = dict->markerSize + 2;
  MarkerDetector detector = testing::ReferenceDetector(im, DetectorOptions());
  std::mt19937_64 rng(seed);
  for (int i = 0; i < images; ++i) {
    std::vector<testing::RenderedMarker> truth;
    const cv::Mat image = testing::RenderReference(*dict, scene, im, rng, &truth);
    const long long failures = detector.stats().refine_failures;
    if (std::getenv("ID123_IMAGE") && std::atoi(std::getenv("ID123_IMAGE")) == i)
      setenv("ID123_DEBUG", "1", 1);
    const std::vector<marker_t> markers = detector.Detect(image);
    unsetenv("ID123_DEBUG");
    std::printf("image %d: %lld refine failures\n", i, detector.stats().refine_failures - failures);
    for (const testing::RenderedMarker& t : truth) {
      if (t.id != id) continue;
      std::printf("image %d id %d side %.1f px angle %.1f deg\n", i, t.id, t.side_px, t.view_angle_deg);
      Print("truth", t, t.corners);
      const cv::Mat bits =
          cv::aruco::Dictionary::getBitsFromByteList(dict->bytesList.rowRange(id, id + 1), dict->markerSize);
      cv::Mat gray = image.channels() == 1 ? image : cv::Mat();
      if (gray.empty()) cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
      for (const marker_t& m : markers) {
        if (m.id != id) continue;
        std::array<cv::Point2d, 4> found;
        for (int k = 0; k < 4; ++k) found[k] = {m.corners[k][0], m.corners[k][1]};
        Print("mcmt", t, found);
        std::array<cv::Point2d, 4> again = found;
        const bool ok =
            RefineMarkerCorners(gray, cells, bits, nullptr, 1, &again, true, nullptr, true, nullptr, 1);
        Print(ok ? "refined from mcmt" : "from mcmt FAILED", t, again);
      }
      std::array<cv::Point2d, 4> start = t.corners;
      const bool ok =
          RefineMarkerCorners(gray, cells, bits, nullptr, 1, &start, true, nullptr, true, nullptr, 1);
      Print(ok ? "refined from truth" : "from truth FAILED", t, start);
      for (double d : {0.5, -0.5}) {
        std::array<cv::Point2d, 4> s = t.corners;
        for (int k = 0; k < 4; ++k) s[k] += cv::Point2d(d, -d);
        const bool ok2 =
            RefineMarkerCorners(gray, cells, bits, nullptr, 1, &s, true, nullptr, true, nullptr, 1);
        Print(ok2 ? "refined truth+shift" : "truth+shift FAILED", t, s);
      }
      if (const char* c = std::getenv("ID123_START")) {  // "x0,y0,x1,y1,x2,y2,x3,y3": the candidate
        std::array<cv::Point2d, 4> cand;
        std::sscanf(c, "%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf", &cand[0].x, &cand[0].y, &cand[1].x, &cand[1].y,
                    &cand[2].x, &cand[2].y, &cand[3].x, &cand[3].y);
        cv::Mat smooth;
        cv::GaussianBlur(gray, smooth, cv::Size(0, 0), 0.6);
        for (int sm = 0; sm < 2; ++sm) {
          std::array<cv::Point2d, 4> s = cand;
          const bool ok3 = RefineMarkerCorners(sm ? smooth : gray, cells, bits, nullptr, 1, &s, true, nullptr,
                                               true, nullptr, 1);
          Print(!ok3 ? "cand FAILED" : sm ? "cand smoothed" : "cand plain", t, s);
        }
      }
      std::vector<cv::Point2f> sp;
      for (const cv::Point2d& c : t.corners) sp.push_back(cv::Point2f(c.x, c.y));
      cv::cornerSubPix(gray, sp, cv::Size(2, 2), cv::Size(-1, -1),
                       cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 30, 0.01));
      std::array<cv::Point2d, 4> sub;
      for (int k = 0; k < 4; ++k) sub[k] = sp[k];
      Print("cornerSubPix(truth,2)", t, sub);
      if (std::getenv("SAVE")) cv::imwrite(std::getenv("SAVE"), gray);
    }
  }
  return 0;
}
