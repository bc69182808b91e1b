// The accuracy matrix: the detector's corners on the independent reference renderer
// (tests/detector/reference_renderer.h, no code shared with sim/render.cc) over the imaging catalogue x
// marker sizes (15-60 px) x view angles (0-75 deg), a sample of the matrix bench_accuracy runs in full;
// and the same detector on mcmt_sim's renders, so that neither renderer alone vouches for the corners.
//
// The targets: |mean signed offset along the edge normals| <= 0.02 px, median corner error
// <= 0.10 px, no wrong id, recall >= 0.99 below 60 deg and >= 0.90 below 75 deg (markers >= 20 px).
// Conditions that do not meet them yet are asserted at the bounds they reach today, named in kShortfalls
// (a regression guard, not a target): see docs/detector.md.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "tests/detector/accuracy.h"
#include "tests/detector/sim_eval.h"

namespace mcmt {
namespace {

struct Bounds {
  double offset = 0.02, median = 0.10, recall60 = 0.99, recall75 = 0.90;
};

// Measured shortfalls (8 images per condition, seed 11), asserted at what they reach. Candidates are
// no longer lost on narrow margins (min_marker_distance_rate: OpenCV decoded only the margin's quad)
// nor on blur (reread_rejected): recall below 60 deg is 1.000 in every condition (it was 0.0-0.96 on
// the half-cell margins, 0.95 under blur). A side whose fitted margin has the border's level is refitted
// with one surround level, and margins are modelled down to 0.2 cells (side_model.h): no margin
// -0.043 -> +0.008 px, hard -0.081 -> -0.052, wood -0.028 -> -0.021. Still short: recall at 60-75 deg
// under blur and gamma (the code's cells ~1 px across under 1.2 px blur), and offsets where a half-cell
// margin on a black tool, or sharpening + JPEG leave edges the side model does not fit yet.
// Side fits of the wrong polarity (the border's level brighter than the code's: a code row taken for the
// border) are retried a cell outward or dropped (side_model.h): webcam -0.038 -> -0.024 px; what is left
// is one marker (27 px, 68 deg) whose kept-line side moves ~1 px outward every model pass until the
// corners pass the refinement's limit and cornerSubPix takes it (-0.75 px). Recall below 75 deg of the
// black tool and webcam (0.846, 0.897) is what main measured at 9781c6a (its bounds 0.87 and 0.92 failed).
// A side whose crossings lie on the code's edge is turned by the model, and an edge beyond the profiles'
// middle is re-profiled about it (DetectorAccuracy.SideOnTheCodesEdgeIsTurned): webcam -0.024 -> -0.012
// px, recall <75 deg 0.897 -> 0.923. No margin (+0.009 / 0.076 / 1.000), wood (-0.015 / 0.062 / 0.974)
// and webcam (-0.012 / 0.085 / 0.923) now meet the targets and are asserted at them; bounds tightened to
// what is measured: black tool -0.043 / 0.060 / 0.846, hard -0.052 / 0.168 / 0.947.
// (A paper-margin refit, bench/results/2026-12-05-margin.md, reached hard -0.012 / 0.142 px but made the
// maps of an independent renderer of the paper's rig worse: MapperReferenceRenders. Not applied.)
// Codes whose cells are about as narrow as the blur are read from their cells' levels unmixed
// (DetectorAccuracy.CellsAsNarrowAsTheBlurAreRead): recall <75 deg blur 0.74 -> 0.829, gamma 0.88 -> 0.971
// (now meets the targets: -0.002 / 0.043 / 1.000), hard 0.947 -> 1.000. Blur's markers still lost at
// 60-75 deg have no candidate quad (their thin blurred border breaks where white cells touch it); the
// black tool's neither (the half-cell margin under blur joins the border to the dark surface).
// A two-level margin whose far side lies beyond the profiles' outer end is refitted with one surround
// level (side_model.cc FitSideModels; 2026-12-05 evening): hard -0.043 -> -0.035 px (bound 0.06 -> 0.04).
// Added to the catalogue (bench/results/2026-12-06-catalogue.md): an inverted print meets the targets
// (-0.003 / 0.045 / 1.000 / 1.000); a half-cell margin on a dark grey surface (0.15, inside the margin
// penalty's surround gate) misses them like the black tool: -0.035 / 0.047 / 1.000 / 0.846.
// Their markers lost at 60-75 deg had a candidate: the dark card's outline around the marker, whose
// half-cell margin the view made too thin to part the border from the card at the adaptive threshold.
// Such a rejected candidate is now searched inside at low levels of the local range (detector option
// inside_rejected_level): black tool -0.015 / 0.049 / 1.000 / 0.872 -> -0.012 / 0.050 / 1.000 / 0.949,
// dark grey -0.017 / 0.047 / 1.000 / 0.846 -> -0.013 / 0.048 / 1.000 / 0.923: both meet the targets now
// and are asserted at them.
// Blur's markers lost at 60-75 deg (no candidate quad: the border broken where white cells touch it) are
// searched for on blurred frames below the local mean plus 3 grey levels (detector option
// broken_border_window; DetectorAccuracy.BlurredBordersBrokenByWhiteCellsAreFound): blur 1.2 -0.005 /
// 0.054 / 1.000 / 0.829 -> -0.019 / 0.070 / 1.000 / 0.971, now meeting the targets (asserted at them);
// defocus recall <75 0.971 -> 1.000, gamma 0.971 -> 1.000 (offset -0.007 -> -0.008 px).
const std::map<std::string, Bounds>& Shortfalls() {
  static const std::map<std::string, Bounds> s = {
      {"hard", {0.04, 0.18, 0.99, 1.00}},
      // No margin on a grey surface met the 0.02 px offset only because two markers of its first image (ids
      // 123 and 240, 16-20 px at 67-69 deg) fell back to cornerSubPix, up to 1.63 px inward: +0.008 px.
      // Refined (SmoothedRefinementACellOffIsRefinedUnsmoothed) the condition shows its own outward bias,
      // +0.022 px (median 0.058 -> 0.054 px): a shortfall (bench/results/2026-12-07-id123.md).
      {"no margin, grey surface", {0.025, 0.10, 0.99, 0.90}},
  };
  return s;
}

// The reference renderer's sharpening amount: positive sharpens an edge (overshoot beside it), negative
// blurs it (the pixels beside the edge move toward its other side). A negative amount used to be ignored
// (the image was the unsharpened one, byte for byte; found by cam1width).
TEST(ReferenceRenderer, SharpeningAmountOfEitherSign) {
  cv::Mat linear(8, 16, CV_64F, cv::Scalar(40.0));
  linear.colRange(8, 16).setTo(200.0);
  auto render = [&](double amount) {
    testing::Imaging im;
    im.read_noise = 0, im.sharpen = amount;
    std::mt19937_64 rng(1);
    return testing::reference::CameraPipeline(linear.clone(), im, rng);
  };
  const cv::Mat none = render(0), sharp = render(0.6), soft = render(-0.6);
  // Row 4, the columns each side of the step (7 dark, 8 bright).
  EXPECT_LT(sharp.at<uint8_t>(4, 7), none.at<uint8_t>(4, 7));
  EXPECT_GT(sharp.at<uint8_t>(4, 8), none.at<uint8_t>(4, 8));
  EXPECT_GT(soft.at<uint8_t>(4, 7), none.at<uint8_t>(4, 7) + 10);
  EXPECT_LT(soft.at<uint8_t>(4, 8) + 10, none.at<uint8_t>(4, 8));
}

// The benches' MCMT_IMAGING_OVERRIDE: the named fields take the values, the name records them, the
// rest of the condition stays; an unknown field or a value that is no number throws.
TEST(ReferenceRenderer, OverrideSetsTheNamedFields) {
  testing::Imaging im = testing::CatalogueCondition("hard");
  const testing::Imaging hard = im;
  testing::OverrideImaging("margin_cells=1,jpeg_quality=0,sharpen_linear=1", &im);
  EXPECT_EQ(im.margin_cells, 1.0);
  EXPECT_EQ(im.jpeg_quality, 0);
  EXPECT_TRUE(im.sharpen_linear);
  EXPECT_EQ(im.surface_texture, hard.surface_texture);
  EXPECT_EQ(im.motion_px, hard.motion_px);
  EXPECT_EQ(im.name, "hard [margin_cells=1] [jpeg_quality=0] [sharpen_linear=1]");
  EXPECT_THROW(testing::OverrideImaging("margin=1", &im), std::invalid_argument);
  EXPECT_THROW(testing::OverrideImaging("gamma=two", &im), std::invalid_argument);
  EXPECT_THROW(testing::OverrideImaging("gamma", &im), std::invalid_argument);
}

// The catalogue's inverted print is what ArUco calls an inverted marker: stock OpenCV decodes its
// markers with detectInvertedMarker, none without, and its corners are as close to the truth as on the
// plain print of the same scenes (its contours run on the dark pixels: inside a plain marker's border,
// offset -0.43 px, median error 0.72 px; outside an inverted one's, +0.12 / 0.56 px). Before, the renderer
// printed an inverted marker's margin white like its border, which left the border no edge: stock
// OpenCV found none of the markers.
TEST(ReferenceRenderer, InvertedPrintIsArucosInvertedMarker) {
  testing::Imaging inverted;
  for (const testing::Imaging& im : testing::ImagingCatalogue())
    if (im.inverted) inverted = im;
  ASSERT_TRUE(inverted.inverted);
  testing::Imaging plain = inverted;
  plain.inverted = false;
  auto dict = LoadDictionary("DICT_6X6_250");
  testing::ReferenceScene scene;
  scene.min_side_px = 30, scene.max_side_px = 60, scene.max_angle_deg = 45;
  struct Found {
    int markers = 0, found = 0, found_other = 0;  // found_other: with the other polarity's search
    double worst_px = 0;
    testing::CornerErrors corners;
  };
  // Stock OpenCV on 4 renders of `print` (the same scenes for either print: the same seed).
  auto stock = [&](const testing::Imaging& print) {
    std::mt19937_64 rng(3);
    Found f;
    for (int i = 0; i < 4; ++i) {
      std::vector<testing::RenderedMarker> truth;
      const cv::Mat image = testing::RenderReference(*dict, scene, print, rng, &truth);
      f.markers += static_cast<int>(truth.size());
      f.found_other += static_cast<int>(testing::StockDetect(image, dict, !print.inverted).size());
      for (const marker_t& m : testing::StockDetect(image, dict, print.inverted))
        for (const testing::RenderedMarker& t : truth) {
          if (t.id != m.id) continue;
          ++f.found;
          testing::AddCornerErrors(t, testing::CornersOf(m), &f.corners);
          for (int k = 0; k < 4; ++k)
            f.worst_px = std::max(
                f.worst_px, std::hypot(m.corners[k][0] - t.corners[k].x, m.corners[k][1] - t.corners[k].y));
        }
    }
    return f;
  };
  const Found a = stock(inverted), b = stock(plain);
  std::printf(
      "stock OpenCV, %d inverted markers: %d found with detectInvertedMarker (corners within %.2f px, "
      "offset %+.3f px, median %.3f px), %d without; the plain print: %d found (within %.2f px, offset "
      "%+.3f px, median %.3f px)\n",
      a.markers, a.found, a.worst_px, testing::MeanOf(a.corners.offsets), testing::MedianOf(a.corners.errors),
      a.found_other, b.found, b.worst_px, testing::MeanOf(b.corners.offsets),
      testing::MedianOf(b.corners.errors));
  EXPECT_GE(a.markers, 16);
  EXPECT_EQ(a.found, a.markers);
  EXPECT_EQ(a.found_other, 0);
  EXPECT_LE(std::abs(testing::MeanOf(a.corners.offsets)), 0.5);
  EXPECT_LE(testing::MedianOf(a.corners.errors), testing::MedianOf(b.corners.errors));
}

TEST(DetectorAccuracy, ImagingCatalogueOnReferenceRenders) {
  testing::Accuracy all;
  for (const testing::Imaging& im : testing::ImagingCatalogue()) {
    testing::ReferenceScene scene;
    scene.min_side_px = 15, scene.max_side_px = 60;
    const testing::Accuracy a =
        testing::MeasureReference("DICT_6X6_250", scene, im, DetectorOptions(), 8, 11);
    std::printf("%-30s offset %+.3f px median %.3f px recall60 %.3f recall75 %.3f wrong %d (%zu corners)\n",
                im.name.c_str(), a.MeanOffset(), a.MedianError(), a.Recall60(), a.Recall75(), a.wrong_ids,
                a.corners.errors.size());
    const auto it = Shortfalls().find(im.name);
    const Bounds b = it == Shortfalls().end() ? Bounds() : it->second;
    EXPECT_EQ(a.wrong_ids, 0) << im.name;
    if (b.offset < 1e8) {
      ASSERT_GT(a.corners.errors.size(), 40u) << im.name;
      EXPECT_LE(std::abs(a.MeanOffset()), b.offset) << im.name;
      EXPECT_LE(a.MedianError(), b.median) << im.name;
    }
    EXPECT_GE(a.Recall60(), b.recall60) << im.name;
    EXPECT_GE(a.Recall75(), b.recall75) << im.name;
    if (it == Shortfalls().end()) all.Add(a);
  }
  // Every condition that meets the targets, together.
  EXPECT_LE(std::abs(all.MeanOffset()), 0.02);
  EXPECT_LE(all.MedianError(), 0.10);
}

// A camera whose gamma and sharpening are known (detector.gamma, unsharp_amount: the renderer's unsharp
// mask of encoded values, sigma 1 px) given to the detector instead of the per-side gamma fit: on the
// webcam and gamma conditions the corners meet the targets and are not worse than with the fit.
TEST(DetectorAccuracy, KnownCameraOnReferenceRenders) {
  for (const testing::Imaging& im : testing::ImagingCatalogue()) {
    if (im.name != "webcam" && im.name != "gamma 2.2") continue;
    testing::ReferenceScene scene;
    scene.min_side_px = 15, scene.max_side_px = 60;
    DetectorOptions known;
    known.gamma = im.gamma, known.unsharp_amount = im.sharpen, known.unsharp_sigma = 1.0;
    const testing::Accuracy fitted =
        testing::MeasureReference("DICT_6X6_250", scene, im, DetectorOptions(), 8, 11);
    const testing::Accuracy a = testing::MeasureReference("DICT_6X6_250", scene, im, known, 8, 11);
    std::printf(
        "%-12s known: offset %+.3f px median %.3f px recall75 %.3f (%zu corners); fitted: %+.3f / %.3f / "
        "%.3f\n",
        im.name.c_str(), a.MeanOffset(), a.MedianError(), a.Recall75(), a.corners.errors.size(),
        fitted.MeanOffset(), fitted.MedianError(), fitted.Recall75());
    EXPECT_EQ(a.wrong_ids, 0) << im.name;
    ASSERT_GT(a.corners.errors.size(), 40u) << im.name;
    EXPECT_LE(std::abs(a.MeanOffset()), 0.02) << im.name;
    EXPECT_LE(a.MedianError(), std::min(0.10, fitted.MedianError() + 0.005)) << im.name;
    EXPECT_GE(a.Recall75(), fitted.Recall75() - 0.01) << im.name;
  }
}

// No wrong id on images without a dictionary marker: squares of random code patterns (every one at
// least 7 bits from every id of the dictionary in every rotation: outside the correction margin)
// printed like markers, on plain, wood-grain and dark surfaces, under the catalogue's imaging, where
// the candidate search's relaxed grouping (min_marker_distance_rate) tries more candidates than
// OpenCV's default does.
TEST(DetectorAccuracy, NoWrongIdsOnPatternsOutsideTheDictionary) {
  auto dict = LoadDictionary("DICT_6X6_250");
  std::mt19937_64 rng(17);
  std::vector<cv::Mat> patterns;
  while (patterns.size() < 250) {
    cv::Mat bits(dict->markerSize, dict->markerSize, CV_8U);
    for (int i = 0; i < bits.rows * bits.cols; ++i) bits.at<uint8_t>(i) = rng() & 1;
    int nearest = 1000;
    for (int id = 0; id < dict->bytesList.rows; ++id)
      nearest = std::min(nearest, dict->getDistanceToId(bits, id));
    if (nearest >= 7) patterns.push_back(cv::aruco::Dictionary::getByteListFromBits(bits));
  }
  cv::Mat bytes;
  cv::vconcat(patterns, bytes);
  const cv::aruco::Dictionary fake(bytes, dict->markerSize, 0);
  int stock_detections = 0, squares = 0;
  // Both candidate searches (DetectorOptions::candidate_search) on the same renders.
  DetectorOptions own;
  own.candidate_search = "own";
  for (const testing::Imaging& im : testing::ImagingCatalogue()) {
    MarkerDetector detector = testing::ReferenceDetector(im),
                   own_detector = testing::ReferenceDetector(im, own);
    testing::ReferenceScene scene;
    scene.min_side_px = 15, scene.max_side_px = 80, scene.markers = 12;
    int detections = 0, own_detections = 0;
    for (int i = 0; i < 4; ++i) {
      std::vector<testing::RenderedMarker> truth;
      const cv::Mat image = testing::RenderReference(fake, scene, im, rng, &truth);
      squares += static_cast<int>(truth.size());
      detections += static_cast<int>(detector.Detect(image).size());
      own_detections += static_cast<int>(own_detector.Detect(image).size());
      stock_detections += static_cast<int>(testing::StockDetect(image, dict, im.inverted).size());
    }
    EXPECT_EQ(detections, 0) << im.name;
    EXPECT_EQ(own_detections, 0) << im.name << " (candidate_search own)";
  }
  std::printf("%d squares of non-dictionary patterns: stock OpenCV found %d markers\n", squares,
              stock_detections);
  EXPECT_GT(squares, 400);
}

// candidate_search "own" (detector/candidates.h): no wrong ids under any imaging condition of the
// catalogue, and the recall it measured (4 images per condition: 1.000 / 0.934; bench_accuracy 3: <60
// deg 0.999, <75 deg 0.971, against 0.999 / 0.970 with "opencv": it still loses a few webcam markers at
// 70-75 deg, 0.942 against 0.967, hence not the default). With codes read from unmixed cell levels where
// their centres do not read (ReadCode): 1.000 / 0.959 here; bench_accuracy 3 1.000 / 0.985 (opencv
// 1.000 / 0.984), webcam still 0.950 against 0.967, no margin's offset +0.035 px against +0.019.
TEST(DetectorAccuracy, OwnCandidateSearchOnReferenceRenders) {
  DetectorOptions o;
  o.candidate_search = "own";
  testing::Accuracy all;
  for (const testing::Imaging& im : testing::ImagingCatalogue()) {
    testing::ReferenceScene scene;
    scene.min_side_px = 15, scene.max_side_px = 60;
    const testing::Accuracy a = testing::MeasureReference("DICT_6X6_250", scene, im, o, 4, 11);
    std::printf("%-30s offset %+.3f px median %.3f px recall60 %.3f recall75 %.3f wrong %d\n",
                im.name.c_str(), a.MeanOffset(), a.MedianError(), a.Recall60(), a.Recall75(), a.wrong_ids);
    EXPECT_EQ(a.wrong_ids, 0) << im.name;
    all.Add(a);
  }
  std::printf("all: recall60 %.3f recall75 %.3f\n", all.Recall60(), all.Recall75());
  EXPECT_GE(all.Recall60(), 0.99);  // measured 1.000
  EXPECT_GE(all.Recall75(), 0.95);  // measured 0.959 (0.934 before unmixed reads)
}

// Image `image` (from 0) of bench_accuracy's cell (side band, angle band) of the catalogue's condition
// named `condition`, and its markers' truth; an empty image if no condition has that name.
cv::Mat BenchImage(const cv::aruco::Dictionary& dict, const std::string& condition, int side_band,
                   int angle_band, int image, std::vector<testing::RenderedMarker>* truth) {
  const std::vector<testing::Imaging> catalogue = testing::ImagingCatalogue();
  size_t c = 0;
  while (c < catalogue.size() && catalogue[c].name != condition) ++c;
  if (c == catalogue.size()) return cv::Mat();
  std::mt19937_64 rng(testing::BenchSeed(static_cast<int>(c), side_band, angle_band));
  cv::Mat out;
  for (int i = 0; i <= image; ++i)
    out =
        testing::RenderReference(dict, testing::BenchScene(side_band, angle_band), catalogue[c], rng, truth);
  return out;
}

// Markers the own candidate search lost and OpenCV's found (bench_accuracy's renders, build/bench/
// diag_recall --own): a half-cell margin on a black tool at 57 deg, whose blurred margin is dark at the
// range's levels 0.5 and 0.35 (found at 0.25); a 35 px marker at 70 deg under 1.2 px blur, whose border
// breaks at the mid level where white cells touch it (found at 0.65); a webcam marker at 66 deg, found
// only below the local mean (mean_window_px) and read with border cells wrong. Before (levels 0.5 and
// 0.35, one border cell wrong at most) none was found. A 20 px marker at 51 deg under 1.2 px blur (quad at
// 0.65 within 0.43 px) and a webcam marker at 68 deg (below the mean) read with 8 and 7 of the 28 border
// cells bright: lost while 6 were allowed.
TEST(DetectorAccuracy, OwnCandidateSearchFindsThinMarginsAndBlurredBorders) {
  struct Case {
    std::string condition;
    int side_band, angle_band, image, id;
  };
  const std::vector<Case> cases = {{"half-cell margin, black tool", 1, 1, 0, 145},
                                   {"gaussian blur 1.2", 2, 2, 0, 209},
                                   {"webcam", 1, 2, 0, 230},
                                   {"gaussian blur 1.2", 0, 1, 1, 158},
                                   {"webcam", 1, 2, 2, 229}};
  auto dict = LoadDictionary("DICT_6X6_250");
  MarkerConfig mc;
  mc.dictionary = "DICT_6X6_250";
  DetectorOptions own;
  own.candidate_search = "own";
  for (const Case& k : cases) {
    std::vector<testing::RenderedMarker> truth;
    const cv::Mat image = BenchImage(*dict, k.condition, k.side_band, k.angle_band, k.image, &truth);
    ASSERT_FALSE(image.empty()) << k.condition;
    MarkerDetector detector(mc, own);
    bool found = false;
    for (const marker_t& m : detector.Detect(image)) found = found || m.id == k.id;
    EXPECT_TRUE(found) << k.condition << " id " << k.id;
  }
}

// An inverted print is searched as dark-bordered markers of the negated image, where its black margin
// is a white one. With OpenCV's grouping at its default 0.05 there (kept for detectInvertedMarker) this 51
// px marker at 32 deg (bench_accuracy's inverted print, 40-60 px, 0-40 deg, image 0) was lost, as stock
// OpenCV's plain search loses it on the negated image (likely its margin's quad taken for it:
// min_marker_distance_rate); mcmt's plain search on the negated image and stock OpenCV's
// detectInvertedMarker found it. The negated search now groups as the plain one does.
TEST(DetectorAccuracy, InvertedPrintsMarginIsNotTheMarker) {
  auto dict = LoadDictionary("DICT_6X6_250");
  testing::Imaging inverted;
  for (const testing::Imaging& im : testing::ImagingCatalogue())
    if (im.inverted) inverted = im;
  std::vector<testing::RenderedMarker> truth;
  const cv::Mat image = BenchImage(*dict, inverted.name, 2, 0, 0, &truth);
  ASSERT_FALSE(image.empty());
  bool found = false;
  for (const marker_t& m : testing::ReferenceDetector(inverted).Detect(image)) found = found || m.id == 73;
  EXPECT_TRUE(found);
}

// The corner errors of marker `id` among `found` against its truth (none where it was not found).
testing::CornerErrors ErrorsOfId(const std::vector<marker_t>& found,
                                 const std::vector<testing::RenderedMarker>& truth, int id) {
  testing::CornerErrors e;
  for (const marker_t& m : found)
    for (const auto& t : truth)
      if (m.id == id && t.id == id) testing::AddCornerErrors(t, testing::CornersOf(m), &e);
  return e;
}

// The largest |x| of `v` (0 when empty).
double MaxAbsOf(const std::vector<double>& v) {
  double worst = 0;
  for (double x : v) worst = std::max(worst, std::abs(x));
  return worst;
}

// Markers whose code cells are about as narrow as the blur (bench_accuracy's renders, build/bench/
// diag_recall): under 1.2 px Gaussian blur at 59-71 deg (21-24 px, cells of 1.5-2.5 px across) OpenCV's
// candidate, refined by mid-level crossings, read 3-8 inner bits and up to 13 border cells wrong at the
// cells' centres (so did the true corners). Their levels unmixed under a model of the blur (ReadCode,
// DeconvolvedCells) read 0-3 wrong. Before, none of these was found (recall <60 deg 0.988). Their corners:
// offsets within 0.2 px except id 84's (a thin rhombus at 71 deg: -0.57 to +0.51 px, corners up to 1.76 px
// along its long diagonal; the refinement's, not the read's).
TEST(DetectorAccuracy, CellsAsNarrowAsTheBlurAreRead) {
  struct Case {
    int side_band, angle_band, image, id;
  };
  const std::vector<Case> cases = {{1, 1, 1, 66}, {1, 2, 0, 189}, {1, 2, 1, 84}, {1, 2, 1, 149}};
  auto dict = LoadDictionary("DICT_6X6_250");
  MarkerConfig mc;
  mc.dictionary = "DICT_6X6_250";
  for (const Case& k : cases) {
    std::vector<testing::RenderedMarker> truth;
    const cv::Mat image = BenchImage(*dict, "gaussian blur 1.2", k.side_band, k.angle_band, k.image, &truth);
    ASSERT_FALSE(image.empty());
    MarkerDetector detector(mc, DetectorOptions());
    const testing::CornerErrors e = ErrorsOfId(detector.Detect(image), truth, k.id);
    ASSERT_EQ(e.errors.size(), 4u) << "id " << k.id << " not found";
    const double worst = MaxAbsOf(e.errors), worst_offset = MaxAbsOf(e.offsets);
    std::printf("id %d: largest corner error %.2f px, largest offset %.3f px\n", k.id, worst, worst_offset);
    EXPECT_LE(worst, 2.0) << "id " << k.id;
    EXPECT_LE(worst_offset, 0.6) << "id " << k.id;
    EXPECT_GE(detector.stats().deconvolved_reads, 1) << "id " << k.id;
  }
}

// Markers whose thin blurred border breaks where the code's white cells touch it (the catalogue test's
// renders: 1.2 px Gaussian blur, seed 11, 22-29 px at 67-75 deg; build/bench/diag_recall with
// MCMT_DIAG_TEST_SEED=11). At OpenCV's adaptive threshold (windows 5 and 15, dark below the mean less 7)
// the nearest contour was 12-101 px long against perimeters of 89-117 and never a quad near the marker;
// at the own search's levels of the local range (0.25-0.9) only ids 24 and 33 had one within 2 px
// (0.6-0.65). Dark below the mean of 5 px plus 3 (the broken-border search on blurred frames, detector
// option broken_border_window) the border stays whole: quads within 0.5-1.7 px of the true corners, read
// as rejected candidates are. Before, none was found; now all 5, corners within 1.6 px (largest offsets
// 0.13-0.61 px: steep and blurred, cells ~1.5 px across).
TEST(DetectorAccuracy, BlurredBordersBrokenByWhiteCellsAreFound) {
  const testing::Imaging im = testing::CatalogueCondition("gaussian blur 1.2");
  auto dict = LoadDictionary("DICT_6X6_250");
  MarkerConfig mc;
  mc.dictionary = "DICT_6X6_250";
  testing::ReferenceScene scene;
  scene.min_side_px = 15, scene.max_side_px = 60;
  std::mt19937_64 rng(11);
  const std::map<int, std::vector<int>> lost = {{0, {184}}, {1, {24}}, {3, {166}}, {4, {33, 132}}};
  int found = 0;
  long long read = 0, read_found = 0;
  for (int i = 0; i <= 4; ++i) {
    std::vector<testing::RenderedMarker> truth;
    const cv::Mat image = testing::RenderReference(*dict, scene, im, rng, &truth);
    if (!lost.count(i)) continue;
    MarkerDetector detector(mc, DetectorOptions());
    const std::vector<marker_t> markers = detector.Detect(image);
    for (int id : lost.at(i)) {
      const testing::CornerErrors e = ErrorsOfId(markers, truth, id);
      EXPECT_EQ(e.errors.size(), 4u) << "image " << i << " id " << id << " not found";
      if (e.errors.size() != 4u) continue;
      ++found;
      const double worst = MaxAbsOf(e.errors), worst_offset = MaxAbsOf(e.offsets);
      std::printf("image %d id %d: largest corner error %.2f px, largest offset %.3f px\n", i, id, worst,
                  worst_offset);
      EXPECT_LE(worst, 2.0) << "id " << id;
    }
    EXPECT_GE(detector.stats().broken_border_found, 1) << "image " << i;
    read += detector.stats().broken_border_quads, read_found += detector.stats().broken_border_found;
  }
  EXPECT_EQ(found, 5);
  // Only quads whose border is darker than the ring just outside them by 20 grey levels are read
  // (kBrokenBorderDepth): these four images' search read 18 quads for its 5 markers on 8968f3f, 5 now.
  std::printf("broken-border search: %lld quads read, %lld markers\n", read, read_found);
  EXPECT_LE(read, read_found + 1);
}

// A side whose crossings lie on the code's edge along part of it (a 27 px marker at 68 deg under the
// webcam condition, image 5 of the accuracy test's seed 11: its left side's candidate line is turned by
// about 5 px over 31 px, its crossings mix the border-to-code edge in, their levels are in the wrong order
// for the print's polarity). The side model turns the line (each half of the side's rays fitted about the
// whole side's edge), and an edge found beyond the profiles' middle is sampled again about it. Before,
// the corners walked out of the refinement's reach and cornerSubPix took the marker: mean offset -0.75
// px, largest corner error 1.98 px; now -0.22 / 0.77 px (the target, 0.1 px, is not met: its other
// sides sit 0.3-0.6 px off under the sharpening, which the side model does not model).
TEST(DetectorAccuracy, SideOnTheCodesEdgeIsTurned) {
  const testing::Imaging im = testing::CatalogueCondition("webcam");
  auto dict = LoadDictionary("DICT_6X6_250");
  MarkerConfig mc;
  mc.dictionary = "DICT_6X6_250";
  MarkerDetector detector(mc, DetectorOptions());
  testing::ReferenceScene scene;
  scene.min_side_px = 15, scene.max_side_px = 60;
  std::mt19937_64 rng(11);
  for (int i = 0; i <= 5; ++i) {
    std::vector<testing::RenderedMarker> truth;
    const cv::Mat image = testing::RenderReference(*dict, scene, im, rng, &truth);
    const std::vector<marker_t> found = detector.Detect(image);
    if (i < 5) continue;
    const testing::CornerErrors e = ErrorsOfId(found, truth, 108);
    ASSERT_EQ(e.errors.size(), 4u) << "id 108 not found";
    const double worst = MaxAbsOf(e.errors);
    std::printf("id 108: offset %+.3f px, largest corner error %.3f px\n", testing::MeanOf(e.offsets), worst);
    EXPECT_LE(std::abs(testing::MeanOf(e.offsets)), 0.3);
    EXPECT_LE(worst, 0.9);
  }
}

// Steep views keep their shape (issue 15): markers of the paper's rig's size (20-25 px head-on) at 65-75
// deg, plain prints, detected with the defaults; each marker's long and short diagonal against the truth.
// With the sides' directions from their crossings alone, the line of each side turned its end at the
// quad's acute angle inward (the perpendicular side's border and margin within the blur there): the long
// diagonal came out short and the short one long (these 83 markers: mean -0.34 / +1.49 %; such errors set
// each steep view's distance and so the map's scale: MapperReferenceRenders). The model turns the sides of
// skewed quads (SkewTurnWeight in detector.cc): +0.079 / +0.711 %. Bounds: the long diagonal within 0.25 %,
// the short one within 0.7 % of the long one's error (the quad's shape).
// The shape figure sits at its bound (0.00698 at 991ff95) and is not stable in the last bits: the
// candidates moved by 1e-9 px flip some side fits (bench/results/2026-12-07-fullsettle.md) and take it to
// 0.00742 (-1e-9 px). A change that moves it across 0.007 by such a flip is not a worse shape; show that
// with the perturbation probe (2026-12-07-fullsettle-probe.patch) before moving the bound.
TEST(DetectorAccuracy, SteepViewsKeepTheirDiagonals) {
  auto dict = LoadDictionary("DICT_6X6_250");
  MarkerConfig mc;
  mc.dictionary = "DICT_6X6_250";
  MarkerDetector detector(mc, DetectorOptions());
  testing::ReferenceScene scene;
  scene.min_side_px = 20, scene.max_side_px = 25, scene.min_angle_deg = 65, scene.max_angle_deg = 75;
  scene.markers = 8;
  std::mt19937_64 rng(5);
  std::vector<double> long_error, short_error;  // relative, per marker found
  for (int i = 0; i < 12; ++i) {
    std::vector<testing::RenderedMarker> truth;
    const cv::Mat image = testing::RenderReference(*dict, scene, testing::Imaging(), rng, &truth);
    for (const marker_t& m : detector.Detect(image))
      for (const auto& t : truth) {
        if (t.id != m.id) continue;
        auto diagonal = [](const cv::Point2d& a, const cv::Point2d& b) { return cv::norm(b - a); };
        const std::array<cv::Point2d, 4> got = testing::CornersOf(m);
        const double true02 = diagonal(t.corners[0], t.corners[2]),
                     true13 = diagonal(t.corners[1], t.corners[3]);
        const double e02 = diagonal(got[0], got[2]) / true02 - 1, e13 = diagonal(got[1], got[3]) / true13 - 1;
        long_error.push_back(true02 >= true13 ? e02 : e13),
            short_error.push_back(true02 >= true13 ? e13 : e02);
      }
  }
  std::printf("%zu markers at 65-75 deg: long / short diagonal %+.3f / %+.3f %%\n", long_error.size(),
              100 * testing::MeanOf(long_error), 100 * testing::MeanOf(short_error));
  EXPECT_GE(long_error.size(), 40u);
  EXPECT_LE(std::abs(testing::MeanOf(long_error)), 0.0025);
  EXPECT_LE(std::abs(testing::MeanOf(short_error) - testing::MeanOf(long_error)), 0.007);
}

// Sizes x angles of the plain condition and the webcam-like one: the bias does not depend on the
// marker's size or on its view angle.
TEST(DetectorAccuracy, SizesAndAnglesOnReferenceRenders) {
  const double sizes[3][2] = {{15, 25}, {25, 40}, {40, 60}};
  const double angles[2][2] = {{0, 60}, {60, 75}};
  for (int s = 0; s < 3; ++s)
    for (int g = 0; g < 2; ++g) {
      testing::ReferenceScene scene;
      scene.min_side_px = sizes[s][0], scene.max_side_px = sizes[s][1];
      scene.min_angle_deg = angles[g][0], scene.max_angle_deg = angles[g][1];
      testing::Imaging im;
      im.blur_sigma = 0.7;
      const testing::Accuracy a =
          testing::MeasureReference("DICT_6X6_250", scene, im, DetectorOptions(), 4, 20 + s * 2 + g);
      std::printf("%2.0f-%2.0f px, %2.0f-%2.0f deg: offset %+.3f median %.3f recall60 %.3f recall75 %.3f\n",
                  sizes[s][0], sizes[s][1], angles[g][0], angles[g][1], a.MeanOffset(), a.MedianError(),
                  a.Recall60(), a.Recall75());
      EXPECT_EQ(a.wrong_ids, 0);
      // 60-75 deg: foreshortened sides, fewer samples (a shortfall): +0.02-0.03 px outward, and -0.044
      // for 15-25 px on these 4 images (one marker whose side kept its line; +0.021 over 16 images of
      // seed 3, as before that change).
      EXPECT_LE(std::abs(a.MeanOffset()), g == 0 ? 0.02 : 0.045);
      EXPECT_LE(a.MedianError(), g == 0 ? 0.10 : 0.15);
      EXPECT_GE(a.Recall75(), 0.90);
    }
}

// Small markers, 12-15 px (DICT_6X6_250: cells of 1.5-1.9 px, about two blur sigmas), sharp and under
// 0.7 px blur: the side model's corners stay unbiased where a cell is barely wider than the blur.
// Measured (12 images each, seeds 31 and 32): see the printout; bench_accuracy's small-marker table has
// 10-15 px over the whole catalogue. The pentagon's +0.04 px on mcmt-sim renders is its crowded faces
// (BENCHMARKS.md, issue 15 "small"), not the size.
TEST(DetectorAccuracy, SmallMarkersOnReferenceRenders) {
  for (double blur : {0.0, 0.7}) {
    testing::ReferenceScene scene;
    scene.min_side_px = 12, scene.max_side_px = 15, scene.max_angle_deg = 60, scene.markers = 10;
    testing::Imaging im;
    im.blur_sigma = blur;
    const testing::Accuracy a =
        testing::MeasureReference("DICT_6X6_250", scene, im, DetectorOptions(), 12, blur > 0 ? 32 : 31);
    std::printf("12-15 px, blur %.1f: offset %+.4f median %.3f found %d/%d (%zu corners) wrong %d\n", blur,
                a.MeanOffset(), a.MedianError(), a.found_small, a.visible_small, a.corners.errors.size(),
                a.wrong_ids);
    EXPECT_EQ(a.wrong_ids, 0);
    ASSERT_GT(a.corners.errors.size(), 100u);
    EXPECT_LE(std::abs(a.MeanOffset()), 0.02);
    EXPECT_LE(a.MedianError(), 0.12);
  }
}

// Small faces: mcmt-sim's pentagon (2.5 cm markers, 10-14 px at 1.0 m, cells of 1.4 px) has 1.25-1.5 cells
// of face beyond each marker's 1-cell margin before the face's edge, the next face (another shade), the
// top or the other marker's white margin: a second step inside the side profiles' reach (2.3 cells there),
// back towards the margin's level. With one level beyond the margin the fits made the margins narrow and
// bright and the corners came out +0.045 px outward here (12 frames, 102 markers; the session's map
// -0.727 %). The sides with such a step are fitted again with the profiles ending before it and the
// margin tied to the paper (SecondStepBeyondMargin): +0.010 px (bench/results/2026-12-07-smallface.md).
TEST(DetectorAccuracy, SmallFacesDoNotPushCornersOutward) {
  testing::SimEvalOptions o;
  o.object = sim::ObjectKind::kPentagon;
  o.marker_size = 0.025;
  o.min_size_px = 10;
  o.frames = 12;
  const testing::SimEvalResult r = testing::EvaluateOnSim(o);
  const double offset = testing::MeanOf(r.corners.offsets);
  std::printf("pentagon, 1.0 m: %d markers, offset %+.4f px, median %.3f px, wrong %d\n", r.detections,
              offset, testing::MedianOf(r.corners.errors), r.wrong_ids);
  ASSERT_GT(r.corners.offsets.size(), 300u);
  EXPECT_EQ(r.wrong_ids, 0);
  EXPECT_LE(std::abs(offset), 0.03);
}

// Small markers (13-19 px, up to 65 deg) with a half-cell margin on dark grey and on a black tool: first
// crossing lines turned 3-4 px at one end (crossings of different edges on the margin's rays) led the
// model passes beyond the refinement's limit, and such a marker fell back to cornerSubPix, 0.66 px
// inward per side (detector.cc LineWithinProfiles). 40 images each: 7 of 232 and 14 of 213 markers
// unrefined before, 2 of 232 and 7 of 212 with a refinement that failed retried with the crossing
// lines held within their profiles (asserted: at most 2.5 % of both conditions' markers unrefined;
// 4.7 % before).
TEST(DetectorAccuracy, SmallMarkersOnADarkSurroundAreRefined) {
  auto dict = LoadDictionary("DICT_6X6_250");
  long long unrefined = 0, markers = 0;
  for (const char* name : {"half-cell margin, dark grey", "half-cell margin, black tool"}) {
    const testing::Imaging im = testing::CatalogueCondition(name);
    testing::ReferenceScene scene;
    scene.min_side_px = 13, scene.max_side_px = 19, scene.max_angle_deg = 65, scene.markers = 10;
    MarkerDetector detector = testing::ReferenceDetector(im);
    std::mt19937_64 rng(15);
    testing::Accuracy a;
    for (int i = 0; i < 40; ++i) {
      std::vector<testing::RenderedMarker> truth;
      const cv::Mat image = testing::RenderReference(*dict, scene, im, rng, &truth);
      testing::Score(truth, detector.Detect(image), &a);
    }
    std::printf("%s: %lld of %lld markers unrefined, found %d/%d, offset %+.4f median %.3f\n", name,
                detector.stats().refine_failures, detector.stats().markers, a.found_small, a.visible_small,
                a.MeanOffset(), a.MedianError());
    EXPECT_EQ(a.wrong_ids, 0) << name;
    unrefined += detector.stats().refine_failures, markers += detector.stats().markers;
  }
  ASSERT_GT(markers, 300);
  EXPECT_LE(unrefined, 0.025 * markers);
}

// A sharp frame's marker refined on its smoothed region a cell off is refined again on the region itself
// (MarkerDetector::RefineCorners). The catalogue test's first "no margin, grey surface" image (seed 11):
// id 123, 15.9 px at 69 deg, cells about a pixel deep across its foreshortened sides. On the smoothed
// region one such side's fit lost the code rows and ended 1.3 px outward, the code read a cell off, and
// the marker fell back to cornerSubPix, its corners 0.31-1.63 px off (bench/results/2026-12-07-id123.md).
// Asserted: every marker of the image found and refined, each corner within 0.5 px.
TEST(DetectorAccuracy, SmoothedRefinementACellOffIsRefinedUnsmoothed) {
  auto dict = LoadDictionary("DICT_6X6_250");
  const testing::Imaging im = testing::CatalogueCondition("no margin, grey surface");
  testing::ReferenceScene scene;
  scene.min_side_px = 15, scene.max_side_px = 60;
  MarkerDetector detector = testing::ReferenceDetector(im);
  std::mt19937_64 rng(11);
  std::vector<testing::RenderedMarker> truth;
  const cv::Mat image = testing::RenderReference(*dict, scene, im, rng, &truth);
  const std::vector<marker_t> markers = detector.Detect(image);
  bool found123 = false;
  for (const marker_t& m : markers)
    for (const testing::RenderedMarker& t : truth) {
      if (t.id != m.id) continue;
      found123 = found123 || m.id == 123;
      for (int k = 0; k < 4; ++k) {
        const double error = std::hypot(m.corners[k][0] - t.corners[k].x, m.corners[k][1] - t.corners[k].y);
        std::printf("id %3d (%.1f px, %.1f deg) corner %d: %.3f px\n", t.id, t.side_px, t.view_angle_deg, k,
                    error);
        EXPECT_LE(error, 0.5) << "id " << t.id << " corner " << k;
      }
    }
  EXPECT_TRUE(found123);
  EXPECT_EQ(detector.stats().refine_failures, 0);
}

// A sharp frame's marker whose smoothed refinement reads its code worse than its candidate does, but within
// the allowance, is refined again unsmoothed from the candidate (MarkerDetector::RefineCorners).
// bench_accuracy's matrix renders (condition, side band, angle band, image): three steep markers whose
// smoothed refinement put a side 0.8-1.0 px off and read 2-10 cells wrong (the candidate 0 or 4); their
// worst corners were 1.13, 0.95 and 1.50 px off, refined unsmoothed 0.10, 0.30 and 0.20 px
// (bench/results/2026-12-07-gross.md). Asserted: each found, every corner within 0.5 px.
TEST(DetectorAccuracy, SmoothedRefinementReadingWorseThanItsCandidateIsRefinedUnsmoothed) {
  auto dict = LoadDictionary("DICT_6X6_250");
  const std::vector<testing::Imaging> catalogue = testing::ImagingCatalogue();
  struct Case {
    int condition, side_band, angle_band, image, id;
  };
  for (const Case& c : {Case{1, 0, 1, 6, 201}, Case{1, 0, 2, 7, 174}, Case{4, 0, 2, 5, 183}}) {
    const testing::Imaging& im = catalogue[c.condition];
    std::mt19937_64 rng(testing::BenchSeed(c.condition, c.side_band, c.angle_band));
    std::vector<testing::RenderedMarker> truth;
    cv::Mat image;
    for (int i = 0; i <= c.image; ++i)
      image =
          testing::RenderReference(*dict, testing::BenchScene(c.side_band, c.angle_band), im, rng, &truth);
    MarkerDetector detector = testing::ReferenceDetector(im);
    bool found = false;
    for (const marker_t& m : detector.Detect(image))
      for (const testing::RenderedMarker& t : truth) {
        if (t.id != m.id || m.id != c.id) continue;
        found = true;
        for (int k = 0; k < 4; ++k) {
          const double error = std::hypot(m.corners[k][0] - t.corners[k].x, m.corners[k][1] - t.corners[k].y);
          std::printf("%s id %3d (%.1f px, %.1f deg) corner %d: %.3f px\n", im.name.c_str(), t.id, t.side_px,
                      t.view_angle_deg, k, error);
          EXPECT_LE(error, 0.5) << im.name << " id " << t.id << " corner " << k;
        }
      }
    EXPECT_TRUE(found) << im.name << " id " << c.id;
  }
}

// A wide paper margin is not taken for the surround: small markers (15-22 px, 0-60 deg) with a 3-cell
// margin under the catalogue's gaussian blur 1.2. The margin's far side lies just beyond the side
// profiles' outer end (1.6 cells + 1 px) and its blurred step still darkens their last bins; fitted with
// one surround level (FitSideModels' `unseen`), that level came out low and the corners +0.042 px outward
// (now +0.024; the blur 1.2 map with margin_cells=3 -0.138 -> -0.040 %; bench/results/2026-12-07-margin2.md).
TEST(DetectorAccuracy, WidePaperMarginsDoNotMoveCornersOutward) {
  testing::Imaging im = testing::CatalogueCondition("gaussian blur 1.2");
  im.margin_cells = 3;
  testing::ReferenceScene scene;
  scene.min_side_px = 15, scene.max_side_px = 22, scene.max_angle_deg = 60, scene.markers = 10;
  const testing::Accuracy a = testing::MeasureReference("DICT_6X6_250", scene, im, DetectorOptions(), 30, 7);
  std::printf("3-cell margin, blur 1.2: found %d/%d, offset %+.4f px, median %.3f px\n", a.found_small,
              a.visible_small, a.MeanOffset(), a.MedianError());
  EXPECT_EQ(a.wrong_ids, 0);
  EXPECT_LE(std::abs(a.MeanOffset()), 0.03);
}

// The interior angle (deg) of quad `q` at corner k.
double CornerAngleDeg(const std::array<cv::Point2d, 4>& q, int k) {
  const cv::Point2d a = q[(k + 3) % 4] - q[k], b = q[(k + 1) % 4] - q[k];
  return std::acos(a.dot(b) / (cv::norm(a) * cv::norm(b))) * 180.0 / M_PI;
}

// Blur does not square a skewed marker: small markers (15-22 px) at 45-60 deg under the catalogue's
// gaussian blur 1.2 and gamma 2.2 (blur 0.8), the mean error of each marker's most acute angle. Blurred,
// the crossings' line of a side turns its end at the acute angle inward (the perpendicular side's border
// lies within the blur there) and the quad came out too square: +0.63 deg under blur 1.2, its long
// diagonal short and the map 0.2 % too large (bench/results/2026-12-06-blurrow.md). Sides are now turned by
// the model from smaller skews where the fitted blur is a larger part of a cell (SkewTurnWeight).
TEST(DetectorAccuracy, BlurDoesNotSquareASkewedMarker) {
  auto dict = LoadDictionary("DICT_6X6_250");
  for (const char* name : {"gaussian blur 1.2", "gamma 2.2"}) {
    const testing::Imaging im = testing::CatalogueCondition(name);
    MarkerDetector detector = testing::ReferenceDetector(im);
    testing::ReferenceScene scene;
    scene.min_side_px = 15, scene.max_side_px = 22, scene.min_angle_deg = 45, scene.max_angle_deg = 60;
    std::mt19937_64 rng(11);
    std::vector<double> errors;  // per marker found at 45-60 deg, deg
    for (int i = 0; i < 150; ++i) {
      std::vector<testing::RenderedMarker> truth;
      const cv::Mat image = testing::RenderReference(*dict, scene, im, rng, &truth);
      for (const marker_t& m : detector.Detect(image))
        for (const testing::RenderedMarker& t : truth) {
          if (t.id != m.id || t.view_angle_deg < 45 || t.view_angle_deg >= 60) continue;
          const std::array<cv::Point2d, 4> got = testing::CornersOf(m);
          int acute = 0;
          for (int k = 1; k < 4; ++k)
            if (CornerAngleDeg(t.corners, k) < CornerAngleDeg(t.corners, acute)) acute = k;
          errors.push_back(CornerAngleDeg(got, acute) - CornerAngleDeg(t.corners, acute));
        }
    }
    std::printf("%s: the most acute angle %+.3f deg off (%zu markers at 45-60 deg)\n", name,
                testing::MeanOf(errors), errors.size());
    ASSERT_GT(errors.size(), 200u) << name;
    EXPECT_LE(std::abs(testing::MeanOf(errors)), 0.4) << name;
  }
}

// The same detector on mcmt_sim's renders (the paper's rig at 1.0 m, 20-25 px markers): both
// renderers' corners agree with the detector's.
TEST(DetectorAccuracy, SimRendererAgreesWithReferenceRenderer) {
  testing::SimEvalOptions o;
  o.radius = 1.0;
  o.frames = 8;
  o.blur = 0.7;
  const testing::SimEvalResult sim = testing::EvaluateOnSim(o);
  testing::ReferenceScene scene;
  scene.min_side_px = 15, scene.max_side_px = 30, scene.max_angle_deg = 75;
  testing::Imaging im;
  im.blur_sigma = 0.7;
  const testing::Accuracy ref = testing::MeasureReference("DICT_6X6_250", scene, im, DetectorOptions(), 8, 5);
  const double sim_offset = testing::MeanOf(sim.corners.offsets),
               sim_median = testing::MedianOf(sim.corners.errors);
  std::printf("mcmt_sim: offset %+.3f median %.3f (%zu corners); reference: offset %+.3f median %.3f (%zu)\n",
              sim_offset, sim_median, sim.corners.errors.size(), ref.MeanOffset(), ref.MedianError(),
              ref.corners.errors.size());
  ASSERT_GT(sim.corners.errors.size(), 100u);
  EXPECT_LE(std::abs(sim_offset), 0.02);
  EXPECT_LE(std::abs(ref.MeanOffset()), 0.02);
  EXPECT_LE(sim_median, 0.10);
  EXPECT_LE(ref.MedianError(), 0.10);
  EXPECT_LE(std::abs(sim_offset - ref.MeanOffset()), 0.02);
  EXPECT_EQ(sim.wrong_ids, 0);
  EXPECT_EQ(ref.wrong_ids, 0);
}

// mcmt_sim under --imaging random (margins, surfaces, blur or defocus, noise, gamma, sharpening, JPEG
// drawn per camera): the corners stay unbiased on the simulator's own varied imaging too.
TEST(DetectorAccuracy, SimRandomImaging) {
  for (uint64_t seed : {11, 13}) {
    testing::SimEvalOptions o;
    o.radius = 1.0;
    o.frames = 8;
    o.random_imaging = seed;
    const testing::SimEvalResult r = testing::EvaluateOnSim(o);
    const double offset = testing::MeanOf(r.corners.offsets), median = testing::MedianOf(r.corners.errors);
    std::printf("random imaging %d: offset %+.3f median %.3f recall60 %.3f (%d/%d) wrong %d\n", int(seed),
                offset, median, r.Recall60(), r.found60, r.visible60, r.wrong_ids);
    ASSERT_GT(r.corners.errors.size(), 60u);
    EXPECT_LE(std::abs(offset), 0.02);
    // A shortfall (target 0.10): over 16 frames the median is 0.107-0.113 px for both seeds (sharpened
    // and JPEG cameras among them); 8 frames read 0.094-0.105.
    EXPECT_LE(median, 0.12);
    EXPECT_EQ(r.wrong_ids, 0);
  }
}

// Fast mode searches near the previous frame's markers (other threshold windows, other candidates) but
// must put every corner where the accurate mode does (issue 15: within 0.02 px, markers >= 15 px within
// 75 deg). Frame by frame on bench_detector's sequences (mcmt_sim box object, 5 cm markers, 1 m, noise
// 2, 60 frames x 2 cameras) at 320x240, 640x480 and 1280x960, and on reference renders of the imaging
// catalogue (each image repeated: a full search, then searches near the markers). Before the fix a 15 px
// marker at 65 deg (640x480, camera 0, frame 28) was 2.4 px off: its candidate, a pixel from the
// accurate mode's, let one side keep a crossing line a cell inside.
struct ModeDiff {
  double max_px = 0;
  int compared = 0, extra = 0, missing = 0;
  std::string worst;
  std::string extras;  // where fast mode found a marker the accurate mode did not
};
void CompareModes(const std::vector<marker_t>& accurate, const std::vector<marker_t>& fast,
                  const std::function<bool(int)>& comparable, const std::string& where, ModeDiff* d) {
  for (const marker_t& f : fast) {
    const marker_t* a = nullptr;
    for (const marker_t& m : accurate)
      if (m.id == f.id) a = &m;
    if (!comparable(f.id)) continue;
    if (!a) {
      ++d->extra;
      d->extras += where + " id " + std::to_string(f.id) + "; ";
      continue;
    }
    ++d->compared;
    for (int k = 0; k < 4; ++k)
      for (int c = 0; c < 2; ++c) {
        const double diff = std::abs(f.corners[k][c] - a->corners[k][c]);
        if (diff > d->max_px) d->max_px = diff, d->worst = where + " id " + std::to_string(f.id);
      }
  }
  for (const marker_t& a : accurate) {
    bool found = false;
    for (const marker_t& f : fast) found = found || f.id == a.id;
    d->missing += !found && comparable(a.id);
  }
}

// Fast and accurate mode on the first two cameras of a bench scene (testing::MakeDetectorBenchScene) at
// width x (width * 3 / 4): markers in issue 15's domain (testing::InCornerTargetDomain) compared.
ModeDiff CompareModesOnSim(const testing::DetectorBenchScene& scene, int width) {
  const std::vector<sim::SimCamera> cameras = scene.Cameras(2, width, width * 3 / 4);
  ModeDiff d;
  for (int c = 0; c < 2; ++c) {
    DetectorOptions fast_options;
    fast_options.fast = true;
    MarkerDetector accurate(scene.markers, DetectorOptions()), fast(scene.markers, fast_options);
    accurate.SetCamera(cameras[c].model);
    fast.SetCamera(cameras[c].model);
    for (size_t i = 0; i < scene.trajectory.size(); ++i) {
      const cv::Mat image =
          scene.renderer->Render(cameras[c], c, scene.trajectory[i].seq, scene.trajectory[i].rig_from_object);
      const auto views = sim::ProjectMarkers(cameras[c], scene.object, scene.trajectory[i].rig_from_object);
      auto comparable = [&](int id) {
        for (const auto& v : views)
          if (v.id == id) return testing::InCornerTargetDomain(v);
        return false;
      };
      CompareModes(accurate.Detect(image), fast.Detect(image), comparable,
                   "camera " + std::to_string(c) + " frame " + std::to_string(i), &d);
    }
  }
  std::printf("%dx%d: %d markers compared, fast vs accurate max %.4f px (%s), extra %d, missing %d\n", width,
              width * 3 / 4, d.compared, d.max_px, d.worst.c_str(), d.extra, d.missing);
  if (d.extra) std::printf("  extra: %s\n", d.extras.c_str());
  return d;
}

TEST(DetectorAccuracy, FastModeCornersAreTheAccurateModesOnSim) {
  const testing::DetectorBenchScene scene = testing::MakeDetectorBenchScene(60);
  for (const int width : {320, 640, 1280}) {
    const ModeDiff d = CompareModesOnSim(scene, width);
    // 320x240: the markers are 8-14 px (none compared; an 11.8 px one at 43 deg differs by 0.2 px).
    if (width > 320) {
      EXPECT_GT(d.compared, 300);
    }
    EXPECT_LE(d.max_px, 0.02) << width << ": " << d.worst;
    // Fast mode searches a band of fast_band_sides around the frame before's markers as the full search
    // searches the image: it finds what the accurate mode finds. Before (one threshold window about each
    // marker, new markers only at the next full search) it missed the markers coming into view (640x480:
    // 38 of 404; 1280x960: 30 of 465) and found one the accurate mode did not (camera 0 frame 4 id 4).
    EXPECT_EQ(d.missing, 0) << width;
    EXPECT_EQ(d.extra, 0) << width << ": " << d.extras;
  }
}

// bench_detector's own scene (30 frames) at 1280x960: a 32 px marker at 69 deg (camera 1 frame 25 id 7)
// on a sheared quad, whose wide-cell sides' profile rays cross code columns; without the row steps
// (detector.cc AddRowSteps) those sides' gamma had two valleys and the start chose one: fast mode's
// corners 0.423 px from the accurate mode's (bench/results/2026-12-05-{bistable,widemodel,rowsteps}.md).
TEST(DetectorAccuracy, FastModeCornersAreTheAccurateModesOnTheBenchScene) {
  const ModeDiff d = CompareModesOnSim(testing::MakeDetectorBenchScene(30), 1280);
  EXPECT_GT(d.compared, 150);  // 239 (193 before fast_band_sides: 46 markers coming into view missed)
  EXPECT_LE(d.max_px, 0.02) << d.worst;
  EXPECT_EQ(d.extra, 0) << d.extras;
  EXPECT_EQ(d.missing, 0);
}

// Whether marker `id` of a reference render is one the corner comparisons below take: in the render
// (its ids are distinct), at least 15 px, at most 75 deg.
bool ComparedOnReference(const std::vector<testing::RenderedMarker>& truth, int id) {
  for (const auto& t : truth)
    if (t.id == id) return t.side_px >= 15 && t.view_angle_deg <= 75;
  return false;
}

TEST(DetectorAccuracy, FastModeCornersAreTheAccurateModesOnReferenceRenders) {
  auto dict = LoadDictionary("DICT_6X6_250");
  ModeDiff all;
  for (const testing::Imaging& im : testing::ImagingCatalogue()) {
    testing::ReferenceScene scene;
    std::mt19937_64 rng(31);
    ModeDiff d;
    for (int i = 0; i < 3; ++i) {
      std::vector<testing::RenderedMarker> truth;
      const cv::Mat image = testing::RenderReference(*dict, scene, im, rng, &truth);
      auto comparable = [&](int id) { return ComparedOnReference(truth, id); };
      DetectorOptions fast_options;
      fast_options.fast = true;
      MarkerDetector accurate = testing::ReferenceDetector(im),
                     fast = testing::ReferenceDetector(im, fast_options);
      for (int frame = 0; frame < 4; ++frame)
        CompareModes(accurate.Detect(image), fast.Detect(image), comparable,
                     im.name + " image " + std::to_string(i) + " frame " + std::to_string(frame), &d);
      EXPECT_EQ(fast.stats().full_searches, 1) << im.name;
    }
    std::printf("%-30s %3d markers compared, fast vs accurate max %.4f px (%s), extra %d, missing %d\n",
                im.name.c_str(), d.compared, d.max_px, d.worst.c_str(), d.extra, d.missing);
    // Fast mode searches a band of fast_band_sides around the frame before's markers as the full search
    // searches the image, so on a still image its candidates, and so its corners, are the accurate
    // mode's: 0.0000 px in every condition. Before, its own region search started the refinement from
    // other corners, and the black tool's id 90 (image 1, 25.6 px at 71 deg) ended 0.030 px away; no
    // margin on grey kept 3 markers the accurate mode dropped. That start dependence is no longer tested
    // here (bench/results/2026-12-05-{settle,rulec}.md: a start probe, not yet a test).
    EXPECT_LE(d.max_px, 0.02) << im.name << ": " << d.worst;
    EXPECT_EQ(d.extra, 0) << im.name << ": " << d.extras;
    EXPECT_EQ(d.missing, 0) << im.name;
  }
}

// The refinement does not depend on its start. Fast mode's corners rest on this rule, and since fast mode
// takes the full search's candidates (fast_band_sides), FastModeCornersAreTheAccurateModes* compare
// identical starts and no longer check it. Each marker of the reference renders the accurate mode found
// (>= 15 px, <= 75 deg) is refined again from its corners rounded to whole pixels and from its corners
// moved by up to half a pixel in x and y; the two results should agree within 0.02 px. Not every marker
// does yet: 1-2.5 % of them, in any condition, are markers whose refinement never settles (its passes
// move the corners by more than the rule at every round: bench/results/2026-12-05-{settle,rulec,aitken,
// unsettled}.md), and which conditions show one depends on the images drawn. 6 images per condition,
// markers more than 0.02 px apart / compared, largest distance: seed 31 (the test's) 5 / 396, 0.21 px;
// seed 41 8 / 409, 1.39 px; seed 51 10 / 399, 1.42 px (MCMT_PROBE_SEED). So the share is bounded over
// every condition, at 3 %, and the distance at 1.5 px.
constexpr int kProbeImages = 6;  // per condition
// Markers refined from one of the probe's two starts only, all conditions: 2 / 0 / 1 at seeds 31 / 41 / 51
// (black tool and dark grey image 1 id 90: neither refit finds an edge with a step; wood image 3 id 155).
// Before the inward refit of a margin's outer edge (polarity), on the 13 conditions then: 2 / 2 / 2.
constexpr int kOneStartFailedMax = 2;

TEST(DetectorAccuracy, RefinementDoesNotDependOnItsStart) {
  auto dict = LoadDictionary("DICT_6X6_250");
  const int cells = dict->markerSize + 2;
  const int seed = std::getenv("MCMT_PROBE_SEED") ? std::atoi(std::getenv("MCMT_PROBE_SEED")) : 31;
  int all_compared = 0, all_apart = 0, all_one_failed = 0;
  for (const testing::Imaging& im : testing::ImagingCatalogue()) {
    testing::ReferenceScene scene;
    // The starts' shifts have their own generator: the images do not depend on how many markers were found.
    std::mt19937_64 rng(seed), start_rng(seed + 1);
    std::uniform_real_distribution<double> shift(-0.5, 0.5);
    double max_px = 0;
    int compared = 0, apart = 0, one_failed = 0;
    std::string worst, failed;
    for (int i = 0; i < kProbeImages; ++i) {
      std::vector<testing::RenderedMarker> truth;
      const cv::Mat image = testing::RenderReference(*dict, scene, im, rng, &truth);
      for (const marker_t& m : testing::ReferenceDetector(im).Detect(image)) {
        if (!ComparedOnReference(truth, m.id)) continue;
        const cv::Mat bits = cv::aruco::Dictionary::getBitsFromByteList(
            dict->bytesList.rowRange(m.id, m.id + 1), dict->markerSize);
        std::array<cv::Point2d, 4> rounded, moved;
        for (int k = 0; k < 4; ++k) {
          rounded[k] = {std::round(m.corners[k][0]), std::round(m.corners[k][1])};
          moved[k] = {m.corners[k][0] + shift(start_rng), m.corners[k][1] + shift(start_rng)};
        }
        const int polarity = im.inverted ? -1 : 1;  // the border darker than its ring, or brighter
        const bool ok_rounded = RefineMarkerCorners(image, cells, bits, nullptr, 1, &rounded, true, nullptr,
                                                    true, nullptr, polarity);
        const bool ok_moved = RefineMarkerCorners(image, cells, bits, nullptr, 1, &moved, true, nullptr, true,
                                                  nullptr, polarity);
        if (ok_rounded != ok_moved) {
          ++one_failed;
          failed += " image " + std::to_string(i) + " id " + std::to_string(m.id);
        }
        if (!ok_rounded || !ok_moved) continue;
        ++compared;
        double d = 0;
        for (int k = 0; k < 4; ++k) d = std::max(d, cv::norm(rounded[k] - moved[k]));
        if (d > 0.02) ++apart;
        if (d > max_px) max_px = d, worst = "image " + std::to_string(i) + " id " + std::to_string(m.id);
      }
    }
    std::printf(
        "%-30s %3d markers refined from two starts, %d more than 0.02 px apart, max %.4f px (%s); %d refined "
        "from one start only%s\n",
        im.name.c_str(), compared, apart, max_px, worst.c_str(), one_failed, failed.c_str());
    EXPECT_GT(compared, 10 * kProbeImages / 3) << im.name;
    EXPECT_LE(max_px, 1.5) << im.name << ": " << worst;
    all_compared += compared, all_apart += apart, all_one_failed += one_failed;
  }
  std::printf("all: %d of %d markers more than 0.02 px apart, %d refined from one start only\n", all_apart,
              all_compared, all_one_failed);
  EXPECT_LE(all_apart, 0.03 * all_compared);
  // A refinement that fails from one start and not the other depends on its start as much as two far-apart
  // ends do (a side that took a wrong edge in its first passes: bench/results/2026-12-06-polarity.md).
  EXPECT_LE(all_one_failed, kOneStartFailedMax);
}

// One marker of the start probe (RefinementDoesNotDependOnItsStart) as the probe saw it at `seed`: its
// image (the probe's `image`-th under `im`), true corners and two starts (the detected corners rounded, and
// moved by up to half a pixel, the start shifts drawn in the probe's order). False if it was not compared.
struct ProbeMarker {
  cv::Mat image, bits;
  std::array<cv::Point2d, 4> truth, rounded, moved;
};
bool ProbeStarts(const testing::Imaging& im, int seed, int image, int id, ProbeMarker* out) {
  auto dict = LoadDictionary("DICT_6X6_250");
  testing::ReferenceScene scene;
  std::mt19937_64 rng(seed), start_rng(seed + 1);
  std::uniform_real_distribution<double> shift(-0.5, 0.5);
  for (int i = 0; i <= image; ++i) {
    std::vector<testing::RenderedMarker> truth;
    const cv::Mat rendered = testing::RenderReference(*dict, scene, im, rng, &truth);
    for (const marker_t& m : testing::ReferenceDetector(im).Detect(rendered)) {
      if (!ComparedOnReference(truth, m.id)) continue;
      std::array<cv::Point2d, 4> rounded, moved;
      for (int k = 0; k < 4; ++k) {
        rounded[k] = {std::round(m.corners[k][0]), std::round(m.corners[k][1])};
        moved[k] = {m.corners[k][0] + shift(start_rng), m.corners[k][1] + shift(start_rng)};
      }
      if (i < image || m.id != id) continue;
      out->image = rendered, out->rounded = rounded, out->moved = moved;
      out->bits =
          cv::aruco::Dictionary::getBitsFromByteList(dict->bytesList.rowRange(id, id + 1), dict->markerSize);
      for (const testing::RenderedMarker& t : truth)
        if (t.id == id) out->truth = t.corners;
      return true;
    }
  }
  return false;
}

// A side whose edge undershoots (sharpening, a gamma off the side's) fitted a strip of a fifth of a cell
// darker than the border as its margin, half a cell inside the one-level fit's edge; the model-only
// rounds' cold fits alternated between the two (1.25 px per round) and the probe's two starts of this
// marker (hard, seed 51, image 4, id 96) ended 1.42 px apart (bench/results/2026-12-06-onevalley.md).
TEST(DetectorAccuracy, AnUndershootIsNoMargin) {
  const int cells = LoadDictionary("DICT_6X6_250")->markerSize + 2;
  ProbeMarker p;
  ASSERT_TRUE(ProbeStarts(testing::CatalogueCondition("hard"), 51, 4, 96, &p));
  ASSERT_TRUE(
      RefineMarkerCorners(p.image, cells, p.bits, nullptr, 1, &p.rounded, true, nullptr, true, nullptr, 1));
  ASSERT_TRUE(
      RefineMarkerCorners(p.image, cells, p.bits, nullptr, 1, &p.moved, true, nullptr, true, nullptr, 1));
  double apart = 0;
  for (int k = 0; k < 4; ++k) apart = std::max(apart, cv::norm(p.rounded[k] - p.moved[k]));
  std::printf("hard image 4 id 96: refined from two starts, %.4f px apart\n", apart);
  EXPECT_LE(apart, 0.1);
}

// A side whose crossings lie on the outer edge of a half-cell margin over a black surface (bright inside,
// dark outside) fits a wrong-polarity model there; its refit one cell outward lies on the surface and takes
// it for the border (no step at its edge), and the refinement from that start ended outside the marker or
// failed. The refit half a cell inward finds the edge. The probe's two starts of these markers (black tool,
// seed 41 image 5 id 82; seed 31 image 4 id 22): one of them failed before (id 82 0.58 px from the truth,
// id 22 0.43 px), bench/results/2026-12-06-polarity.md.
TEST(DetectorAccuracy, AMarginsOuterEdgeIsNotTheBorders) {
  const int cells = LoadDictionary("DICT_6X6_250")->markerSize + 2;
  const testing::Imaging black_tool = testing::CatalogueCondition("half-cell margin, black tool");
  struct Case {
    int seed, image, id;
  };
  for (const Case& c : {Case{41, 5, 82}, Case{31, 4, 22}}) {
    const std::string what = "seed " + std::to_string(c.seed) + " image " + std::to_string(c.image) + " id " +
                             std::to_string(c.id);
    ProbeMarker p;
    ASSERT_TRUE(ProbeStarts(black_tool, c.seed, c.image, c.id, &p)) << what;
    double apart = 0, error = 0;
    for (auto* start : {&p.rounded, &p.moved}) {
      EXPECT_TRUE(
          RefineMarkerCorners(p.image, cells, p.bits, nullptr, 1, start, true, nullptr, true, nullptr, 1))
          << what;
      for (int k = 0; k < 4; ++k) error = std::max(error, cv::norm((*start)[k] - p.truth[k]));
    }
    for (int k = 0; k < 4; ++k) apart = std::max(apart, cv::norm(p.rounded[k] - p.moved[k]));
    std::printf("black tool %s: refined from two starts, %.4f px apart, %.4f px from the truth\n",
                what.c_str(), apart, error);
    EXPECT_LE(apart, 0.02) << what;
    EXPECT_LE(error, 0.2) << what;
  }
}

// The refinement of a frame does not depend on the frames before it (the rule: results never depend on
// the order frames arrive). The choice to smooth a sharp marker's region before refining it was made
// on a running average of the fitted blur over each detector's history: the same sharp frame after
// blurred frames was refined raw, after sharp frames smoothed (corners up to ~0.1 px apart; fast and
// accurate modes, whose histories differ, disagreed the same way).
TEST(DetectorAccuracy, CornersDoNotDependOnTheFramesBefore) {
  auto dict = LoadDictionary("DICT_6X6_250");
  MarkerConfig mc;
  mc.dictionary = "DICT_6X6_250";
  const testing::Imaging sharp = testing::CatalogueCondition("plain"),
                         blurred = testing::CatalogueCondition("gaussian blur 1.2");
  testing::ReferenceScene scene;
  std::mt19937_64 rng(41);
  auto render = [&](const testing::Imaging& im) {
    std::vector<testing::RenderedMarker> truth;
    return testing::RenderReference(*dict, scene, im, rng, &truth);
  };
  std::vector<cv::Mat> sharp_history, blurred_history;
  for (int i = 0; i < 3; ++i) sharp_history.push_back(render(sharp));
  for (int i = 0; i < 3; ++i) blurred_history.push_back(render(blurred));
  std::vector<std::pair<std::string, cv::Mat>> targets;
  for (int i = 0; i < 3; ++i) targets.emplace_back("sharp " + std::to_string(i), render(sharp));
  for (int i = 0; i < 3; ++i) targets.emplace_back("blurred " + std::to_string(i), render(blurred));
  for (const bool fast_mode : {false, true}) {
    DetectorOptions options;
    options.fast = fast_mode;
    for (const auto& [name, target] : targets) {
      const std::string what = std::string(fast_mode ? "fast" : "accurate") + ", " + name + " frame";
      MarkerDetector fresh(mc, options), after_sharp(mc, options), after_blurred(mc, options);
      for (const cv::Mat& image : sharp_history) after_sharp.Detect(image);
      for (const cv::Mat& image : blurred_history) after_blurred.Detect(image);
      after_sharp.Reset(), after_blurred.Reset();  // fast mode: no previous frame to track
      const std::vector<marker_t> reference = fresh.Detect(target);
      EXPECT_GE(reference.size(), 3u) << what;
      for (const auto& [history, detector] :
           {std::pair<std::string, MarkerDetector*>{"sharp", &after_sharp}, {"blurred", &after_blurred}}) {
        const std::vector<marker_t> markers = detector->Detect(target);
        ASSERT_EQ(markers.size(), reference.size()) << what << " after " << history << " frames";
        double max_px = 0;
        for (size_t j = 0; j < markers.size(); ++j) {
          ASSERT_EQ(markers[j].id, reference[j].id) << what << " after " << history << " frames";
          for (int k = 0; k < 4; ++k)
            max_px = std::max(max_px, std::hypot(markers[j].corners[k][0] - reference[j].corners[k][0],
                                                 markers[j].corners[k][1] - reference[j].corners[k][1]));
        }
        std::printf("%s after %s frames: %zu markers, max %.2e px from a fresh detector's\n", what.c_str(),
                    history.c_str(), markers.size(), max_px);
        EXPECT_LE(max_px, 1e-6) << what << " after " << history << " frames";
      }
    }
  }
}

}  // namespace
}  // namespace mcmt
