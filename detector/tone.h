// A camera's tone curve and sharpening estimated from its own decoded markers, without any board
// geometry (detector option `tone: auto`).
//
// Once a marker is decoded and its corners refined, every cell of it is known: its image inside the
// outer edge is, in linear light, the border's level L0 with the code's white cells at L1, and outside
// the marker some surround level S. The estimator renders that scene for each marker (8 x 8 samples per
// pixel through the homography of its corners), blurs it with the marker's own Gaussian blur b (optics
// and defocus differ per marker), and puts it through the camera: an unsharp mask
// y = (1 + amount) x - amount G_sigma x and the encoding 255 (x / 255)^(1 / gamma), in either order
// (sharpening of linear light before the encoding, as the caliscope webcams do, or of encoded values).
// It compares the rendering with the 8-bit pixels at least kToneInnerPx inside the marker's outer edge
// (where the unknown surround barely reaches) and fits gamma, amount and sigma shared by all markers,
// and b, L0, L1, S per marker (Ceres, numeric derivatives), once per order; the order with the smaller
// residual is the camera's. The result is used as the detector's gamma / unsharp_* options.
#pragma once

#include <array>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace mcmt {

struct DetectorOptions;

struct ToneEstimate {
  bool ok = false;     // enough markers were fitted
  double gamma = 1.0;  // encoding 255 (v / 255)^(1 / gamma)
  double unsharp_amount = 0.0;
  double unsharp_sigma = 1.0;     // px
  bool unsharp_linear = false;    // sharpening of linear light (before the encoding)
  int markers = 0;                // markers fitted
  double rms = 0;                 // residual of the chosen order, grey levels
  double rms_other = 0;           // residual of the other order, grey levels
  std::array<double, 3> other{};  // the other order's gamma, amount, sigma
  // One line: the values as `detector:` keys (to put in a rig's config) and the fit's figures.
  std::string Describe() const;
  // The estimate as the detector's options: gamma (1 when within 0.1 of it: linear images), and the
  // sharpening where amount >= kToneMinAmount (else none).
  void Apply(DetectorOptions* options) const;
};

class ToneEstimator {
 public:
  // One decoded marker: the 8-bit image, its refined corners (ArUco order, pixel centres at integer
  // coordinates), its bits (cells-2 square, CV_8U 0/1, as MarkerDetector's) and its width in cells.
  // Markers too small (cells below 2.5 px), too close to the image border or without white cells are
  // skipped; returns whether the marker was kept.
  bool Add(const cv::Mat& gray, const std::array<cv::Point2d, 4>& corners, const cv::Mat& bits, int cells);
  int markers() const { return static_cast<int>(samples_.size()); }
  // The fit over the markers added (ok false below kToneMinMarkers).
  ToneEstimate Estimate() const;

  struct Sample {
    cv::Mat observed;        // CV_64F grey levels of the region
    cv::Mat white, outside;  // CV_64F coverage (0..1) of the code's white cells and of the surround
    std::vector<int> inner;  // pixel indices compared (at least kToneInnerPx inside the outer edge)
    double white_mean = 0, dark_mean = 0, outside_mean = 0;  // observed starts for the levels
  };

 private:
  std::vector<Sample> samples_;
};

constexpr int kToneMinMarkers = 8;
constexpr double kToneInnerPx = 1.5;
constexpr double kToneMinAmount = 0.05;

}  // namespace mcmt
