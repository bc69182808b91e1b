// Where the reference renderer's "hard" condition's corner error comes from: "hard" with one ingredient
// taken out at a time (and a few ingredients alone), on bench_accuracy's matrix of sizes x view angles,
// each scene rendered once in linear light and put through the camera under `repeats` noise draws (the
// motion's direction fixed per image), so that a corner's error splits into its mean over the draws
// (bias: the model's misfit) and the draws' scatter around it (noise).
//   diag_hard [images per cell (2)] [repeats (1)] [|variant|variant|... | all] [known | gamma] > corners.csv
// Prints one CSV line per corner found: variant, repeat, cell, image, id, side px, view deg, corner,
// corner angle deg, error x, y, error along the outward normals of the sides before and after it.
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "tests/detector/accuracy.h"

using namespace mcmt;
using testing::Imaging;

namespace {
struct Variant {
  std::string name;
  Imaging im;
};

std::vector<Variant> Variants() {
  const Imaging hard = testing::CatalogueCondition("hard");
  std::vector<Variant> v;
  auto add = [&](const std::string& name, auto change) {
    Imaging im = hard;
    change(im);
    v.push_back({name, im});
  };
  add("hard", [](Imaging&) {});
  add("-noise", [](Imaging& im) { im.read_noise = 0, im.shot_noise = 0; });
  add("-jpeg", [](Imaging& im) { im.jpeg_quality = 0; });
  add("-sharpen", [](Imaging& im) { im.sharpen = 0; });
  add("-gamma", [](Imaging& im) { im.gamma = 1; });
  add("-defocus", [](Imaging& im) { im.defocus_radius = 0; });
  add("-motion", [](Imaging& im) { im.motion_px = 0; });
  add("-texture", [](Imaging& im) { im.surface_texture = 0; });
  add("-shading", [](Imaging& im) { im.face_shading = 0, im.gradient = 0; });
  add("-noise-jpeg", [](Imaging& im) { im.read_noise = 0, im.shot_noise = 0, im.jpeg_quality = 0; });
  add("-noise-jpeg-sharpen",
      [](Imaging& im) { im.read_noise = 0, im.shot_noise = 0, im.jpeg_quality = 0, im.sharpen = 0; });
  add("-noise-jpeg-sharpen-gamma", [](Imaging& im) {
    im.read_noise = 0, im.shot_noise = 0, im.jpeg_quality = 0, im.sharpen = 0, im.gamma = 1;
  });
  // Only the optics (blur, defocus, motion, the margin): no noise, JPEG, sharpening, gamma, shading, texture.
  auto optics = [](Imaging& im) {
    im.read_noise = 0, im.shot_noise = 0, im.jpeg_quality = 0, im.sharpen = 0, im.gamma = 1;
    im.face_shading = 0, im.gradient = 0, im.surface_texture = 0;
  };
  add("optics only", optics);
  add("optics + texture", [&](Imaging& im) { optics(im), im.surface_texture = hard.surface_texture; });
  add("optics + shading",
      [&](Imaging& im) { optics(im), im.face_shading = hard.face_shading, im.gradient = hard.gradient; });
  add("optics + gamma", [&](Imaging& im) { optics(im), im.gamma = hard.gamma; });
  add("optics + gamma + sharpen",
      [&](Imaging& im) { optics(im), im.gamma = hard.gamma, im.sharpen = hard.sharpen; });
  add("optics + noise",
      [&](Imaging& im) { optics(im), im.read_noise = hard.read_noise, im.shot_noise = hard.shot_noise; });
  add("optics + jpeg", [&](Imaging& im) { optics(im), im.jpeg_quality = hard.jpeg_quality; });
  add("optics - defocus", [&](Imaging& im) { optics(im), im.defocus_radius = 0; });
  add("optics - motion", [&](Imaging& im) { optics(im), im.motion_px = 0; });
  add("optics gaussian 0.6",
      [&](Imaging& im) { optics(im), im.defocus_radius = 0, im.motion_px = 0, im.blur_sigma = 0.6; });
  add("optics margin 1", [&](Imaging& im) { optics(im), im.margin_cells = 1.0; });
  add("optics no margin", [&](Imaging& im) { optics(im), im.margin_cells = 0.0; });
  add("-texture-shading", [](Imaging& im) { im.surface_texture = 0, im.face_shading = 0, im.gradient = 0; });
  add("margin 1", [](Imaging& im) { im.margin_cells = 1.0; });
  return v;
}
}  // namespace

int main(int argc, char** argv) {
  const int images = argc > 1 ? std::atoi(argv[1]) : 2;
  const int repeats = argc > 2 ? std::atoi(argv[2]) : 1;
  const char* only = argc > 3 && std::strcmp(argv[3], "all") != 0 ? argv[3] : nullptr;
  // "known": the detector is given the camera's gamma and sharpening; "gamma": only its gamma.
  const bool known = argc > 4 && std::strcmp(argv[4], "known") == 0;
  const bool known_gamma = known || (argc > 4 && std::strcmp(argv[4], "gamma") == 0);
  cv::setNumThreads(1);
  auto dict = LoadDictionary("DICT_6X6_250");
  MarkerConfig mc;
  mc.dictionary = "DICT_6X6_250";
  std::printf("variant,repeat,cell,image,id,side_px,view_deg,corner,corner_deg,ex,ey,n_before,n_after\n");
  for (const Variant& v : Variants()) {
    if (only && !std::strstr(only, ("|" + v.name + "|").c_str())) continue;
    DetectorOptions options;
    if (known_gamma && v.im.gamma != 1.0) options.gamma = v.im.gamma;
    if (known && v.im.sharpen > 0) options.unsharp_amount = v.im.sharpen, options.unsharp_sigma = 1.0;
    for (int s = 0; s < 3; ++s)
      for (int g = 0; g < 3; ++g) {
        const int cell = 3 * s + g;
        const uint64_t seed = testing::BenchSeed(12, s, g);
        std::mt19937_64 scene_rng(seed);
        for (int i = 0; i < images; ++i) {
          std::vector<testing::RenderedMarker> truth;
          const cv::Mat linear =
              testing::RenderReferenceLinear(*dict, testing::BenchScene(s, g), v.im, scene_rng, &truth);
          for (int r = 0; r < repeats; ++r) {
            std::mt19937_64 camera_rng(seed * 7919 + i), noise_rng(seed * 104729 + 1000 * i + r);
            const cv::Mat image =
                testing::reference::CameraPipeline(linear.clone(), v.im, camera_rng, &noise_rng);
            MarkerDetector detector(mc, options);
            for (const marker_t& m : detector.Detect(image))
              for (const auto& t : truth) {
                if (t.id != m.id || t.view_angle_deg > 75) continue;
                for (int k = 0; k < 4; ++k) {
                  const cv::Point2d e(m.corners[k][0] - t.corners[k].x, m.corners[k][1] - t.corners[k].y);
                  const cv::Point2d a = t.corners[(k + 3) % 4] - t.corners[k],
                                    b = t.corners[(k + 1) % 4] - t.corners[k];
                  const double angle = std::acos(a.dot(b) / cv::norm(a) / cv::norm(b)) * 180 / M_PI;
                  std::printf("%s,%d,%d,%d,%d,%.3f,%.3f,%d,%.2f,%.5f,%.5f,%.5f,%.5f\n", v.name.c_str(), r,
                              cell, i, m.id, t.side_px, t.view_angle_deg, k, angle, e.x, e.y,
                              e.dot(testing::OutwardNormal(t, (k + 3) % 4)),
                              e.dot(testing::OutwardNormal(t, k)));
                }
              }
          }
        }
      }
    std::fflush(stdout);
  }
  return 0;
}
