// Issue 15 (bench/results/2026-12-06-sharpturn.md): mcmt-sim's exact-area renderer (RenderIdeal) and the
// reference renderer (RenderReferenceRigView, tests/mapper/reference_rig_view.h) against an independent
// fine point-sampled render (S x S samples per pixel, pixel centres at integer coordinates) of the same
// views of bench_imaging_maps' session, in linear light with equal levels (ink 25, paper 225, surface
// 127.5), no noise, no optics, no light gradient or shading. Prints, per renderer, the largest and mean
// |difference| and the mean signed difference (gray levels) over the pixels about each marker seen at
// 40 deg or more (its print with its margin, one pixel around), split into pixels inside the print, on its
// outer edge, surface only, and pixels on two faces (the edge between two of the body's faces). The
// reference's 8-bit output rounds: 0.25 mean |d| of that is its quantisation.
//   diag_render_compare [radius (1.3)] [frames to scan (40)] [S (32)]
// ST_WORST=1 lists the pixels where the reference differs by more than 8 levels.
// RC_BLUR=SIGMA (px) and / or RC_DEFOCUS=R (px): both renderers' full pipelines with that optics only (no
// noise, gamma 1, no sharpening or JPEG: 8-bit outputs) against the exact optics of the scene: the fine
// render (S x S points per pixel) convolved with the continuous Gaussian (sigma S fine samples) or disc
// (radius R S), then box-averaged per pixel. Prints per renderer and marker size band the mean signed and
// mean |difference| over each marker's pixels (those the background reaches with less than 1e-4 of the
// kernel) and the marker's apparent size error: the least-squares s of d = -s (p - c).grad I (a scale about
// the marker's centre c), given as the outward offset per side s x half the marker's side, px (blurgap,
// 2026-12-08).
#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <opencv2/aruco.hpp>
#include <opencv2/imgproc.hpp>

#include "core/dictionary.h"
#include "tests/mapper/reference_rig_view.h"
#include "tests/mapper/rendered_session.h"

using namespace mcmt;

namespace {
constexpr double kBlack = 25.0, kWhite = 225.0, kSurface = 0.5;

struct Fine {
  const sim::SimObject* object;
  const cv::aruco::Dictionary* dict;
  Rigid3 cam_from_object;
  CameraModel model;
  int margin;
  mutable bool in_print = false;
  mutable const sim::SimFace* face = nullptr;
  // The scene's linear level seen along the ray through image point (x, y); -1 where no face is hit.
  double At(double x, double y) const {
    const Eigen::Vector3d ray((x - model.cx) / model.fx, (y - model.cy) / model.fy, 1.0);
    double best = 1e300, value = -1;
    in_print = false;
    for (const sim::SimFace& f : object->faces) {
      std::vector<Eigen::Vector3d> v;
      for (const auto& p : f.vertices) v.push_back(cam_from_object * p);
      const Eigen::Vector3d n = (v[1] - v[0]).cross(v[2] - v[0]).normalized();
      const double d = n.dot(ray);
      if (!(d < 0)) continue;
      const double t = n.dot(v[0]) / d;
      const Eigen::Vector3d X = t * ray;
      bool inside = true;
      for (size_t k = 0; k < v.size(); ++k)
        if (n.dot((v[(k + 1) % v.size()] - v[k]).cross(X - v[k])) < 0) inside = false;
      if (!inside || t >= best) continue;
      best = t;
      face = &f;
      value = 255.0 * kSurface;
      for (const sim::SimMarker& m : object->markers) {
        const Rigid3 cm = cam_from_object * m.object_from_marker;
        if (cm.linear().col(2).dot(n) < 0.999) continue;
        const Eigen::Vector3d q = cm.inverse() * X;
        const int cells = dict->markerSize + 2;
        const double cell = m.size / cells;
        const double cx = q.x() / cell + 0.5 * cells, cy = 0.5 * cells - q.y() / cell;  // cells, row down
        if (cx < -margin || cy < -margin || cx >= cells + margin || cy >= cells + margin) continue;
        const int c = static_cast<int>(std::floor(cx)), r = static_cast<int>(std::floor(cy));
        bool white = true;
        if (c >= 0 && r >= 0 && c < cells && r < cells) {
          white = false;
          if (c >= 1 && r >= 1 && c + 1 < cells && r + 1 < cells) {
            const cv::Mat bits = cv::aruco::Dictionary::getBitsFromByteList(
                dict->bytesList.rowRange(m.id, m.id + 1), dict->markerSize);
            white = bits.at<uint8_t>(r - 1, c - 1) != 0;
          }
        }
        value = white ? kWhite : kBlack;
        in_print = true;
      }
    }
    return value;
  }
};
}  // namespace

// The exact optics on a fine render (S x S samples per pixel): the continuous Gaussian (sigma px, sigma S
// fine samples) then the disc (radius `defocus` px; each fine cell its disc area from 4 x 4 sub-samples),
// normalised, both with replicated borders.
void BlurLikeTheOptics(double sigma, double defocus, int S, cv::Mat* fine) {
  if (sigma > 0) {
    const int k = 2 * static_cast<int>(std::ceil(4 * sigma * S)) + 1;
    cv::GaussianBlur(*fine, *fine, cv::Size(k, k), sigma * S, sigma * S, cv::BORDER_REPLICATE);
  }
  if (defocus > 0) {
    const int r = static_cast<int>(std::ceil(defocus * S)) + 1;
    cv::Mat kernel(2 * r + 1, 2 * r + 1, CV_64F, cv::Scalar(0));
    for (int y = 0; y < kernel.rows; ++y)
      for (int x = 0; x < kernel.cols; ++x)
        for (int a = 0; a < 4; ++a)
          for (int b = 0; b < 4; ++b) {
            const double dx = x - r - 0.5 + (b + 0.5) / 4, dy = y - r - 0.5 + (a + 0.5) / 4;
            kernel.at<double>(y, x) += dx * dx + dy * dy <= defocus * S * defocus * S;
          }
    kernel /= cv::sum(kernel)[0];
    cv::filter2D(*fine, *fine, -1, kernel, cv::Point(-1, -1), 0, cv::BORDER_REPLICATE);
  }
}

// RC_BLUR / RC_DEFOCUS (top of the file).
int BlurCompare(double radius, int scan, int S, double sigma, double defocus) {
  const testing::RenderedMapSession session = testing::MakeRenderedMapSession(radius, 300);
  const cv::Ptr<cv::aruco::Dictionary> dict = LoadDictionary(session.markers.dictionary);
  sim::RenderOptions ro;
  ro.noise_sigma = 0, ro.textured_background = false, ro.background_level = 128, ro.lighting_gradient = 0;
  ro.shading = 0, ro.black_level = kBlack, ro.white_level = kWhite, ro.surface_albedo = kSurface;
  ro.blur_sigma = sigma, ro.defocus_radius = defocus;
  sim::Renderer renderer(session.object, session.markers.dictionary, ro);
  testing::Imaging im;
  im.ink = kBlack / 255.0, im.paper = kWhite / 255.0, im.surface = kSurface, im.read_noise = 0;
  im.blur_sigma = sigma, im.defocus_radius = defocus;
  const int reach = static_cast<int>(std::ceil(4 * sigma + defocus)) + 1;  // px
  const double bands[4] = {0, 15, 20, 25};
  // [band][renderer]: sums of d, |d|, pixels; scale fits' numerators and denominators per marker.
  double sd[5][2] = {}, sa[5][2] = {}, off_sum[5][2] = {}, off_sq[5][2] = {};
  long long np[5] = {}, nm[5] = {};
  for (int fi = 0; fi < scan; ++fi) {
    const sim::SimFrame& f = session.trajectory[fi * 7 % session.trajectory.size()];
    for (size_t c = 0; c < session.cameras.size(); ++c) {
      const sim::SimCamera& cam = session.cameras[c];
      const cv::Mat simimg = renderer.Render(cam, static_cast<int>(c), f.seq, f.rig_from_object);
      const cv::Mat ref =
          testing::RenderReferenceRigView(*dict, session.object, cam, f.rig_from_object, im, 1);
      Fine fine{&session.object, dict.get(), cam.rig_from_cam.inverse() * f.rig_from_object, cam.model, 1};
      for (const sim::MarkerView& v : sim::ProjectMarkers(cam, session.object, f.rig_from_object)) {
        if (!v.fully_visible || v.view_angle_deg > 75) continue;
        double x0 = 1e9, x1 = -1e9, y0 = 1e9, y1 = -1e9;
        for (int k = 0; k < 4; ++k)
          x0 = std::min(x0, v.corners[k][0]), x1 = std::max(x1, v.corners[k][0]),
          y0 = std::min(y0, v.corners[k][1]), y1 = std::max(y1, v.corners[k][1]);
        // Pixels of the marker and one pixel around; the fine render over them and the kernel's reach.
        const int px0 = static_cast<int>(x0) - 1, px1 = static_cast<int>(x1) + 1;
        const int py0 = static_cast<int>(y0) - 1, py1 = static_cast<int>(y1) + 1;
        const int fx0 = px0 - reach, fy0 = py0 - reach, fw = px1 - px0 + 1 + 2 * reach,
                  fh = py1 - py0 + 1 + 2 * reach;
        if (fx0 < 0 || fy0 < 0 || fx0 + fw > cam.model.width || fy0 + fh > cam.model.height) continue;
        cv::Mat scene(fh * S, fw * S, CV_64F), off(fh * S, fw * S, CV_64F);
        for (int a = 0; a < fh * S; ++a)
          for (int b = 0; b < fw * S; ++b) {
            const double val = fine.At(fx0 - 0.5 + (b + 0.5) / S, fy0 - 0.5 + (a + 0.5) / S);
            scene.at<double>(a, b) = val < 0 ? 128.0 : val;
            off.at<double>(a, b) = val < 0 ? 1.0 : 0.0;
          }
        BlurLikeTheOptics(sigma, defocus, S, &scene);
        BlurLikeTheOptics(sigma, defocus, S, &off);
        cv::Mat exact, off_px;
        cv::resize(scene, exact, cv::Size(fw, fh), 0, 0, cv::INTER_AREA);  // the pixels' box mean
        cv::resize(off, off_px, cv::Size(fw, fh), 0, 0, cv::INTER_AREA);
        const double mcx = 0.25 * (v.corners[0][0] + v.corners[1][0] + v.corners[2][0] + v.corners[3][0]);
        const double mcy = 0.25 * (v.corners[0][1] + v.corners[1][1] + v.corners[2][1] + v.corners[3][1]);
        int band = 0;
        while (band < 3 && v.size_px >= bands[band + 1]) ++band;
        double num[2] = {0, 0}, den = 0;
        for (int y = py0; y <= py1; ++y)
          for (int x = px0; x <= px1; ++x) {
            const int ex = x - fx0, ey = y - fy0;
            // Pixels the background reaches through the kernel (the renderers' backgrounds differ) are
            // not compared: their weight of the background above 1e-4 (0.01 gray levels).
            if (off_px.at<double>(ey, ex) > 1e-4) continue;
            const double t = exact.at<double>(ey, ex);
            const double gx = 0.5 * (exact.at<double>(ey, ex + 1) - exact.at<double>(ey, ex - 1));
            const double gy = 0.5 * (exact.at<double>(ey + 1, ex) - exact.at<double>(ey - 1, ex));
            const double g = (x - mcx) * gx + (y - mcy) * gy;
            const double d[2] = {simimg.at<uint8_t>(y, x) - t, ref.at<uint8_t>(y, x) - t};
            for (int r = 0; r < 2; ++r)
              sd[band][r] += d[r], sa[band][r] += std::abs(d[r]), num[r] += d[r] * g;
            den += g * g;
            ++np[band];
          }
        if (den <= 0) continue;
        for (int r = 0; r < 2; ++r) {
          const double o = -num[r] / den * 0.5 * v.size_px;  // outward offset per side, px
          off_sum[band][r] += o, off_sq[band][r] += o * o;
        }
        ++nm[band];
      }
    }
  }
  std::printf(
      "radius %.1f, blur %.2f px, defocus %.2f px, fine %dx%d, fully visible markers at <= 75 deg; "
      "size band 0: under 15 px\n",
      radius, sigma, defocus, S, S);
  std::printf(
      "| size band px | markers | pixels | mcmt-sim: mean d / mean abs d (gray) | size offset per side px "
      "(sd) "
      "| reference: mean d / mean abs d | size offset per side px (sd) |\n|---|---|---|---|---|---|---|\n");
  for (int b = 0; b < 4; ++b) {
    if (nm[b] == 0) continue;
    std::printf("| %s%.0f | %lld | %lld |", b == 3 ? ">= " : "", bands[b], nm[b], np[b]);
    for (int r = 0; r < 2; ++r) {
      const double m = off_sum[b][r] / nm[b];
      std::printf(" %+.3f / %.3f | %+.5f (%.5f) |", sd[b][r] / np[b], sa[b][r] / np[b], m,
                  std::sqrt(std::max(0.0, off_sq[b][r] / nm[b] - m * m)));
    }
    std::printf("\n");
  }
  return 0;
}

int main(int argc, char** argv) {
  if (std::getenv("RC_BLUR") || std::getenv("RC_DEFOCUS"))
    return BlurCompare(argc > 1 ? std::atof(argv[1]) : 1.3, argc > 2 ? std::atoi(argv[2]) : 40,
                       argc > 3 ? std::atoi(argv[3]) : 32,
                       std::getenv("RC_BLUR") ? std::atof(std::getenv("RC_BLUR")) : 0.0,
                       std::getenv("RC_DEFOCUS") ? std::atof(std::getenv("RC_DEFOCUS")) : 0.0);
  const double radius = argc > 1 ? std::atof(argv[1]) : 1.3;
  const int scan = argc > 2 ? std::atoi(argv[2]) : 40;
  const int S = argc > 3 ? std::atoi(argv[3]) : 32;
  const testing::RenderedMapSession session = testing::MakeRenderedMapSession(radius, 300);
  const cv::Ptr<cv::aruco::Dictionary> dict = LoadDictionary(session.markers.dictionary);
  sim::RenderOptions ro;
  ro.noise_sigma = 0, ro.textured_background = false, ro.background_level = 128, ro.lighting_gradient = 0;
  ro.shading = 0, ro.black_level = kBlack, ro.white_level = kWhite, ro.surface_albedo = kSurface;
  sim::Renderer renderer(session.object, session.markers.dictionary, ro);
  testing::Imaging im;
  im.ink = kBlack / 255.0, im.paper = kWhite / 255.0, im.surface = kSurface, im.read_noise = 0;
  double sum_abs[2] = {0, 0}, sum_signed[2] = {0, 0}, max_abs[2] = {0, 0};
  long long n = 0, kn[4] = {0, 0, 0, 0};
  double ks_abs[4][2] = {}, ks_signed[4][2] = {}, ks_max[4][2] = {};
  int markers = 0;
  for (int fi = 0; fi < scan; ++fi) {
    const sim::SimFrame& f = session.trajectory[fi * 7 % session.trajectory.size()];
    for (size_t c = 0; c < session.cameras.size(); ++c) {
      const sim::SimCamera& cam = session.cameras[c];
      const cv::Mat simimg = renderer.RenderIdeal(cam, static_cast<int>(c), f.rig_from_object);
      // The reference's linear image: RenderReferenceRigView without its camera pipeline (read noise 0,
      // gamma 1: the pipeline only quantises), as doubles before quantisation: rebuild it here.
      cv::Mat ref = testing::RenderReferenceRigView(*dict, session.object, cam, f.rig_from_object, im, 1);
      Fine fine{&session.object, dict.get(), cam.rig_from_cam.inverse() * f.rig_from_object, cam.model, 1};
      for (const sim::MarkerView& v : sim::ProjectMarkers(cam, session.object, f.rig_from_object)) {
        if (!v.fully_visible || v.view_angle_deg < 40) continue;
        ++markers;
        double x0 = 1e9, x1 = -1e9, y0 = 1e9, y1 = -1e9;
        for (int k = 0; k < 4; ++k)
          x0 = std::min(x0, v.corners[k][0]), x1 = std::max(x1, v.corners[k][0]),
          y0 = std::min(y0, v.corners[k][1]), y1 = std::max(y1, v.corners[k][1]);
        for (int y = int(y0) - 1; y <= int(y1) + 1; ++y)
          for (int x = int(x0) - 1; x <= int(x1) + 1; ++x) {
            double acc = 0;
            bool ok = true;
            int printed = 0;
            const sim::SimFace* first_face = nullptr;
            bool seam = false;
            for (int a = 0; a < S && ok; ++a)
              for (int b = 0; b < S; ++b) {
                const double val = fine.At(x - 0.5 + (b + 0.5) / S, y - 0.5 + (a + 0.5) / S);
                if (val < 0) ok = false;
                printed += fine.in_print;
                if (!first_face) first_face = fine.face;
                seam = seam || fine.face != first_face;
                acc += val;
              }
            if (!ok) continue;
            const double truth = acc / (S * S);
            const int kind = seam ? 3 : printed == S * S ? 0 : printed > 0 ? 1 : 2;
            const double d[2] = {simimg.at<float>(y, x) - truth, ref.at<uint8_t>(y, x) - truth};
            if (std::getenv("ST_WORST") && std::abs(d[1]) > 8)
              std::printf(
                  "worst cam %zu seq %lld id %d view %.1f size %.1f px (%d,%d) truth %.2f sim %.2f ref %d\n",
                  c, static_cast<long long>(f.seq), v.id, v.view_angle_deg, v.size_px, x, y, truth,
                  simimg.at<float>(y, x), ref.at<uint8_t>(y, x));
            for (int r = 0; r < 2; ++r)
              ks_abs[kind][r] += std::abs(d[r]), ks_signed[kind][r] += d[r],
                  ks_max[kind][r] = std::max(ks_max[kind][r], std::abs(d[r]));
            ++kn[kind];
            for (int r = 0; r < 2; ++r)
              sum_abs[r] += std::abs(d[r]), sum_signed[r] += d[r],
                  max_abs[r] = std::max(max_abs[r], std::abs(d[r]));
            ++n;
          }
      }
    }
  }
  const char* names[2] = {"mcmt-sim (RenderIdeal, float)", "reference (8-bit, no noise)"};
  std::printf("radius %.1f: %d markers >= 40 deg, %lld pixels, fine render %dx%d\n", radius, markers, n, S,
              S);
  for (int r = 0; r < 2; ++r)
    std::printf("%s: max |d| %.3f, mean |d| %.4f, mean d %+.4f gray levels (step %.0f)\n", names[r],
                max_abs[r], sum_abs[r] / n, sum_signed[r] / n, kWhite - kBlack);
  const char* kinds[4] = {"inside the print", "the print's outer edge", "surface only", "two faces (seam)"};
  for (int k = 0; k < 4; ++k)
    for (int r = 0; r < 2; ++r)
      std::printf("  %s, %s (%lld px): max |d| %.3f, mean |d| %.4f, mean d %+.4f\n", kinds[k], names[r],
                  kn[k], ks_max[k][r], ks_abs[k][r] / std::max(1LL, kn[k]),
                  ks_signed[k][r] / std::max(1LL, kn[k]));
  return 0;
}
