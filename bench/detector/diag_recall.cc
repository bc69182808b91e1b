// Why markers are missed: renders reference images of one imaging condition (the bench_accuracy
// scenes), runs the detector, and for every marker it misses (>= 20 px, <= 75 deg) tells what OpenCV's
// candidate search saw at each adaptive-threshold window: the nearest contour's polygon, whether it is
// a quadrilateral near the true corners, and which check drops it. Writes each image with misses and
// its threshold images to DIR (PNG) to look at.
//   diag_recall CONDITION_SUBSTRING [images per cell (3)] [DIR (/tmp/recall_diag)]
//   diag_recall --cost: thread CPU time of Detect on the catalogue's renders with and without
//   reread_rejected, and how many rejected candidates were read again.
//   diag_recall --own CONDITION [images per cell (3)]: markers the OpenCV candidate search finds and the
//   own one (candidate_search "own") misses, and the other way round, with the nearest quad FindQuads
//   gives at each threshold level (mean corner distance to the truth, px).
#include <sys/stat.h>
#include <time.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <opencv2/imgcodecs.hpp>

#include "detector/candidates.h"
#include "tests/detector/accuracy.h"

using namespace mcmt;

namespace {
double MeanCornerDistance(const std::vector<cv::Point>& poly, const std::array<cv::Point2d, 4>& truth) {
  double best = 1e9;
  for (int rot = 0; rot < 4; ++rot)
    for (int dir = 0; dir < 2; ++dir) {
      double d = 0;
      for (int k = 0; k < 4; ++k) {
        const int j = dir ? (rot + k) % 4 : (rot - k + 4) % 4;
        d += cv::norm(cv::Point2d(poly[j].x, poly[j].y) - truth[k]) / 4;
      }
      best = std::min(best, d);
    }
  return best;
}

// Mean corner distance of the nearest quad of `quads` to `truth` (any rotation and direction).
double NearestQuad(const std::vector<std::array<cv::Point2d, 4>>& quads,
                   const std::array<cv::Point2d, 4>& truth) {
  double best = 1e9;
  for (const auto& q : quads) {
    std::vector<cv::Point> poly;
    for (const auto& c : q) poly.emplace_back(cvRound(c.x * 16), cvRound(c.y * 16));
    std::array<cv::Point2d, 4> t16;
    for (int k = 0; k < 4; ++k) t16[k] = truth[k] * 16;
    best = std::min(best, MeanCornerDistance(poly, t16) / 16);
  }
  return best;
}

int CompareSearches(const char* only, int images) {
  cv::setNumThreads(1);
  auto dict = LoadDictionary("DICT_6X6_250");
  DetectorOptions opencv, own;
  own.candidate_search = "own";
  int lost = 0, gained = 0;
  const std::vector<testing::Imaging> catalogue = testing::ImagingCatalogue();
  for (size_t c = 0; c < catalogue.size(); ++c) {
    const testing::Imaging& im = catalogue[c];
    if (std::strcmp(only, "all") != 0 && !std::strstr(im.name.c_str(), only)) continue;
    for (int s = 0; s < 3; ++s)
      for (int g = 0; g < 3; ++g) {
        const testing::ReferenceScene scene = testing::BenchScene(s, g);
        const uint64_t seed = testing::BenchSeed(static_cast<int>(c), s, g);
        MarkerDetector a = testing::ReferenceDetector(im, opencv), b = testing::ReferenceDetector(im, own);
        std::mt19937_64 rng(seed);
        for (int i = 0; i < images; ++i) {
          std::vector<testing::RenderedMarker> truth;
          const cv::Mat image = testing::RenderReference(*dict, scene, im, rng, &truth);
          const std::vector<marker_t> fa = a.Detect(image), fb = b.Detect(image);
          for (const auto& m : fb) {
            bool known = false;
            for (const auto& t : truth) known = known || t.id == m.id;
            if (!known)
              std::printf("%s: WRONG id %d seed %llu image %d\n", im.name.c_str(), m.id,
                          static_cast<unsigned long long>(seed), i);
          }
          for (const auto& t : truth) {
            if (t.view_angle_deg > 75 || t.side_px < 20) continue;
            bool ha = false, hb = false;
            for (const auto& m : fa) ha = ha || m.id == t.id;
            for (const auto& m : fb) hb = hb || m.id == t.id;
            if (ha == hb) continue;
            (ha ? lost : gained) += 1;
            std::printf(
                "%s: %s seed %llu image %d id %d side %.1f px angle %.1f deg centre (%.0f, %.0f); quads:",
                im.name.c_str(), ha ? "LOST" : "gained", static_cast<unsigned long long>(seed), i, t.id,
                t.side_px, t.view_angle_deg, 0.5 * (t.corners[0].x + t.corners[2].x),
                0.5 * (t.corners[0].y + t.corners[2].y));
            for (double level : {own.threshold_level, own.second_threshold_level, 0.25, 0.65}) {
              QuadSearch q;
              q.tile_px = own.threshold_tile_px, q.min_contrast = own.min_tile_contrast, q.levels = {level};
              q.min_perimeter = own.min_perimeter_px, q.max_deviation_rate = own.polygonal_approx_rate;
              q.min_side_rate = own.min_corner_distance_rate;
              std::printf(" %.2f: %.2f", level, NearestQuad(FindQuads(image, q), t.corners));
            }
            std::printf("\n");
            char name[256];
            std::snprintf(name, sizeof(name), "/tmp/recall_diag/own_s%llu_i%d.png",
                          static_cast<unsigned long long>(seed), i);
            mkdir("/tmp/recall_diag", 0755);
            cv::imwrite(name, image);
          }
        }
      }
  }
  std::printf("own search: lost %d, gained %d markers (>= 20 px, <= 75 deg) against opencv's\n", lost,
              gained);
  return 0;
}
}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: diag_recall CONDITION [images per cell] [DIR]\n");
    return 2;
  }
  if (std::strcmp(argv[1], "--cost") == 0) {
    auto dict = LoadDictionary("DICT_6X6_250");
    const std::vector<testing::Imaging> catalogue = testing::ImagingCatalogue();
    std::vector<std::vector<cv::Mat>> renders;  // per condition
    std::mt19937_64 rng(5);
    for (const testing::Imaging& im : catalogue) {
      renders.emplace_back();
      for (int i = 0; i < 4; ++i) {
        std::vector<testing::RenderedMarker> truth;
        renders.back().push_back(testing::RenderReference(*dict, testing::ReferenceScene(), im, rng, &truth));
      }
    }
    cv::setNumThreads(1);
    for (bool reread : {false, true, false, true}) {
      DetectorOptions o;
      o.reread_rejected = reread;
      double ms = 0;
      size_t images = 0, markers = 0;
      long long rereads = 0, rereads_found = 0;
      for (size_t c = 0; c < catalogue.size(); ++c) {
        MarkerDetector detector = testing::ReferenceDetector(catalogue[c], o);  // an inverted print's own
        timespec t0{}, t1{};
        clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t0);
        for (const cv::Mat& image : renders[c]) markers += detector.Detect(image).size();
        clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t1);
        ms += 1e3 * (t1.tv_sec - t0.tv_sec) + 1e-6 * (t1.tv_nsec - t0.tv_nsec);
        images += renders[c].size();
        rereads += detector.stats().rereads, rereads_found += detector.stats().rereads_found;
      }
      std::printf("reread_rejected %d: %.2f ms per image, %zu markers, %lld rereads (%lld markers)\n", reread,
                  ms / images, markers, rereads, rereads_found);
    }
    return 0;
  }
  if (std::strcmp(argv[1], "--own") == 0 && argc > 2)
    return CompareSearches(argv[2], argc > 3 ? std::atoi(argv[3]) : 3);
  const char* only = argv[1];
  const int images = argc > 2 ? std::atoi(argv[2]) : 3;
  const std::string dir = argc > 3 ? argv[3] : "/tmp/recall_diag";
  mkdir(dir.c_str(), 0755);
  cv::setNumThreads(1);
  auto dict = LoadDictionary("DICT_6X6_250");
  DetectorOptions options;
  // MCMT_DIAG_BROKEN_BORDER=0: without the broken-border search (detector option broken_border_window).
  if (std::getenv("MCMT_DIAG_BROKEN_BORDER"))
    options.broken_border_window = std::atoi(std::getenv("MCMT_DIAG_BROKEN_BORDER"));
  int dumped = 0, missed = 0, visible = 0;
  long long blur_quads = 0, blur_found = 0;
  const std::vector<testing::Imaging> catalogue = testing::ImagingCatalogue();
  for (size_t c = 0; c < catalogue.size(); ++c) {
    const testing::Imaging& im = catalogue[c];
    if (!std::strstr(im.name.c_str(), only)) continue;
    // MCMT_DIAG_TEST_SEED=s: the catalogue test's scene instead (15-60 px, 0-75 deg, `images` images
    // from seed s: ImagingCatalogueOnReferenceRenders is 8 images of seed 11).
    const char* test_seed = std::getenv("MCMT_DIAG_TEST_SEED");
    for (int s = 0; s < (test_seed ? 1 : 3); ++s)
      for (int g = 0; g < (test_seed ? 1 : 3); ++g) {
        testing::ReferenceScene scene = testing::BenchScene(s, g);
        uint64_t seed = testing::BenchSeed(static_cast<int>(c), s, g);
        if (test_seed) {
          scene = testing::ReferenceScene();
          scene.min_side_px = 15, scene.max_side_px = 60;
          seed = std::strtoull(test_seed, nullptr, 10);
        }
        MarkerDetector detector = testing::ReferenceDetector(im, options);
        std::mt19937_64 rng(seed);
        for (int i = 0; i < images; ++i) {
          std::vector<testing::RenderedMarker> truth;
          const cv::Mat image = testing::RenderReference(*dict, scene, im, rng, &truth);
          const DetectorStats before = detector.stats();
          const std::vector<marker_t> found = detector.Detect(image);
          bool any = false;
          for (const auto& t : truth) {
            if (t.view_angle_deg > 75 || t.side_px < 20) continue;
            ++visible;
            bool hit = false;
            for (const auto& m : found) hit = hit || m.id == t.id;
            if (hit) continue;
            ++missed;
            any = true;
            std::printf(
                "%s: seed %llu image %d id %d side %.1f px angle %.1f deg corner0 (%.1f, %.1f); image: %lld "
                "refinements failed, %lld dropped (a cell off)\n",
                im.name.c_str(), static_cast<unsigned long long>(seed), i, t.id, t.side_px, t.view_angle_deg,
                t.corners[0].x, t.corners[0].y, detector.stats().refine_failures - before.refine_failures,
                detector.stats().dropped - before.dropped);
            double perimeter = 0;
            for (int k = 0; k < 4; ++k) perimeter += cv::norm(t.corners[(k + 1) % 4] - t.corners[k]);
            std::printf("  own quads:");
            QuadSearch q;
            q.tile_px = options.threshold_tile_px, q.min_contrast = options.min_tile_contrast;
            q.min_perimeter = options.min_perimeter_px, q.max_deviation_rate = options.polygonal_approx_rate;
            q.min_side_rate = options.min_corner_distance_rate;
            for (double level : {0.25, 0.35, 0.5, 0.6, 0.65, 0.7, 0.75, 0.8, 0.85, 0.9}) {
              QuadFinder f(image, q);
              std::printf(" %.2f: %.2f", level, NearestQuad(f.Find(level), t.corners));
            }
            std::printf("\n  below mean:");
            for (int w : {5, 7, 9, 11, 15, 21})
              for (double off : {7.0, 3.0, 0.0, -3.0}) {
                QuadFinder f(image, q);
                std::printf(" w%d/%g: %.2f", w, off, NearestQuad(f.FindBelowMean(w, off), t.corners));
              }
            std::printf("\n");
            for (int w = options.adaptive_window_min; w <= options.adaptive_window_max;
                 w += options.adaptive_window_step) {
              cv::Mat thr;
              cv::adaptiveThreshold(image, thr, 255, cv::ADAPTIVE_THRESH_MEAN_C, cv::THRESH_BINARY_INV, w,
                                    options.adaptive_constant);
              std::vector<std::vector<cv::Point>> contours;
              cv::findContours(thr, contours, cv::RETR_LIST, cv::CHAIN_APPROX_NONE);
              // The contour whose points come nearest the true outline (mean of its best 4 distances).
              double best = 1e9;
              std::vector<cv::Point> best_poly;
              size_t best_size = 0;
              for (const auto& c : contours) {
                if (c.size() < 8) continue;
                std::vector<cv::Point> poly;
                cv::approxPolyDP(c, poly, c.size() * options.polygonal_approx_rate, true);
                double d = 1e9;
                if (poly.size() == 4) d = MeanCornerDistance(poly, t.corners);
                // Contours that are not quads: distance of the contour's bounding box centre.
                const cv::Rect box = cv::boundingRect(c);
                cv::Point2d centre(0, 0);
                for (const auto& k : t.corners) centre += 0.25 * k;
                const double dc =
                    cv::norm(cv::Point2d(box.x + box.width / 2.0, box.y + box.height / 2.0) - centre);
                const double score = poly.size() == 4 ? d : 100 + dc + std::abs(double(c.size()) - perimeter);
                if (score < best) best = score, best_poly = poly, best_size = c.size();
              }
              std::printf(
                  "  window %2d: nearest contour %zu px (true perimeter %.0f), polygon %zu vertices, %s "
                  "%.2f\n",
                  w, best_size, perimeter, best_poly.size(), best < 100 ? "quad corner error" : "score",
                  best);
              if (!any || true) {
                char name[256];
                std::snprintf(name, sizeof(name), "%s/s%llu_i%d_w%d.png", dir.c_str(),
                              static_cast<unsigned long long>(seed), i, w);
                if (dumped < 40) cv::imwrite(name, thr);
              }
            }
          }
          if (i + 1 == images)
            blur_quads += detector.stats().broken_border_quads,
                blur_found += detector.stats().broken_border_found;
          if (any && dumped < 40) {
            char name[256];
            std::snprintf(name, sizeof(name), "%s/s%llu_i%d.png", dir.c_str(),
                          static_cast<unsigned long long>(seed), i);
            cv::imwrite(name, image);
            ++dumped;
          }
        }
      }
  }
  std::printf(
      "missed %d of %d markers (>= 20 px, <= 75 deg); broken-border search: %lld quads read, %lld markers\n",
      missed, visible, blur_quads, blur_found);
  return 0;
}
