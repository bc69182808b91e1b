// Corner accuracy of mcmt's detector and of stock OpenCV ArUco on the independent reference renderer
// (tests/detector/reference_renderer.h): the imaging catalogue x marker sizes x view angles. Prints
// markdown tables: per condition (all sizes 15-60 px and angles 0-75 deg), per size band and per angle band,
// and small markers (10-15 px, cells below 2 px) per condition.
//   bench_accuracy [--quick | images per cell (default 8)] [condition name substring | all] [known | auto]
// "known": the detector is given each condition's gamma and sharpening (detector.gamma, unsharp_amount).
// "auto": they are estimated per condition (detector.tone auto, detector/tone.h) from 48 markers of
// renders of their own (seeds apart from the matrix's), printed, and given to the detector.
// With MCMT_CORNER_DUMP=FILE every corner mcmt found is written there (id x0 y0 ... x3 y3 per line), to
// compare two builds' corners marker by marker. MCMT_CANDIDATE_SEARCH=opencv|own: the detector's
// candidate_search. MCMT_IMAGING_OVERRIDE="motion_px=0,jpeg_quality=0": every condition with those Imaging
// fields set (ablations; the seeds stay the condition's).
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>

#include "tests/detector/accuracy.h"

using namespace mcmt;
using testing::Accuracy;

namespace {
void Row(const char* what, const Accuracy& a, const Accuracy& s) {
  std::printf("| %s | %+.3f | %.3f | %.3f | %.3f | %d | %+.3f | %.3f | %.3f | %.3f |\n", what, a.MeanOffset(),
              a.MedianError(), a.Recall60(), a.Recall75(), a.wrong_ids, s.MeanOffset(), s.MedianError(),
              s.Recall60(), s.Recall75());
  std::fflush(stdout);
}
const char* kHeader =
    "| %s | mcmt mean offset px | mcmt median error px | mcmt recall <60 deg | mcmt recall <75 deg | mcmt "
    "wrong ids | "
    "stock offset px | stock median px | stock recall <60 | stock recall <75 "
    "|\n|---|---|---|---|---|---|---|---|---|---|\n";
}  // namespace

int main(int argc, char** argv) {
  const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
  const int images = quick ? 2 : argc > 1 ? std::atoi(argv[1]) : 8;
  const char* only = argc > 2 && std::strcmp(argv[2], "all") != 0 ? argv[2] : nullptr;
  // "known": each condition's camera given to the detector as known (gamma, sharpening), not estimated.
  const bool known = argc > 3 && std::strcmp(argv[3], "known") == 0;
  const bool automatic = argc > 3 && std::strcmp(argv[3], "auto") == 0;
  cv::setNumThreads(1);
  const auto& sizes = testing::kBenchSides;
  const auto& angles = testing::kBenchAngles;
  std::printf("## Corner accuracy on the reference renderer (DICT_6X6_250, 640x480, %d images per cell)\n\n",
              images);
  std::printf(kHeader, "condition");
  Accuracy all, all_stock, by_size[3], by_size_stock[3], by_angle[3], by_angle_stock[3];
  std::vector<std::string> tones;  // "auto": each condition's estimate
  std::vector<std::pair<std::string, std::pair<Accuracy, Accuracy>>> small;  // per condition: mcmt, stock
  std::ofstream dump;
  if (const char* path = std::getenv("MCMT_CORNER_DUMP")) dump.open(path);
  dump.precision(10);
  std::vector<testing::Imaging> catalogue = testing::ImagingCatalogue();
  if (const char* spec = std::getenv("MCMT_IMAGING_OVERRIDE"))
    for (testing::Imaging& im : catalogue) testing::OverrideImaging(spec, &im);
  for (size_t c = 0; c < catalogue.size(); ++c) {
    const testing::Imaging& im = catalogue[c];
    if (only && !std::strstr(im.name.c_str(), only)) continue;
    Accuracy cond, cond_stock;
    DetectorOptions options;
    if (const char* search = std::getenv("MCMT_CANDIDATE_SEARCH")) options.candidate_search = search;
    if (known && im.gamma != 1.0) options.gamma = im.gamma;
    if (known && im.sharpen > 0) options.unsharp_amount = im.sharpen, options.unsharp_sigma = 1.0;
    if (automatic) {
      const ToneEstimate tone = testing::EstimateToneOnReference(im, 48, 5000 + c);
      tone.Apply(&options);
      tones.push_back(im.name + ": " + tone.Describe());
    }
    for (int s = 0; s < 3; ++s)
      for (int g = 0; g < 3; ++g) {
        const testing::ReferenceScene scene = testing::BenchScene(s, g);
        const uint64_t seed = testing::BenchSeed(static_cast<int>(c), s, g);
        Accuracy stock;
        std::vector<marker_t> found;
        const Accuracy a =
            testing::MeasureReference("DICT_6X6_250", scene, im, options, images, seed, &stock, &found);
        for (const marker_t& m : found) {
          dump << m.id;
          for (int k = 0; k < 4; ++k) dump << ' ' << m.corners[k][0] << ' ' << m.corners[k][1];
          dump << '\n';
        }
        cond.Add(a), cond_stock.Add(stock), by_size[s].Add(a), by_size_stock[s].Add(stock);
        by_angle[g].Add(a), by_angle_stock[g].Add(stock);
      }
    Row(im.name.c_str(), cond, cond_stock);
    all.Add(cond), all_stock.Add(cond_stock);
    Accuracy sm, sm_stock;
    for (int g = 0; g < 3; ++g) {
      Accuracy stock;
      sm.Add(testing::MeasureReference("DICT_6X6_250", testing::SmallScene(g), im, options, images,
                                       testing::SmallSeed(static_cast<int>(c), g), &stock));
      sm_stock.Add(stock);
    }
    small.push_back({im.name, {sm, sm_stock}});
  }
  Row("**all**", all, all_stock);
  std::printf("\n");
  std::printf(kHeader, "marker side");
  for (int s = 0; s < 3; ++s) {
    char what[64];
    std::snprintf(what, sizeof(what), "%.0f-%.0f px", sizes[s][0], sizes[s][1]);
    Row(what, by_size[s], by_size_stock[s]);
  }
  std::printf("\n");
  std::printf(kHeader, "view angle");
  for (int g = 0; g < 3; ++g) {
    char what[64];
    std::snprintf(what, sizeof(what), "%.0f-%.0f deg", angles[g][0], angles[g][1]);
    Row(what, by_angle[g], by_angle_stock[g]);
  }
  std::printf(
      "\nRecall counts markers of 20 px and more; offsets and errors every marker found (15-60 px).\n");
  std::printf("\n#### Small markers (%.0f-%.0f px, 0-75 deg, %d images per angle band)\n\n",
              testing::kSmallSides[0], testing::kSmallSides[1], images);
  std::printf(
      "| condition | mcmt mean offset px | mcmt median error px | mcmt found | mcmt wrong ids | stock offset "
      "px "
      "| stock median px | stock found |\n|---|---|---|---|---|---|---|---|\n");
  Accuracy small_all, small_all_stock;
  auto small_row = [](const std::string& what, const Accuracy& a, const Accuracy& s) {
    std::printf("| %s | %+.3f | %.3f | %d/%d | %d | %+.3f | %.3f | %d/%d |\n", what.c_str(), a.MeanOffset(),
                a.MedianError(), a.found_small, a.visible_small, a.wrong_ids, s.MeanOffset(), s.MedianError(),
                s.found_small, s.visible_small);
  };
  for (const auto& [name, acc] : small) {
    small_row(name, acc.first, acc.second);
    small_all.Add(acc.first), small_all_stock.Add(acc.second);
  }
  small_row("**all**", small_all, small_all_stock);
  if (!tones.empty()) std::printf("\n#### Estimated tone (detector.tone auto, 48 markers per condition)\n\n");
  for (const std::string& t : tones) std::printf("- %s\n", t.c_str());
  return 0;
}
