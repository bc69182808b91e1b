// Which markers carry a condition's corner offset: renders the reference images test_detector_accuracy
// renders (markers 15-60 px at 0-75 deg, one detector over all images of a condition, as
// testing::MeasureReference) and prints, per marker found, its image, id, size, view angle, the mean
// signed offset of its corners along the edge normals (+: outward) and its largest corner error; then
// the condition's mean offset and median error.
//   diag_corners CONDITION_SUBSTRING [images (8)] [seed (11)] [min offset px to print (0)]
// Environment: MIN_PX / MAX_PX (the markers' side, px: 15 / 60); SIDES=1: also one line per side of each
// marker found (PrintSides: its length, extent across, signed offset, and the marker's radial offset).
// With --modes: where fast mode's corners differ from the accurate mode's, on the images
// DetectorAccuracy.FastModeCornersAreTheAccurateModesOnReferenceRenders renders (each image detected
// twice by a fresh detector of each mode: fast mode's second frame is refined from its region search's
// candidates); per marker of the second frame whose corners differ by the given px or more: the
// difference and each mode's mean signed offset and largest corner error.
//   diag_corners --modes CONDITION_SUBSTRING [images (3)] [seed (31)] [min difference px (0.02)]
// With --dump: the per-corner errors bench_imaging_maps writes (MCMT_IMAGING_DUMP=FILE), per band of view
// angle and condition (all when none given): each marker's sides' signed offset along their normals
// (+: outward; the mean of a side's two ends), the thin pair (the smaller extent across: the sides the
// view foreshortens) and the wide pair apart, and its long and short diagonals' length errors (%, the
// long diagonal sets the view's distance in a map).
//   diag_corners --dump FILE [condition index]
#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <vector>

#include "tests/detector/accuracy.h"

using namespace mcmt;
namespace mcmt {}

namespace {
// Mean signed offset (px, +: outward) and largest corner error (px) of a found marker.
void MarkerErrors(const testing::RenderedMarker& t, const marker_t& m, double* offset, double* worst) {
  testing::CornerErrors e;
  std::array<cv::Point2d, 4> got;
  for (int k = 0; k < 4; ++k) got[k] = {m.corners[k][0], m.corners[k][1]};
  testing::AddCornerErrors(t, got, &e);
  *offset = testing::MeanOf(e.offsets);
  *worst = 0;
  for (double x : e.errors) *worst = std::max(*worst, x);
}

// One marker's four corners from a bench_imaging_maps dump: true corners and errors, view angle.
struct DumpedMarker {
  std::array<Eigen::Vector2d, 4> truth, error;
  int seen = 0;  // bits of the corners read
  double view_deg = 0;
};

// The dump's markers of condition `condition` (-1: all).
std::vector<DumpedMarker> ReadDump(const char* path, int condition) {
  std::map<std::array<long long, 4>, DumpedMarker> markers;
  FILE* f = std::fopen(path, "r");
  if (!f) {
    std::fprintf(stderr, "diag_corners --dump %s: cannot read\n", path);
    std::exit(2);
  }
  char line[512];
  if (!std::fgets(line, sizeof line, f)) line[0] = 0;  // the header
  while (std::fgets(line, sizeof line, f)) {
    double radius, dx, dy, err, view, size, border, x, y;
    int cond, camera, id, corner, occluded, visible, in_image;
    long long seq;
    if (std::sscanf(line, "%lf,%d,%d,%lld,%d,%d,%lf,%lf,%lf,%lf,%lf,%d,%d,%d,%lf,%lf,%lf", &radius, &cond,
                    &camera, &seq, &id, &corner, &dx, &dy, &err, &view, &size, &occluded, &visible, &in_image,
                    &border, &x, &y) != 17 ||
        (condition >= 0 && cond != condition) || corner < 0 || corner > 3)
      continue;
    DumpedMarker& m = markers[{cond, camera, seq, id}];
    m.truth[corner] = {x, y}, m.error[corner] = {dx, dy}, m.seen |= 1 << corner, m.view_deg = view;
  }
  std::fclose(f);
  std::vector<DumpedMarker> out;
  for (const auto& [key, m] : markers)
    if (m.seen == 15) out.push_back(m);
  return out;
}

// Per view band: the sides' offsets (thin and wide pairs) and the diagonals' errors of the dump's markers.
void PrintDumpBands(const std::vector<DumpedMarker>& markers) {
  const double edges[] = {0, 30, 45, 60, 67, 75, 90};
  constexpr int kBands = 6;
  // Per band (and all, at kBands): count, thin and wide extent, thin and wide offset, long and short error.
  double sums[kBands + 1][7] = {};
  for (const DumpedMarker& m : markers) {
    const Eigen::Vector2d centre = 0.25 * (m.truth[0] + m.truth[1] + m.truth[2] + m.truth[3]);
    double extent[4], offset[4];
    for (int s = 0; s < 4; ++s) {
      const Eigen::Vector2d a = m.truth[s], b = m.truth[(s + 1) % 4];
      Eigen::Vector2d n = Eigen::Vector2d(b.y() - a.y(), a.x() - b.x()).normalized();
      if (n.dot(0.5 * (a + b) - centre) < 0) n = -n;
      extent[s] =
          0.5 * (std::abs(n.dot(m.truth[(s + 2) % 4] - a)) + std::abs(n.dot(m.truth[(s + 3) % 4] - a)));
      offset[s] = 0.5 * n.dot(m.error[s] + m.error[(s + 1) % 4]);
    }
    const int thin = extent[0] + extent[2] < extent[1] + extent[3] ? 0 : 1;
    double diagonal[2], error[2];
    for (int k = 0; k < 2; ++k) {
      const Eigen::Vector2d d = m.truth[k + 2] - m.truth[k];
      diagonal[k] = d.norm();
      error[k] = 100.0 * (m.error[k + 2] - m.error[k]).dot(d) / d.squaredNorm();
    }
    const int longer = diagonal[0] >= diagonal[1] ? 0 : 1;
    const double row[7] = {1,
                           0.5 * (extent[thin] + extent[thin + 2]),
                           0.5 * (extent[1 - thin] + extent[3 - thin]),
                           0.5 * (offset[thin] + offset[thin + 2]),
                           0.5 * (offset[1 - thin] + offset[3 - thin]),
                           error[longer],
                           error[1 - longer]};
    int band = 0;
    while (band + 1 < kBands && m.view_deg >= edges[band + 1]) ++band;
    for (int k = 0; k < 7; ++k) sums[band][k] += row[k], sums[kBands][k] += row[k];
  }
  std::printf(
      "| view deg | markers | extent across thin / wide sides px | offset thin sides px | offset wide sides "
      "px "
      "| long / short diagonal %% |\n|---|---|---|---|---|---|\n");
  for (int b = 0; b <= kBands; ++b) {
    const double* x = sums[b];
    if (x[0] == 0) continue;
    char name[32];
    if (b < kBands)
      std::snprintf(name, sizeof name, "%.0f-%.0f", edges[b], edges[b + 1]);
    else
      std::snprintf(name, sizeof name, "all");
    std::printf("| %s | %.0f | %.1f / %.1f | %+.4f | %+.4f | %+.3f / %+.3f |\n", name, x[0], x[1] / x[0],
                x[2] / x[0], x[3] / x[0], x[4] / x[0], x[5] / x[0], x[6] / x[0]);
  }
}

// One line per side of a found marker (SIDES=1): its length and extent across (px), its signed offset
// (px, +: outward; the mean of its ends' along its outward normal), the marker's size and view angle.
void PrintSides(const testing::RenderedMarker& t, const marker_t& m) {
  Eigen::Vector2d truth[4], error[4], centre = Eigen::Vector2d::Zero();
  for (int k = 0; k < 4; ++k) {
    truth[k] = {t.corners[k].x, t.corners[k].y};
    error[k] = Eigen::Vector2d(m.corners[k][0], m.corners[k][1]) - truth[k];
    centre += 0.25 * truth[k];
  }
  double radial = 0;  // the mean of the corners' errors along the direction from the marker's centre
  for (int k = 0; k < 4; ++k) radial += 0.25 * error[k].dot((truth[k] - centre).normalized());
  for (int s = 0; s < 4; ++s) {
    const Eigen::Vector2d a = truth[s], b = truth[(s + 1) % 4];
    Eigen::Vector2d n = Eigen::Vector2d(b.y() - a.y(), a.x() - b.x()).normalized();
    if (n.dot(0.5 * (a + b) - centre) < 0) n = -n;
    const double across =
        0.5 * (std::abs(n.dot(truth[(s + 2) % 4] - a)) + std::abs(n.dot(truth[(s + 3) % 4] - a)));
    std::printf("side %d size %.1f angle %.1f length %.2f across %.2f offset %+.4f radial %+.4f\n", s,
                t.side_px, t.view_angle_deg, (b - a).norm(), across,
                0.5 * n.dot(error[s] + error[(s + 1) % 4]), radial);
  }
}

const marker_t* Find(const std::vector<marker_t>& found, int id) {
  for (const marker_t& m : found)
    if (m.id == id) return &m;
  return nullptr;
}
}  // namespace

int main(int argc, char** argv) {
  if (argc > 2 && std::strcmp(argv[1], "--dump") == 0) {
    PrintDumpBands(ReadDump(argv[2], argc > 3 ? std::atoi(argv[3]) : -1));
    return 0;
  }
  const bool sides = std::getenv("SIDES") && std::atoi(std::getenv("SIDES")) != 0;
  const bool modes = argc > 1 && std::strcmp(argv[1], "--modes") == 0;
  if (modes) --argc, ++argv;
  if (argc < 2) {
    std::fprintf(
        stderr,
        "usage: diag_corners CONDITION [images (8)] [seed (11)] [min |offset| px (0)]\n"
        "       diag_corners --modes CONDITION [images (3)] [seed (31)] [min difference px (0.02)]\n");
    return 2;
  }
  const int images = argc > 2 ? std::atoi(argv[2]) : modes ? 3 : 8;
  const uint64_t seed = argc > 3 ? std::strtoull(argv[3], nullptr, 10) : modes ? 31 : 11;
  const double min_print = argc > 4 ? std::atof(argv[4]) : modes ? 0.02 : 0.0;
  cv::setNumThreads(1);
  auto dict = LoadDictionary("DICT_6X6_250");
  DetectorOptions fast_options;
  fast_options.fast = true;
  for (const testing::Imaging& im : testing::ImagingCatalogue()) {
    if (!std::strstr(im.name.c_str(), argv[1])) continue;
    testing::ReferenceScene scene;
    if (!modes) {
      scene.min_side_px = std::getenv("MIN_PX") ? std::atof(std::getenv("MIN_PX")) : 15;
      scene.max_side_px = std::getenv("MAX_PX") ? std::atof(std::getenv("MAX_PX")) : 60;
    }
    MarkerDetector detector = testing::ReferenceDetector(im);
    std::mt19937_64 rng(seed);
    testing::Accuracy all;
    for (int i = 0; i < images; ++i) {
      std::vector<testing::RenderedMarker> truth;
      const cv::Mat image = testing::RenderReference(*dict, scene, im, rng, &truth);
      if (modes) {
        MarkerDetector accurate = testing::ReferenceDetector(im),
                       fast = testing::ReferenceDetector(im, fast_options);
        accurate.Detect(image), fast.Detect(image);
        const std::vector<marker_t> a = accurate.Detect(image), f = fast.Detect(image);
        for (const auto& t : truth) {
          const marker_t *ma = Find(a, t.id), *mf = Find(f, t.id);
          if (!ma || !mf) continue;
          double diff = 0;
          for (int k = 0; k < 4; ++k)
            for (int c = 0; c < 2; ++c)
              diff = std::max(diff, std::abs(ma->corners[k][c] - mf->corners[k][c]));
          if (diff < min_print) continue;
          double oa, wa, of, wf;
          MarkerErrors(t, *ma, &oa, &wa);
          MarkerErrors(t, *mf, &of, &wf);
          std::printf(
              "%s image %d id %3d side %5.1f px angle %4.1f deg: fast - accurate %.3f px; accurate offset "
              "%+.3f max %.3f, fast offset %+.3f max %.3f\n",
              im.name.c_str(), i, t.id, t.side_px, t.view_angle_deg, diff, oa, wa, of, wf);
        }
        continue;
      }
      const std::vector<marker_t> found = detector.Detect(image);
      testing::Score(truth, found, &all);
      for (const auto& t : truth)
        for (const marker_t& m : found) {
          if (m.id != t.id) continue;
          double offset, worst;
          MarkerErrors(t, m, &offset, &worst);
          if (sides) PrintSides(t, m);
          if (std::abs(offset) >= min_print)
            std::printf(
                "%s image %d id %3d side %5.1f px angle %4.1f deg: offset %+.3f px, max error %.3f px\n",
                im.name.c_str(), i, t.id, t.side_px, t.view_angle_deg, offset, worst);
        }
    }
    if (modes) continue;
    std::printf("%s: offset %+.4f px median %.4f px recall60 %.3f recall75 %.3f (%zu corners)\n",
                im.name.c_str(), all.MeanOffset(), all.MedianError(), all.Recall60(), all.Recall75(),
                all.corners.errors.size());
  }
  return 0;
}
