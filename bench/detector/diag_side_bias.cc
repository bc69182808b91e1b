// The side model's corner error on small blurred markers, apart from the candidate search's recall:
// each rendered marker is refined (RefineMarkerCorners) from its true corners moved by Gaussian noise,
// with its known bits, and scored against the truth (signed offset along the edge normals, error).
//   diag_side_bias ref|syn BLUR_PX MIN_SIDE_PX MAX_SIDE_PX IMAGES
//   diag_side_bias sim BLUR_PX RADIUS_M MARKER_SIZE_M FRAMES
//   diag_side_bias cond NAME MIN_SIDE_PX MAX_SIDE_PX IMAGES
// ref: tests/detector/reference_renderer.h (1-cell white margin, surface 0.5); syn: synthetic.h; sim:
// mcmt-sim's paper rig (5 cameras, 640x480) and object OBJECT (four_sided), markers >= MINPX px (15) within
// 75 deg, print margin QUIET (cells, 1) and face albedo ALBEDO (< 0: the object's), offsets per id too,
// SUPERSAMPLING (sim::RenderOptions::supersampling, 0: exact area), FLAT (bits: 1 no light gradient, 2 no
// shading, 4 no background texture).
// cond: the reference renderer under the condition of tests/detector/reference_renderer.h's
// ImagingCatalogue() whose name contains NAME (bench_accuracy's), 0-75 deg unless ANGLE, with the fields
// MCMT_IMAGING_OVERRIDE names set ("blur_sigma=1.05,jpeg_quality=70", as bench_imaging_maps').
// exact: RenderExact below (fronto-parallel, the continuous blurred image point-sampled, no noise).
// Environment: ANGLE (max view angle, deg, 60), MARKERS (per image, 10), NOISE (grey levels, 2),
// MARGIN (cells, ref, 1), SURFACE (ref, 0.5), PERTURB (px, 0.3), FITGAMMA (1: gamma fitted per side as
// the detector's default, 0: linear), SEED (1), PER (print each marker),
// SMOOTH (px: each image smoothed by a Gaussian of this sigma first, as the detector's sharp_smoothing),
// IDS (exact: ids drawn from 0..IDS-1 instead of the whole dictionary, and each (id, side)'s mean offset
// printed; sim prints it always: the rig's object carries ids 0-3), ROLL (exact: every marker's roll, deg),
// SIDES (file: each side's offset, to pair runs), START_OUT (px: every start corner moved
// this far outward from the marker's centre, after PERTURB).
// The last line: each side's signed offset (the mean of its ends' along its normal) by the marker's extent
// across the side (px along the side's normal: its cells' depth x cells).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <map>
#include <string>

#include "bench/detector/diag_support.h"
#include "core/dictionary.h"
#include "detector/detector.h"
#include "tests/detector/accuracy.h"
#include "tests/detector/sim_eval.h"

using namespace mcmt;

namespace {
using diag::Env;

cv::Mat Render(const cv::aruco::Dictionary& dict, bool reference, double blur, double side0, double side1,
               std::mt19937_64& rng, std::vector<testing::RenderedMarker>* truth,
               const testing::Imaging* condition = nullptr) {
  if (!reference) {
    testing::SceneOptions scene;
    scene.min_side_px = side0, scene.max_side_px = side1, scene.max_angle_deg = Env("ANGLE", 60);
    scene.markers = static_cast<int>(Env("MARKERS", 10));
    scene.blur_sigma = blur, scene.noise_sigma = Env("NOISE", 2);
    return testing::RenderScene(dict, scene, rng, truth);
  }
  testing::ReferenceScene scene;
  scene.min_side_px = side0, scene.max_side_px = side1, scene.max_angle_deg = Env("ANGLE", 60);
  scene.min_angle_deg = Env("ANGLE0", 0);
  scene.markers = static_cast<int>(Env("MARKERS", 10));
  testing::Imaging im;
  im.blur_sigma = blur, im.read_noise = Env("NOISE", 2);
  im.margin_cells = Env("MARGIN", 1.0), im.surface = Env("SURFACE", 0.5);
  if (condition) im = *condition, scene.max_angle_deg = Env("ANGLE", 75);
  return testing::RenderReference(dict, scene, im, rng, truth);
}

// The exact image of fronto-parallel markers (random roll, size and position): every pixel the point
// sample at its centre of the print (1-cell margin MARGIN, surface SURFEXT cells beyond it, on a
// uniform background) blurred by a continuous Gaussian of `blur` px, in closed form (a blurred
// rectangle is a product of two differences of Phi). BOX (n): each pixel the mean of n x n such samples.
cv::Mat RenderExact(const cv::aruco::Dictionary& dict, double blur, double side0, double side1,
                    std::mt19937_64& rng, std::vector<testing::RenderedMarker>* truth) {
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  const int cells = dict.markerSize + 2, box = static_cast<int>(Env("BOX", 1));
  const double margin = Env("MARGIN", 1.0), ext = margin + Env("SURFEXT", 2.5);
  const double bg = 0.4 * 255, surface = Env("SURFACE", 0.5) * 255, paper = 0.85 * 255, ink = 0.04 * 255;
  cv::Mat linear(480, 640, CV_64F, cv::Scalar(bg));
  truth->clear();
  const int markers = static_cast<int>(Env("MARKERS", 10));
  for (int i = 0; i < markers; ++i) {
    testing::RenderedMarker m;
    const int ids = static_cast<int>(Env("IDS", 0));
    m.id = std::uniform_int_distribution<int>(0, ids > 0 ? ids - 1 : dict.bytesList.rows - 1)(rng);
    const double side = side0 + (side1 - side0) * uni(rng), scale = side / cells,
                 roll_draw = 2 * M_PI * uni(rng),  // drawn with ROLL too: the same sizes and positions
        roll = Env("ROLL", -1) >= 0 ? Env("ROLL", 0) * M_PI / 180 : roll_draw;
    const double cx = 80 + (i % 5) * 120 + uni(rng), cy = 120 + (i / 5) * 240 + uni(rng);
    const double co = std::cos(roll), si = std::sin(roll), sb = blur / scale;
    auto image = [&](double u, double v) {
      const double x = (u - 0.5 * cells) * scale, y = (v - 0.5 * cells) * scale;
      return cv::Point2d(cx + co * x - si * y, cy + si * x + co * y);
    };
    m.corners = {image(0, 0), image(cells, 0), image(cells, cells), image(0, cells)};
    m.side_px = side, m.view_angle_deg = 0;
    const cv::Mat bits =
        cv::aruco::Dictionary::getBitsFromByteList(dict.bytesList.rowRange(m.id, m.id + 1), dict.markerSize);
    auto phi = [](double z) { return 0.5 * std::erfc(-z * M_SQRT1_2); };
    auto rect = [&](double u, double v, double u0, double v0, double u1, double v1) {
      return (phi((u1 - u) / sb) - phi((u0 - u) / sb)) * (phi((v1 - v) / sb) - phi((v0 - v) / sb));
    };
    const int reach = static_cast<int>((ext + cells / 2.0 + 3) * scale * 1.5);
    for (int y = std::max(0, static_cast<int>(cy) - reach); y <= std::min(linear.rows - 1.0, cy + reach); ++y)
      for (int x = std::max(0, static_cast<int>(cx) - reach); x <= std::min(linear.cols - 1.0, cx + reach);
           ++x) {
        double sum = 0;
        for (int a = 0; a < box; ++a)
          for (int b = 0; b < box; ++b) {
            const double px = x - 0.5 + (b + 0.5) / box - cx, py = y - 0.5 + (a + 0.5) / box - cy;
            const double u = (co * px + si * py) / scale + 0.5 * cells,
                         v = (-si * px + co * py) / scale + 0.5 * cells;
            double f = bg + (surface - bg) * rect(u, v, -ext, -ext, cells + ext, cells + ext) +
                       (paper - surface) * rect(u, v, -margin, -margin, cells + margin, cells + margin) +
                       (ink - paper) * rect(u, v, 0, 0, cells, cells);
            for (int r = 1; r + 1 < cells; ++r)
              for (int c = 1; c + 1 < cells; ++c)
                if (bits.at<uint8_t>(r - 1, c - 1)) f += (paper - ink) * rect(u, v, c, r, c + 1, r + 1);
            sum += f;
          }
        linear.at<double>(y, x) = sum / (box * box);
      }
    truth->push_back(m);
  }
  cv::Mat out;
  linear.convertTo(out, CV_8U);
  return out;
}

// mcmt-sim's renders of the paper's rig as (image, truth) pairs for Refine below.
void ForEachSimImage(
    double blur, double radius, double marker_size, int frames,
    const std::function<void(const cv::Mat&, const std::vector<testing::RenderedMarker>&)>& use) {
  sim::RigOptions rig;
  rig.num_cameras = 5, rig.radius = radius;
  const std::vector<sim::SimCamera> cameras = sim::MakeRig(rig);
  sim::ObjectOptions oo;
  oo.kind = sim::ObjectKindFromName(std::getenv("OBJECT") ? std::getenv("OBJECT") : "four_sided");
  oo.marker_size = marker_size;
  const sim::SimObject object = sim::MakeObject(oo);
  sim::TrajectoryOptions to;
  to.frames = frames, to.seed = 3, to.fps = 3.0;
  sim::RenderOptions ro;
  ro.blur_sigma = blur, ro.noise_sigma = Env("NOISE", 2), ro.seed = 3;
  ro.quiet_zone_cells = static_cast<int>(Env("QUIET", 1)), ro.surface_albedo = Env("ALBEDO", -1);
  ro.supersampling = static_cast<int>(Env("SUPERSAMPLING", 0));
  const int flat = static_cast<int>(Env("FLAT", 0));
  if (flat & 1) ro.lighting_gradient = 0;
  if (flat & 2) ro.shading = 0;
  if (flat & 4) ro.textured_background = false;
  sim::Renderer renderer(object, "DICT_6X6_250", ro);
  for (size_t c = 0; c < cameras.size(); ++c)
    for (const sim::SimFrame& f : sim::MakeTrajectory(to)) {
      std::vector<testing::RenderedMarker> truth;
      for (const sim::MarkerView& v : sim::ProjectMarkers(cameras[c], object, f.rig_from_object)) {
        if (!v.fully_visible || v.size_px < Env("MINPX", 15) || v.view_angle_deg > 75) continue;
        testing::RenderedMarker t;
        t.id = v.id, t.side_px = v.size_px, t.view_angle_deg = v.view_angle_deg;
        for (int k = 0; k < 4; ++k) t.corners[k] = cv::Point2d(v.corners[k].x(), v.corners[k].y());
        truth.push_back(t);
      }
      use(renderer.Render(cameras[c], static_cast<int>(c), f.seq, f.rig_from_object), truth);
    }
}
// The shape errors of refined markers per view angle band (the header's last table).
struct ShapeByAngle {
  static constexpr double kBands[] = {0, 20, 40, 60, 65, 70, 75};
  static constexpr int kCount = sizeof(kBands) / sizeof(kBands[0]) - 1;
  std::vector<double> long_diag[kCount], short_diag[kCount], acute[kCount], obtuse[kCount], turn[kCount];

  void Add(const testing::RenderedMarker& t, const std::array<cv::Point2d, 4>& c) {
    int band = 0;
    while (band + 1 < kCount && t.view_angle_deg >= kBands[band + 1]) ++band;
    const double d02 = cv::norm(t.corners[2] - t.corners[0]), d13 = cv::norm(t.corners[3] - t.corners[1]);
    const double e02 = cv::norm(c[2] - c[0]) / d02 - 1, e13 = cv::norm(c[3] - c[1]) / d13 - 1;
    long_diag[band].push_back(100 * (d02 >= d13 ? e02 : e13));
    short_diag[band].push_back(100 * (d02 >= d13 ? e13 : e02));
    cv::Point2d centre(0, 0);
    for (const auto& p : t.corners) centre += p * 0.25;
    auto cosine = [&](int k) {  // of the interior angle at corner k
      const cv::Point2d a = t.corners[(k + 3) % 4] - t.corners[k], b = t.corners[(k + 1) % 4] - t.corners[k];
      return a.dot(b) / (cv::norm(a) * cv::norm(b));
    };
    for (int k = 0; k < 4; ++k) {
      const cv::Point2d a = t.corners[k], b = t.corners[(k + 1) % 4];
      cv::Point2d n(b.y - a.y, a.x - b.x);
      n *= 1.0 / cv::norm(n);
      if (n.dot(0.5 * (a + b) - centre) < 0) n = -n;
      const double d0 = n.dot(c[k] - a), d1 = n.dot(c[(k + 1) % 4] - b);
      const bool first_acute = cosine(k) > cosine((k + 1) % 4);
      acute[band].push_back(first_acute ? d0 : d1), obtuse[band].push_back(first_acute ? d1 : d0);
      turn[band].push_back(1000 * (first_acute ? d0 - d1 : d1 - d0) / cv::norm(b - a));
    }
  }
  void Print() const {
    std::printf(
        "view deg: markers, diagonal long / short %%, side end offset acute / obtuse px, turn mrad\n");
    for (int band = 0; band < kCount; ++band)
      if (!long_diag[band].empty())
        std::printf("%g-%g: %zu, %+.3f / %+.3f %%, %+.4f / %+.4f px, %+.2f mrad\n", kBands[band],
                    kBands[band + 1], long_diag[band].size(), testing::MeanOf(long_diag[band]),
                    testing::MeanOf(short_diag[band]), testing::MeanOf(acute[band]),
                    testing::MeanOf(obtuse[band]), testing::MeanOf(turn[band]));
  }
};

// The standard error of the values' mean.
double StandardError(const std::vector<double>& values) {
  const double mean = testing::MeanOf(values);
  double var = 0;
  for (double v : values) var += (v - mean) * (v - mean);
  return values.size() > 1 ? std::sqrt(var / (values.size() - 1) / values.size()) : NAN;
}
}  // namespace

int main(int argc, char** argv) {
  if (argc < 6) {
    std::fprintf(stderr,
                 "usage: diag_side_bias ref|syn|exact BLUR_PX MIN_SIDE_PX MAX_SIDE_PX IMAGES | sim BLUR_PX "
                 "RADIUS_M SIZE_M FRAMES | cond NAME MIN_SIDE_PX MAX_SIDE_PX IMAGES\n");
    return 2;
  }
  const bool reference = std::string(argv[1]) == "ref" || std::string(argv[1]) == "cond";
  const testing::Imaging* condition = nullptr;
  std::vector<testing::Imaging> catalogue = testing::ImagingCatalogue();
  if (const char* spec = std::getenv("MCMT_IMAGING_OVERRIDE"))
    for (testing::Imaging& im : catalogue) testing::OverrideImaging(spec, &im);
  if (std::string(argv[1]) == "cond") {
    for (const testing::Imaging& im : catalogue)
      if (!condition && im.name.find(argv[2]) != std::string::npos) condition = &im;
    if (!condition) {
      std::fprintf(stderr, "diag_side_bias: no condition named like '%s' in ImagingCatalogue()\n", argv[2]);
      return 2;
    }
  }
  const double blur = condition ? condition->blur_sigma : std::atof(argv[2]), side0 = std::atof(argv[3]),
               side1 = std::atof(argv[4]);
  const int images = std::atoi(argv[5]);
  auto dict = LoadDictionary("DICT_6X6_250");
  const int cells = dict->markerSize + 2;
  std::mt19937_64 rng(static_cast<uint64_t>(Env("SEED", 1)));
  std::normal_distribution<double> perturb(0.0, Env("PERTURB", 0.3));
  testing::CornerErrors errors;
  int total = 0, refined = 0;
  double sigma_sum = 0;
  std::vector<double> side_mid, side_turn;
  // Per band of the marker's extent across a side (px along its normal; kExtentBands): the sides'
  // signed middle offsets (outward +).
  constexpr double kExtentBands[] = {0, 8, 10, 12, 14, 16, 20, 30, 1e9};
  constexpr int kBands = sizeof(kExtentBands) / sizeof(kExtentBands[0]) - 1;
  std::vector<double> side_by_extent[kBands];
  std::map<int, std::vector<double>> per_id;
  std::map<std::pair<int, int>, std::vector<double>> per_id_side;  // (id, side k): middle offsets (IDS)
  ShapeByAngle shape;
  // An inverted print's markers searched and refined as such.
  MarkerDetector detector = testing::ReferenceDetector(condition ? *condition : testing::Imaging());
  const int polarity = condition && condition->inverted ? -1 : 1;
  const bool detect = Env("DETECT", 0) > 0;
  // SIDES (file): every side's marker number, side, extent across it (px) and offset (px, outward +), to
  // pair two runs side by side (bench/results/2026-12-07-sharpstep-pair.py).
  FILE* sides_out = std::getenv("SIDES") ? std::fopen(std::getenv("SIDES"), "w") : nullptr;
  auto refine = [&](const cv::Mat& rendered, const std::vector<testing::RenderedMarker>& truth) {
    // SMOOTH: as the detector's refinement on sharp frames (DetectorOptions::sharp_smoothing).
    cv::Mat image = rendered;
    if (Env("SMOOTH", 0) > 0) cv::GaussianBlur(rendered, image, cv::Size(0, 0), Env("SMOOTH", 0));
    const std::vector<marker_t> found = detect ? detector.Detect(rendered) : std::vector<marker_t>();
    for (const testing::RenderedMarker& t : truth) {
      ++total;
      std::array<cv::Point2d, 4> c;
      for (int k = 0; k < 4; ++k) c[k] = t.corners[k] + cv::Point2d(perturb(rng), perturb(rng));
      if (Env("START_OUT", 0) != 0) {  // START_OUT (px): every start corner moved outward from the centre
        cv::Point2d mid(0, 0);
        for (const auto& p : t.corners) mid += p * 0.25;
        for (int k = 0; k < 4; ++k)
          c[k] += (t.corners[k] - mid) * (Env("START_OUT", 0) / cv::norm(t.corners[k] - mid));
      }
      const cv::Mat bits = cv::aruco::Dictionary::getBitsFromByteList(
          dict->bytesList.rowRange(t.id, t.id + 1), dict->markerSize);
      double sigma = NAN;
      if (detect) {
        const marker_t* m = nullptr;
        for (const marker_t& f : found) m = f.id == t.id ? &f : m;
        if (!m) continue;
        for (int k = 0; k < 4; ++k) c[k] = cv::Point2d(m->corners[k][0], m->corners[k][1]);
        sigma = 0;
      } else if (!RefineMarkerCorners(image, cells, bits, nullptr, 1, &c, true, &sigma,
                                      Env("FITGAMMA", 1) > 0, nullptr, polarity)) {
        continue;
      }
      ++refined, sigma_sum += sigma;
      shape.Add(t, c);
      cv::Point2d centre(0, 0);
      for (const auto& p : t.corners) centre += p * 0.25;
      for (int k = 0; k < 4; ++k) {  // per side: the error of its middle and of its direction (corners)
        const cv::Point2d a = t.corners[k], b = t.corners[(k + 1) % 4];
        cv::Point2d n(b.y - a.y, a.x - b.x);
        n *= 1.0 / cv::norm(n);
        if (n.dot(0.5 * (a + b) - centre) < 0) n = -n;
        const double d0 = n.dot(c[k] - a), d1 = n.dot(c[(k + 1) % 4] - b);
        side_mid.push_back(std::abs(0.5 * (d0 + d1))), side_turn.push_back(std::abs(0.5 * (d1 - d0)));
        per_id_side[{t.id, k}].push_back(0.5 * (d0 + d1));
        const double extent =
            0.5 * (std::abs(n.dot(t.corners[(k + 2) % 4] - a)) + std::abs(n.dot(t.corners[(k + 3) % 4] - a)));
        if (sides_out) std::fprintf(sides_out, "%d %d %.3f %.6f\n", total, k, extent, 0.5 * (d0 + d1));
        for (int band = 0; band < kBands; ++band)
          if (extent >= kExtentBands[band] && extent < kExtentBands[band + 1])
            side_by_extent[band].push_back(0.5 * (d0 + d1));
      }
      testing::CornerErrors one;
      testing::AddCornerErrors(t, c, &one);
      testing::AddCornerErrors(t, c, &errors);
      per_id[t.id].insert(per_id[t.id].end(), one.offsets.begin(), one.offsets.end());
      if (std::getenv("PER"))
        std::printf("id %d side %.1f px angle %.0f deg offset %+.3f px blur %.2f px\n", t.id, t.side_px,
                    t.view_angle_deg, testing::MeanOf(one.offsets), sigma);
    }
  };
  if (std::string(argv[1]) == "sim") {
    ForEachSimImage(blur, side0, side1, images, refine);
    for (const auto& [key, offsets] : per_id_side)
      std::printf("id %d side %d: %zu, offset %+.4f px\n", key.first, key.second, offsets.size(),
                  testing::MeanOf(offsets));
    for (const auto& [id, offsets] : per_id)
      std::printf("id %d: %zu corners, offset %+.4f px\n", id, offsets.size(), testing::MeanOf(offsets));
  }
  for (int i = 0; i < images && std::string(argv[1]) != "sim"; ++i) {
    std::vector<testing::RenderedMarker> truth;
    const cv::Mat image = std::string(argv[1]) == "exact"
                              ? RenderExact(*dict, blur, side0, side1, rng, &truth)
                              : Render(*dict, reference, blur, side0, side1, rng, &truth, condition);
    refine(image, truth);
  }
  const double mean = testing::MeanOf(errors.offsets);
  double var = 0;
  for (double o : errors.offsets) var += (o - mean) * (o - mean) / errors.offsets.size();
  std::printf(
      "%s%s blur %.2f px, %.2f-%.2f: refined %d of %d, offset %+.4f px (sd %.3f), median error %.3f "
      "px, "
      "fitted blur %.2f px\n",
      argv[1], condition ? (" " + condition->name).c_str() : "", blur, side0, side1, refined, total, mean,
      std::sqrt(var), testing::MedianOf(errors.errors), sigma_sum / refined);
  std::printf("per side: median |middle offset| %.3f px, median |corner offset from the turn| %.3f px\n",
              testing::MedianOf(side_mid), testing::MedianOf(side_turn));
  std::printf("side offset (mean of its ends, outward +) by the marker's extent across it:");
  for (int band = 0; band < kBands; ++band)
    if (!side_by_extent[band].empty())
      std::printf(" %g-%g px %+.4f (%zu, se %.4f);", kExtentBands[band], kExtentBands[band + 1],
                  testing::MeanOf(side_by_extent[band]), side_by_extent[band].size(),
                  StandardError(side_by_extent[band]));
  std::printf("\n");
  if (Env("IDS", 0) > 0)  // each (id, side)'s mean middle offset, outward + (IDS: ids drawn from 0..IDS-1)
    for (const auto& [key, offsets] : per_id_side)
      std::printf("id %d side %d: %zu, offset %+.4f px (se %.4f)\n", key.first, key.second, offsets.size(),
                  testing::MeanOf(offsets), StandardError(offsets));
  shape.Print();
  if (sides_out) std::fclose(sides_out);
}
