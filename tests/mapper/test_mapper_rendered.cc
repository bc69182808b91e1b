// Rendered images -> the project's detector (DetectRecording) -> mapper, against the simulator's
// ground truth: the whole offline pipeline without LCM.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "core/config.h"
#include "core/dictionary.h"
#include "core/lcm_util.h"
#include "detector/detector.h"
#include "mapper/mapper.h"
#include "sim/eval.h"
#include "sim/sim.h"
#include "tests/mapper/reference_rig_view.h"
#include "tests/mapper/rendered_session.h"
#include "tests/support/temp_dir.h"

namespace mcmt {
namespace {

namespace fs = std::filesystem;

struct RenderedCase {
  sim::ObjectKind object;
  double radius;
};

class MapperRendered : public ::testing::TestWithParam<RenderedCase> {};

// The paper's three objects at its smallest, middle and largest radii, rendered, detected and mapped; the
// issue's bounds: object translation 0.5 mm, rotation 0.3 deg, camera position 2 mm, configuration 0.3 mm.
// The pentagon only at 0.7 m: its 2.5 cm markers are 14 px wide at 1 m and 10 px at 1.3 m with these
// 640x480 cameras, below what a 6x6 code can be read at reliably (and below the detector's default
// min_perimeter_px at 1.3 m); the mapper itself is checked on it at every radius in test_mapper_sim.
TEST_P(MapperRendered, WithinTheIssueBounds) {
  const RenderedCase c = GetParam();
  const std::string name = sim::ObjectKindNames()[static_cast<int>(c.object)];
  const test::TempDir tmp("mapper_rendered_" + name);
  const std::string dir = tmp / "session";
  sim::DatasetOptions options;
  options.out_dir = dir;
  options.object.kind = c.object;
  options.object.marker_size = c.object == sim::ObjectKind::kPentagon ? 0.025 : 0.04;
  options.rig.num_cameras = 5;
  options.rig.radius = c.radius;
  options.trajectory.frames = 60;
  options.trajectory.seed = 4;
  options.threads = 2;
  const sim::DatasetSummary summary = sim::GenerateDataset(options);
  const RigConfig rig = LoadRigConfig(dir + "/rig.yaml");
  Mapper mapper(MapperOptions::FromConfig(rig));
  for (const CameraConfig& camera : rig.cameras)
    for (const detections_t& d : DetectRecording(rig, camera.name)) mapper.Add(d);
  const MapResult result = mapper.Solve();
  const sim::EvalResult e = sim::Evaluate(summary.truth, &result.map, &result.trajectory);
  const std::string what = name + " at " + std::to_string(c.radius) + " m";
  EXPECT_EQ(e.mapped_cameras, 5) << what;
  EXPECT_EQ(e.mapped_markers, e.gt_markers) << what;
  EXPECT_LT(e.object_translation_aligned_mm.mean, 0.5) << what;
  EXPECT_LT(e.object_rotation_deg.mean, 0.3) << what;
  EXPECT_LT(e.camera_position_mm.mean, 2.0) << what;
  EXPECT_LT(e.configuration_mm.mean, 0.3) << what;
  RecordProperty("errors", what + ": " + std::to_string(e.object_translation_aligned_mm.mean) + " mm, " +
                               std::to_string(e.object_rotation_deg.mean) + " deg, cam " +
                               std::to_string(e.camera_position_mm.mean) + " mm, config " +
                               std::to_string(e.configuration_mm.mean) + " mm, rms " +
                               std::to_string(result.map.rms_px) + " px");
}

INSTANTIATE_TEST_SUITE_P(PapersObjectsAndRadii, MapperRendered,
                         ::testing::Values(RenderedCase{sim::ObjectKind::kFourSided, 0.7},
                                           RenderedCase{sim::ObjectKind::kFourSided, 1.0},
                                           RenderedCase{sim::ObjectKind::kFourSided, 1.3},
                                           RenderedCase{sim::ObjectKind::kBox, 0.7},
                                           RenderedCase{sim::ObjectKind::kBox, 1.0},
                                           RenderedCase{sim::ObjectKind::kBox, 1.3},
                                           RenderedCase{sim::ObjectKind::kPentagon, 0.7}));

// Issue 15: the paper's rig at 1.0 m, mcmt-sim's default imaging, 150 frames, every frame detected in
// memory. The detector's corners of markers seen above 60 deg are 2-6x less precise than below 45 (RMS
// 0.16-0.57 px against 0.09, measured with bench_imaging_maps MCMT_IMAGING_DUMP); weighted equally they
// dominated the cameras' error: 0.68 mm (scale +0.052 %) without the view weighting, 0.23 mm with power 3
// (scale -0.017 %), against 0.27-0.38 mm from the true corners + 0.07 px noise.
TEST(MapperRenderedViews, ForeshortenedMarkersWeightedByTheirPrecision) {
  const testing::RenderedMapSession s = testing::MakeRenderedMapSession(1.0, 150);
  const sim::Renderer renderer(s.object, s.markers.dictionary);
  MapperOptions mo = s.Mapping();
  mo.view_weight_power = 3;  // off by default: it costs the biased conditions (BENCHMARKS.md)
  Mapper mapper(mo);
  for (size_t c = 0; c < s.cameras.size(); ++c) {
    MarkerDetector detector(s.markers, DetectorOptions());
    detector.SetCamera(s.cameras[c].model);
    for (const sim::SimFrame& f : s.trajectory) mapper.Add(s.Detect(renderer, c, f, &detector));
  }
  const sim::GroundTruth truth = s.Truth();
  const MapResult result = mapper.Solve();
  const sim::EvalResult e = sim::Evaluate(truth, &result.map, nullptr);
  EXPECT_EQ(e.mapped_cameras, 5);
  EXPECT_LT(e.camera_position_mm.mean, 0.4);
  EXPECT_LT(e.configuration_mm.mean, 0.05);
  RecordProperty("camera_mm", std::to_string(e.camera_position_mm.mean));
}

// The reference renderer's view of the body (tests/mapper/reference_rig_view.h): every pixel inside the
// body's outline (convex; at least half a pixel diagonal inside it) is the surface's level where all faces
// are lit alike, also on the edges between two faces. Painted face by face, those edges took the
// background's level into their pixels (a later face's pass saw the earlier one's pixel means): on the
// paper's rig at 1.3 m mcmt-sim's exact render differed there by -6.4 gray levels on average, up to 27
// (bench/sim/diag_render_compare.cc; bench/results/2026-12-06-sharpturn.md). Markers left out (surface only),
// no noise; 20 frames x 5 cameras.
TEST(MapperReferenceRenders, EdgesBetweenFacesShowNoBackground) {
  testing::RenderedMapSession s = testing::MakeRenderedMapSession(1.3, 20);
  s.object.markers.clear();
  const cv::Ptr<cv::aruco::Dictionary> dictionary = LoadDictionary(s.markers.dictionary);
  testing::Imaging im;
  im.read_noise = 0;
  const double level = im.surface * im.exposure;
  int inside = 0, off = 0;
  double worst = 0;
  for (size_t c = 0; c < s.cameras.size(); ++c)
    for (const sim::SimFrame& f : s.trajectory) {
      const cv::Mat image =
          testing::RenderReferenceRigView(*dictionary, s.object, s.cameras[c], f.rig_from_object, im, 1);
      const Rigid3 cam_from_object = s.cameras[c].rig_from_cam.inverse() * f.rig_from_object;
      const CameraModel& m = s.cameras[c].model;
      std::vector<cv::Point2f> points, hull;
      for (const sim::SimFace& face : s.object.faces)
        for (const Eigen::Vector3d& p : face.vertices) {
          const Eigen::Vector2d pixel = m.Project(cam_from_object * p);
          points.emplace_back(pixel.x(), pixel.y());
        }
      cv::convexHull(points, hull);
      for (int y = 0; y < image.rows; ++y)
        for (int x = 0; x < image.cols; ++x) {
          if (cv::pointPolygonTest(hull, cv::Point2f(x, y), true) < 0.75) continue;
          ++inside;
          const double d = std::abs(image.at<uint8_t>(y, x) - level);
          worst = std::max(worst, d);
          off += d > 1.0;
        }
    }
  std::printf("%d pixels inside the body, %d off the surface's level by more than 1, worst %.1f\n", inside,
              off, worst);
  EXPECT_GT(inside, 10000);
  EXPECT_EQ(off, 0);
}

// The paper's rig at 1.0 m, 150 frames, drawn by the independent reference renderer
// (tests/mapper/reference_rig_view.h) under `imaging`, detected with the defaults and mapped once per
// corner weighting (corner_weights: equal, sides); prints and returns each map's errors against the truth.
// `radius_m`: the rig's radius (the cameras' distance to the object's centre), m.
std::vector<sim::EvalResult> MapReferenceSession(const testing::Imaging& imaging,
                                                 const std::vector<std::string>& corner_weights,
                                                 double radius_m = 1.0) {
  const testing::RenderedMapSession s = testing::MakeRenderedMapSession(radius_m, 150);
  const cv::Ptr<cv::aruco::Dictionary> dictionary = LoadDictionary(s.markers.dictionary);
  std::vector<std::unique_ptr<Mapper>> mappers;
  for (const std::string& weights : corner_weights) {
    MapperOptions o = s.Mapping();
    o.corner_weighting.mode = weights;
    mappers.push_back(std::make_unique<Mapper>(o));
  }
  for (size_t c = 0; c < s.cameras.size(); ++c) {
    MarkerDetector detector(s.markers, DetectorOptions());
    detector.SetCamera(s.cameras[c].model);
    for (const sim::SimFrame& f : s.trajectory) {
      const cv::Mat image = testing::RenderReferenceRigView(*dictionary, s.object, s.cameras[c],
                                                            f.rig_from_object, imaging, 1009 * c + f.seq);
      const auto detections = s.Detect(image, c, f, &detector);
      for (auto& mapper : mappers) mapper->Add(detections);
    }
  }
  std::vector<sim::EvalResult> errors;
  for (size_t i = 0; i < mappers.size(); ++i) {
    const MapResult result = mappers[i]->Solve();
    errors.push_back(sim::Evaluate(s.Truth(), &result.map, nullptr));
    const sim::EvalResult& e = errors.back();
    std::printf(
        "reference renderer, %s, %.1f m, corner weights %s: scale %+.3f %%, cameras %.2f / %.2f mm, "
        "configuration %.3f mm\n",
        imaging.name.c_str(), radius_m, corner_weights[i].c_str(), 100 * e.scale_error,
        e.camera_position_mm.mean, e.camera_position_mm.max, e.configuration_mm.mean);
  }
  return errors;
}

struct MapBounds {
  double scale, camera_mm, configuration_mm;
};
void ExpectWithin(const sim::EvalResult& e, const MapBounds& b) {
  EXPECT_EQ(e.mapped_cameras, 5);
  EXPECT_EQ(e.mapped_markers, e.gt_markers);
  EXPECT_LT(std::abs(e.scale_error), b.scale);
  EXPECT_LT(e.camera_position_mm.mean, b.camera_mm);
  EXPECT_LT(e.configuration_mm.mean, b.configuration_mm);
}

// Issue 15, truth from outside mcmt-sim: the plain condition. Beyond 60 deg each marker's corners came out
// turned along its sides on these renders (long diagonal 0.9 % short, short one 1.6 % long), and the
// map's scale followed those long diagonals: +0.101 %, cameras 1.06 / 1.31 mm with every corner weighing
// the same. The detector now turns the sides of skewed quads (detector.cc TurnSkewedSides;
// DetectorAccuracy.SteepViewsKeepTheirDiagonals):
// - corner_weights equal (the default): measured +0.038 %, cameras 0.50 / 0.60 mm, configuration 0.059 mm;
// - corner_weights sides (a corner is barely located along two sides that meet at a narrow angle; not the
//   default: on the real caliscope board it moves the scale by +0.03 %, test_mapper_realdata): measured
//   +0.019 %, 0.30 / 0.44 mm, 0.047 mm.
// Bounds: the issue's scale target (0.05 %), the cameras and configuration at what is measured with room.
TEST(MapperReferenceRenders, PaperRigFromAnIndependentRenderer) {
  const std::vector<sim::EvalResult> e =
      MapReferenceSession(testing::ImagingCatalogue()[0], {"equal", "sides"});
  ExpectWithin(e[0], {0.0005, 0.7, 0.08});
  ExpectWithin(e[1], {0.0005, 0.5, 0.07});
}

// Issue 15: markers printed without a margin on a grey surface. About a third of their sides' fits put a
// faint bright strip beyond the edge (a margin under half a cell barely above the surround, no print's),
// paired with a per-side gamma off the image's, which moved the edge outward; this map came out -0.327 %,
// cameras 3.29 / 3.52 mm, configuration 0.127 mm. Such a strip is now refitted with one surround level
// (side_model.cc kMinMarginExcess). With the strip's area bound at 0.04 cell (its width times its excess
// over the surround, in parts of the code-to-surround contrast) strips of 0.04-0.1 cell stayed (166 sides
// of the bench's no-margin map, +0.10..0.15 px outward each): -0.233 %, 2.35 / 2.73 mm, 0.094 mm. With the
// bound at 0.1 cell (the narrowest printed margin, "hard"'s 0.3 cell of paper, fits at 0.1 or more):
// measured -0.199 %, 2.01 / 2.27 mm, 0.085 mm. Not yet the issue's 0.05 %: the single-surround fits of
// skewed quads (corner angles below 60 deg) lie 0.05 px outward (plain's two-level fits 0.015 px;
// bench/results/2026-12-06-nomargin.md). Bounds: between the 0.04 and the 0.1 figures.
TEST(MapperReferenceRenders, NoMarginIsNotShrunkByAFaintStrip) {
  const testing::Imaging no_margin = testing::ImagingCatalogue()[1];
  ASSERT_EQ(no_margin.name, "no margin, grey surface");
  ExpectWithin(MapReferenceSession(no_margin, {"equal"})[0], {0.0021, 2.2, 0.2});
}

// Issue 15: a 2-cell paper margin over a white surface (0.8 of the paper) at 1.3 m (cells 1.1-1.9 px). The
// margin's excess over the surround is small and MarginWeight's area gate left its level free; its far step
// lies near the side profiles' end (1.6 cells + 1 px) and its level and width traded, the edge with them:
// -0.131 %, cameras 1.71 / 1.94 mm, configuration 0.064 mm. Wide paper margins are now tied to the paper
// (side_model.cc kWideTieCells): measured -0.081 %, 1.06 / 1.27 mm, 0.057 mm
// (bench/results/2026-12-07-twocell2.md). Not yet the issue's 0.05 %. Bounds: between the two figures.
TEST(MapperReferenceRenders, TwoCellMarginAt1300mmIsTiedToThePaper) {
  const testing::Imaging two_cell = testing::CatalogueCondition("two-cell margin, white");
  ExpectWithin(MapReferenceSession(two_cell, {"equal"}, 1.3)[0], {0.001, 1.4, 0.1});
}

}  // namespace
}  // namespace mcmt
