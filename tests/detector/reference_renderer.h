// An independent reference renderer of printed markers for the detector's accuracy tests and benchmark.
// It shares no code with sim/render.cc: every marker (its cells, the print's margin and the surface it
// is glued on) is a set of convex quadrilaterals under a homography, point-sampled at kSuper x kSuper
// points per pixel by an exact scanline test of each sample's centre (pixel centres at integer
// coordinates, pixel (0, 0) covers [-0.5, 0.5]^2) and box-filtered down, in linear light. A camera
// pipeline follows: optics (Gaussian, defocus disc, motion line), vignetting, level-dependent noise,
// gamma encoding, sharpening, 8-bit quantisation and JPEG.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <opencv2/aruco.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "tests/detector/synthetic.h"

namespace mcmt::testing {

// One imaging condition: the print, the surface, the light and the camera.
struct Imaging {
  std::string name = "plain";
  double margin_cells = 1.0;        // margin of the print around the marker, cells (0: none)
  bool inverted = false;            // white-on-black print (markers.inverted): white border, black margin
  double ink = 0.04, paper = 0.85;  // reflectances of the ink and the paper
  double surface = 0.5;             // reflectance of the surface the print is glued on
  double surface_texture = 0.0;     // relative amplitude of the surface's wood-like grain (0: plain)
  double face_shading = 0.0;        // each marker's face lit by a factor in [1 - s, 1]
  double gradient = 0.0;            // light falls linearly by this fraction across the image
  double vignetting = 0.0;          // light falls by this fraction at the image corners (r^2 law)
  double blur_sigma = 0.0;          // Gaussian optics, px
  double defocus_radius = 0.0;      // defocus disc radius, px
  double motion_px = 0.0;           // motion blur: length of the line, px (random direction)
  double read_noise = 2.0;          // gray levels (linear), at any level
  double shot_noise = 0.0;          // variance added per linear gray level (photon noise)
  double gamma = 1.0;               // encoding: 255 (v / 255)^(1 / gamma)
  double sharpen = 0.0;             // unsharp mask amount (sigma 1 px) after encoding; < 0: a blur
  bool sharpen_linear = false;      // the unsharp mask on linear light, before the encoding
  int jpeg_quality = 0;             // 0: none
  double exposure = 255.0;          // linear gray level of a reflectance-1 surface in full light
};

// The catalogue the accuracy matrix runs over: each condition stresses one thing, "webcam" and
// "hard" combine them.
inline std::vector<Imaging> ImagingCatalogue() {
  std::vector<Imaging> c;
  Imaging base;
  c.push_back(base);
  Imaging x = base;
  x.name = "no margin, grey surface", x.margin_cells = 0, x.surface = 0.35, c.push_back(x);
  x = base, x.name = "half-cell margin, black tool", x.margin_cells = 0.5, x.surface = 0.06, c.push_back(x);
  x = base, x.name = "half-cell margin, wood", x.margin_cells = 0.5, x.surface = 0.45;
  x.surface_texture = 0.25, c.push_back(x);
  x = base, x.name = "two-cell margin, white", x.margin_cells = 2, x.surface = 0.8, c.push_back(x);
  x = base, x.name = "shading + gradient", x.face_shading = 0.5, x.gradient = 0.4, x.vignetting = 0.3;
  c.push_back(x);
  x = base, x.name = "gaussian blur 1.2", x.blur_sigma = 1.2, c.push_back(x);
  x = base, x.name = "defocus r 1.5", x.defocus_radius = 1.5, c.push_back(x);
  x = base, x.name = "motion 2.5 px", x.motion_px = 2.5, c.push_back(x);
  x = base, x.name = "gamma 2.2", x.gamma = 2.2, x.blur_sigma = 0.8, c.push_back(x);
  x = base, x.name = "shot noise", x.read_noise = 1.5, x.shot_noise = 0.15, x.exposure = 200, c.push_back(x);
  x = base, x.name = "webcam", x.margin_cells = 0.6, x.surface = 0.3, x.face_shading = 0.3, x.gradient = 0.2;
  x.vignetting = 0.25, x.blur_sigma = 0.7, x.gamma = 2.2, x.sharpen = 0.6, x.jpeg_quality = 75;
  x.shot_noise = 0.08, c.push_back(x);
  x = base, x.name = "hard", x.margin_cells = 0.3, x.surface = 0.7, x.surface_texture = 0.2;
  x.face_shading = 0.4, x.gradient = 0.3, x.defocus_radius = 1.0, x.motion_px = 1.5, x.gamma = 2.0;
  x.sharpen = 0.4, x.jpeg_quality = 60, x.shot_noise = 0.1, c.push_back(x);
  // Added after the others, so that their indices (bench_imaging_maps' MCMT_IMAGING_CONDITIONS) and
  // seeds (BenchSeed, SmallSeed) stay as they were.
  x = base, x.name = "inverted print", x.inverted = true, c.push_back(x);
  // A surround between the black tool's and the grey one's: the side model's margin penalty is gated by
  // the surround's level b = (S - ink) / (paper - ink) between 0.1 and 0.2 (side_model.cc MarginWeight),
  // surfaces 0.12-0.20 here; 0.15 is b = 0.14, inside that range.
  x = base, x.name = "half-cell margin, dark grey", x.margin_cells = 0.5, x.surface = 0.15, c.push_back(x);
  return c;
}

// The catalogue's condition named `name`; throws std::invalid_argument if there is none.
inline Imaging CatalogueCondition(const std::string& name) {
  for (const Imaging& im : ImagingCatalogue())
    if (im.name == name) return im;
  throw std::invalid_argument("no imaging condition named \"" + name + "\" in ImagingCatalogue()");
}

// One "name=value" item of a benches' override spec ("motion_px=0,jpeg_quality=0").
struct OverrideItem {
  std::string text, name;  // "motion_px=0", "motion_px"
  double value = 0.0;
};

// The items of a spec, in order. Throws std::invalid_argument naming the item when one has no '=' or a
// value that is not a number. The one parser of MCMT_IMAGING_OVERRIDE (OverrideImaging) and of
// bench_imaging_maps' MCMT_IMAGING_SIM_OVERRIDE.
inline std::vector<OverrideItem> ParseOverrideSpec(const std::string& spec) {
  std::vector<OverrideItem> items;
  size_t begin = 0;
  while (begin < spec.size()) {
    const size_t end = std::min(spec.find(',', begin), spec.size());
    OverrideItem it;
    it.text = spec.substr(begin, end - begin);
    begin = end + 1;
    const size_t eq = it.text.find('=');
    if (eq == std::string::npos) throw std::invalid_argument("imaging override \"" + it.text + "\": no '='");
    it.name = it.text.substr(0, eq);
    const std::string value_text = it.text.substr(eq + 1);
    char* parsed_end = nullptr;
    it.value = std::strtod(value_text.c_str(), &parsed_end);
    if (value_text.empty() || *parsed_end != '\0')
      throw std::invalid_argument("imaging override \"" + it.text + "\": not a number");
    items.push_back(it);
  }
  return items;
}

// Diagnostics (benches' MCMT_IMAGING_OVERRIDE): sets the fields a spec like "motion_px=0,jpeg_quality=0"
// names to its values (numbers; sharpen_linear and inverted 0 or 1). Throws std::invalid_argument on an
// unknown field or a value that is not a number.
inline void OverrideImaging(const std::string& spec, Imaging* im) {
  struct Field {
    const char* name;
    double Imaging::*member;
  };
  static const Field kFields[] = {{"margin_cells", &Imaging::margin_cells},
                                  {"ink", &Imaging::ink},
                                  {"paper", &Imaging::paper},
                                  {"surface", &Imaging::surface},
                                  {"surface_texture", &Imaging::surface_texture},
                                  {"face_shading", &Imaging::face_shading},
                                  {"gradient", &Imaging::gradient},
                                  {"vignetting", &Imaging::vignetting},
                                  {"blur_sigma", &Imaging::blur_sigma},
                                  {"defocus_radius", &Imaging::defocus_radius},
                                  {"motion_px", &Imaging::motion_px},
                                  {"read_noise", &Imaging::read_noise},
                                  {"shot_noise", &Imaging::shot_noise},
                                  {"gamma", &Imaging::gamma},
                                  {"sharpen", &Imaging::sharpen},
                                  {"exposure", &Imaging::exposure}};
  for (const OverrideItem& item : ParseOverrideSpec(spec)) {
    const std::string& name = item.name;
    const double value = item.value;
    if (name == "jpeg_quality") {
      im->jpeg_quality = static_cast<int>(value);
    } else if (name == "sharpen_linear") {
      im->sharpen_linear = value != 0;
    } else if (name == "inverted") {
      im->inverted = value != 0;
    } else {
      const Field* f = std::find_if(std::begin(kFields), std::end(kFields),
                                    [&](const Field& x) { return name == x.name; });
      if (f == std::end(kFields)) throw std::invalid_argument("imaging override: no field \"" + name + "\"");
      im->*(f->member) = value;
    }
    im->name += " [" + item.text + "]";
  }
}

namespace reference {

constexpr int kSuper = 16;  // samples per pixel and axis

// A convex quadrilateral in image pixels with its linear level (or a grain function of the marker's
// plane coordinates when grain > 0).
struct Quad {
  std::array<cv::Point2d, 4> p;
  double level;
  double grain = 0;
  const cv::Matx33d* plane_from_image = nullptr;  // its grain's plane (nullptr: the one Paint is given)
};

// Spans of the samples of one sample row y (image coordinates) inside the convex polygon: [x0, x1).
inline bool Span(const Quad& q, double y, double* x0, double* x1) {
  double lo = -1e300, hi = 1e300;
  double area = 0;
  for (int k = 0; k < 4; ++k) area += q.p[k].x * q.p[(k + 1) % 4].y - q.p[(k + 1) % 4].x * q.p[k].y;
  const double orient = area > 0 ? 1.0 : -1.0;
  for (int k = 0; k < 4; ++k) {
    const cv::Point2d a = q.p[k], b = q.p[(k + 1) % 4];
    // Inside: orient * cross(b - a, s - a) >= 0, linear in s.x: A * x + B >= 0.
    const double A = -orient * (b.y - a.y), B = orient * ((b.x - a.x) * (y - a.y) + (b.y - a.y) * a.x);
    if (std::abs(A) < 1e-15) {
      if (B < 0) return false;
      continue;
    }
    const double x = -B / A;
    if (A > 0)
      lo = std::max(lo, x);
    else
      hi = std::min(hi, x);
  }
  *x0 = lo, *x1 = hi;
  return hi > lo;
}

// Paints the quads (in order, later ones on top) into the linear image `image` (CV_64F) over the
// rectangle `roi`: each pixel becomes the mean of its kSuper^2 point samples; samples no quad covers
// keep the pixel's previous value. `plane_from_image` maps pixels to the marker plane (for grain; a quad's
// own plane_from_image where it has one). Quads that share a pixel must be painted in one call: a later
// call sees the earlier one's pixel means, not its samples.
inline void Paint(const std::vector<Quad>& quads, const cv::Rect& roi, const cv::Matx33d& plane_from_image,
                  cv::Mat* image) {
  const int w = roi.width;
  std::vector<double> row(static_cast<size_t>(w) * kSuper), acc(w);
  for (int r = roi.y; r < roi.y + roi.height; ++r) {
    std::fill(acc.begin(), acc.end(), 0.0);
    double* out = image->ptr<double>(r);
    for (int sy = 0; sy < kSuper; ++sy) {
      const double y = r - 0.5 + (sy + 0.5) / kSuper;
      for (int i = 0; i < w * kSuper; ++i) row[i] = out[roi.x + i / kSuper];
      for (const Quad& q : quads) {
        double x0, x1;
        if (!Span(q, y, &x0, &x1)) continue;
        // Sample i has centre roi.x - 0.5 + (i + 0.5) / kSuper; inside when x0 <= centre < x1.
        const int i0 = std::max(0, static_cast<int>(std::ceil((x0 - roi.x + 0.5) * kSuper - 0.5)));
        const int i1 = std::min(w * kSuper, static_cast<int>(std::ceil((x1 - roi.x + 0.5) * kSuper - 0.5)));
        for (int i = i0; i < i1; ++i) {
          double v = q.level;
          if (q.grain > 0) {
            const double x = roi.x - 0.5 + (i + 0.5) / kSuper;
            const cv::Vec3d m =
                (q.plane_from_image ? *q.plane_from_image : plane_from_image) * cv::Vec3d(x, y, 1.0);
            const double u = m[0] / m[2], t = m[1] / m[2];
            v *= 1.0 + q.grain * std::sin(2.3 * u + 1.5 * std::sin(0.7 * t));
          }
          row[i] = v;
        }
      }
      for (int i = 0; i < w * kSuper; ++i) acc[i / kSuper] += row[i];
    }
    for (int c = 0; c < w; ++c) out[roi.x + c] = acc[c] / (kSuper * kSuper);
  }
}

inline cv::Point2d Apply(const cv::Matx33d& h, double x, double y) {
  const cv::Vec3d p = h * cv::Vec3d(x, y, 1.0);
  return {p[0] / p[2], p[1] / p[2]};
}

// The quads of one marker seen through image_from_plane (plane coordinates: the marker's black square
// is [0, cells]^2 in cells, row 0 at the top), printed with a margin on a surface (margin_cells + 2.5
// cells of it around the print; none with `with_surface` false: drawn already), lit by `light`. An
// inverted print (im.inverted) swaps ink and paper: white border and code cells, a black margin.
inline std::vector<Quad> MarkerQuads(const cv::Mat& bits, int cells, const cv::Matx33d& image_from_plane,
                                     const Imaging& im, double light, bool with_surface = true) {
  auto quad = [&](double x0, double y0, double x1, double y1, double reflectance, double grain) {
    Quad q;
    q.p = {Apply(image_from_plane, x0, y0), Apply(image_from_plane, x1, y0), Apply(image_from_plane, x1, y1),
           Apply(image_from_plane, x0, y1)};
    q.level = reflectance * light * im.exposure;
    q.grain = grain;
    return q;
  };
  const double dark = im.inverted ? im.paper : im.ink, bright = im.inverted ? im.ink : im.paper;
  std::vector<Quad> quads;
  const double s = im.margin_cells + 2.5;  // surface extent around the print
  if (with_surface) quads.push_back(quad(-s, -s, cells + s, cells + s, im.surface, im.surface_texture));
  const double m = im.margin_cells;
  if (m > 0) quads.push_back(quad(-m, -m, cells + m, cells + m, bright, 0));
  quads.push_back(quad(0, 0, cells, cells, dark, 0));
  for (int r = 1; r + 1 < cells; ++r)
    for (int c = 1; c + 1 < cells; ++c)
      if (bits.at<uint8_t>(r - 1, c - 1)) quads.push_back(quad(c, r, c + 1, r + 1, bright, 0));
  return quads;
}

// The camera pipeline on a linear image (gray levels, CV_64F): optics, vignetting, noise, encoding,
// sharpening, quantisation, JPEG. Returns 8-bit gray. The noise is drawn from `noise_rng` when given
// (diagnostics: one scene under several noise draws), else from `rng` like the motion's direction.
inline cv::Mat CameraPipeline(cv::Mat linear, const Imaging& im, std::mt19937_64& rng,
                              std::mt19937_64* noise_rng = nullptr) {
  if (im.blur_sigma > 0) cv::GaussianBlur(linear, linear, cv::Size(0, 0), im.blur_sigma);
  if (im.defocus_radius > 0) {
    const int r = static_cast<int>(std::ceil(im.defocus_radius)) + 1;
    cv::Mat k(2 * r + 1, 2 * r + 1, CV_64F, cv::Scalar(0));
    for (int y = 0; y < k.rows; ++y)  // the disc's area in each kernel cell (8x8 samples)
      for (int x = 0; x < k.cols; ++x)
        for (int a = 0; a < 8; ++a)
          for (int b = 0; b < 8; ++b) {
            const double dx = x - r - 0.5 + (b + 0.5) / 8, dy = y - r - 0.5 + (a + 0.5) / 8;
            if (dx * dx + dy * dy <= im.defocus_radius * im.defocus_radius) k.at<double>(y, x) += 1;
          }
    k /= cv::sum(k)[0];
    cv::filter2D(linear, linear, -1, k, cv::Point(-1, -1), 0, cv::BORDER_REFLECT);
  }
  if (im.motion_px > 0) {
    const double a = std::uniform_real_distribution<double>(0, M_PI)(rng);
    const int r = static_cast<int>(std::ceil(0.5 * im.motion_px)) + 1;
    cv::Mat k(2 * r + 1, 2 * r + 1, CV_64F, cv::Scalar(0));
    for (int i = 0; i < 400; ++i) {  // a line of length motion_px, bilinear splats
      const double t = (i + 0.5) / 400 - 0.5;
      const double x = r + t * im.motion_px * std::cos(a), y = r + t * im.motion_px * std::sin(a);
      const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
      const double fx = x - x0, fy = y - y0;
      k.at<double>(y0, x0) += (1 - fx) * (1 - fy), k.at<double>(y0, x0 + 1) += fx * (1 - fy);
      k.at<double>(y0 + 1, x0) += (1 - fx) * fy, k.at<double>(y0 + 1, x0 + 1) += fx * fy;
    }
    k /= cv::sum(k)[0];
    cv::filter2D(linear, linear, -1, k, cv::Point(-1, -1), 0, cv::BORDER_REFLECT);
  }
  const double cx = 0.5 * (linear.cols - 1), cy = 0.5 * (linear.rows - 1), r2max = cx * cx + cy * cy;
  std::normal_distribution<double> normal(0.0, 1.0);
  cv::Mat encoded(linear.size(), CV_64F);
  for (int y = 0; y < linear.rows; ++y)
    for (int x = 0; x < linear.cols; ++x) {
      double v = linear.at<double>(y, x);
      v *= 1.0 - im.gradient * x / linear.cols;
      v *= 1.0 - im.vignetting * ((x - cx) * (x - cx) + (y - cy) * (y - cy)) / r2max;
      v += normal(noise_rng ? *noise_rng : rng) *
           std::sqrt(im.read_noise * im.read_noise + im.shot_noise * std::max(0.0, v));
      v = std::clamp(v, 0.0, 255.0);
      encoded.at<double>(y, x) = im.sharpen_linear ? v : 255.0 * std::pow(v / 255.0, 1.0 / im.gamma);
    }
  auto sharpen = [&]() {
    cv::Mat smooth;
    cv::GaussianBlur(encoded, smooth, cv::Size(0, 0), 1.0);
    encoded = encoded + im.sharpen * (encoded - smooth);
  };
  if (im.sharpen_linear) {  // sharpened in linear light, then encoded
    if (im.sharpen != 0) sharpen();
    for (double& v : cv::Mat_<double>(encoded))
      v = 255.0 * std::pow(std::max(v, 0.0) / 255.0, 1.0 / im.gamma);
  } else if (im.sharpen != 0) {
    sharpen();
  }
  cv::Mat out;
  encoded.convertTo(out, CV_8U);  // rounds and saturates
  if (im.jpeg_quality > 0) {
    std::vector<uint8_t> buffer;
    cv::imencode(".jpg", out, buffer, {cv::IMWRITE_JPEG_QUALITY, im.jpeg_quality});
    out = cv::imdecode(buffer, cv::IMREAD_GRAYSCALE);
  }
  return out;
}

}  // namespace reference

struct ReferenceScene {
  int width = 640, height = 480;
  double focal = 600;
  double min_side_px = 15, max_side_px = 60;
  double min_angle_deg = 0, max_angle_deg = 75;
  int markers = 6;
};

namespace reference {
// The linear background: smooth clutter (an 8 x 6 grid of random levels, bicubic).
inline cv::Mat Clutter(int width, int height, const Imaging& im, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  cv::Mat small(6, 8, CV_64F), linear;
  for (int i = 0; i < small.rows * small.cols; ++i)
    small.at<double>(i) = im.exposure * (0.15 + 0.6 * uni(rng));
  cv::resize(small, linear, cv::Size(width, height), 0, 0, cv::INTER_CUBIC);
  return linear;
}
}  // namespace reference

// The linear light of a random image of markers (random ids, sizes, view angles, in-plane rotations)
// under one imaging condition, before the camera, with the exact corners (ArUco order) of every marker.
inline cv::Mat RenderReferenceLinear(const cv::aruco::Dictionary& dict, const ReferenceScene& scene,
                                     const Imaging& im, std::mt19937_64& rng,
                                     std::vector<RenderedMarker>* truth) {
  using reference::Apply;
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  const int cells = dict.markerSize + 2;
  cv::Mat linear = reference::Clutter(scene.width, scene.height, im, rng);
  truth->clear();
  std::vector<cv::Rect> used;
  const cv::Matx33d K(scene.focal, 0, scene.width / 2.0, 0, scene.focal, scene.height / 2.0, 0, 0, 1);
  for (int attempt = 0; attempt < 300 && static_cast<int>(truth->size()) < scene.markers; ++attempt) {
    const int id = std::uniform_int_distribution<int>(0, dict.bytesList.rows - 1)(rng);
    bool dup = false;
    for (const auto& t : *truth) dup = dup || t.id == id;
    if (dup) continue;
    const double side_px = scene.min_side_px + (scene.max_side_px - scene.min_side_px) * uni(rng);
    const double c0 = std::cos(scene.min_angle_deg * M_PI / 180),
                 c1 = std::cos(scene.max_angle_deg * M_PI / 180);
    const double tilt = std::acos(c0 - uni(rng) * (c0 - c1));
    const double axis = 2 * M_PI * uni(rng), roll = 2 * M_PI * uni(rng);
    const double z = scene.focal / side_px;  // a unit side at depth z is side_px wide head-on
    const double px = (0.1 + 0.8 * uni(rng)) * scene.width, py = (0.1 + 0.8 * uni(rng)) * scene.height;
    const cv::Vec3d centre((px - scene.width / 2.0) * z / scene.focal,
                           (py - scene.height / 2.0) * z / scene.focal, z);
    // Rotation: roll about z, tilt about an in-plane axis, then turn the marker to face its viewing ray.
    cv::Mat r_roll, r_tilt, r_ray = cv::Mat::eye(3, 3, CV_64F);
    cv::Rodrigues(cv::Mat(cv::Vec3d(0, 0, roll)), r_roll);
    cv::Rodrigues(cv::Mat(cv::Vec3d(std::cos(axis), std::sin(axis), 0) * tilt), r_tilt);
    const cv::Vec3d ray = centre / cv::norm(centre), zaxis(0, 0, 1), turn = zaxis.cross(ray);
    if (cv::norm(turn) > 1e-12)
      cv::Rodrigues(cv::Mat(turn / cv::norm(turn) * std::asin(std::min(1.0, cv::norm(turn)))), r_ray);
    const cv::Matx33d R = cv::Matx33d(r_ray) * cv::Matx33d(r_tilt) * cv::Matx33d(r_roll);
    // Plane coordinates in cells ([0, cells]^2, y down) -> marker frame (side 1, centred) -> image.
    const double u = 1.0 / cells;
    const cv::Matx33d plane(R(0, 0), R(0, 1), centre[0], R(1, 0), R(1, 1), centre[1], R(2, 0), R(2, 1),
                            centre[2]);
    const cv::Matx33d image_from_plane = K * plane * cv::Matx33d(u, 0, -0.5, 0, u, -0.5, 0, 0, 1);
    RenderedMarker m;
    m.id = id;
    const double tc[4][2] = {{0, 0}, {double(cells), 0}, {double(cells), double(cells)}, {0, double(cells)}};
    const double ext = im.margin_cells + 2.5;
    double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
    for (int k = 0; k < 4; ++k) {
      m.corners[k] = Apply(image_from_plane, tc[k][0], tc[k][1]);
      const cv::Point2d e =
          Apply(image_from_plane, tc[k][0] < 1 ? -ext : cells + ext, tc[k][1] < 1 ? -ext : cells + ext);
      for (const cv::Point2d& p : {m.corners[k], e})
        x0 = std::min(x0, p.x), x1 = std::max(x1, p.x), y0 = std::min(y0, p.y), y1 = std::max(y1, p.y);
    }
    if (x0 < 2 || y0 < 2 || x1 > scene.width - 3 || y1 > scene.height - 3) continue;
    const cv::Rect box(cv::Point(int(x0) - 1, int(y0) - 1), cv::Point(int(x1) + 2, int(y1) + 2));
    bool overlap = false;
    for (const auto& b : used) overlap = overlap || (b & box).area() > 0;
    if (overlap) continue;
    used.push_back(box);
    m.side_px = 0;
    for (int k = 0; k < 4; ++k) m.side_px += cv::norm(m.corners[(k + 1) % 4] - m.corners[k]) / 4;
    m.view_angle_deg = std::acos(std::abs(cv::Vec3d(R(0, 2), R(1, 2), R(2, 2)).dot(ray))) * 180 / M_PI;
    const cv::Mat bits =
        cv::aruco::Dictionary::getBitsFromByteList(dict.bytesList.rowRange(id, id + 1), dict.markerSize);
    const double light = 1.0 - im.face_shading * uni(rng);
    reference::Paint(reference::MarkerQuads(bits, cells, image_from_plane, im, light), box,
                     image_from_plane.inv(), &linear);
    truth->push_back(m);
  }
  return linear;
}

// RenderReferenceLinear through the camera: the image the detector sees.
inline cv::Mat RenderReference(const cv::aruco::Dictionary& dict, const ReferenceScene& scene,
                               const Imaging& im, std::mt19937_64& rng, std::vector<RenderedMarker>* truth) {
  return reference::CameraPipeline(RenderReferenceLinear(dict, scene, im, rng, truth), im, rng);
}

}  // namespace mcmt::testing
