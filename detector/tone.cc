#include "detector/tone.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>

#include "detector/detector.h"

namespace mcmt {
namespace {

constexpr int kRadius = 6;  // px, half width of every Gaussian (fixed: the model is smooth in its sigmas)
constexpr int kSuper = 8;   // coverage samples per pixel and axis
constexpr int kPad = 8;     // px of surround around the marker's box
// Shared parameters: gamma, amount, sigma; per marker: blur b, border level L0, white level L1, surround S.
constexpr int kShared = 3, kOwn = 4;

void Blur(const cv::Mat& in, double sigma, cv::Mat* out) {
  cv::Mat k(2 * kRadius + 1, 1, CV_64F);
  double sum = 0;
  for (int i = -kRadius; i <= kRadius; ++i)
    sum += k.at<double>(i + kRadius) = std::exp(-0.5 * i * i / (sigma * sigma));
  k /= sum;
  cv::sepFilter2D(in, *out, CV_64F, k, k, cv::Point(-1, -1), 0, cv::BORDER_REFLECT);
}

// The camera's image of one marker's scene (8-bit scale, not rounded or clipped).
void Render(const ToneEstimator::Sample& s, const double* shared, const double* own, bool linear,
            cv::Mat* y) {
  const double gamma = shared[0], amount = shared[1], sigma = shared[2];
  cv::Mat scene = own[1] + (own[2] - own[1]) * s.white + (own[3] - own[1]) * s.outside;
  Blur(scene, own[0], y);
  auto encode = [&]() {
    cv::max(*y * (1.0 / 255.0), 1e-4, *y);
    cv::pow(*y, 1.0 / gamma, *y);
    *y *= 255.0;
  };
  auto sharpen = [&]() {
    cv::Mat smooth;
    Blur(*y, sigma, &smooth);
    *y = (1.0 + amount) * *y - amount * smooth;
  };
  if (linear) sharpen();
  encode();
  if (!linear) sharpen();
}

struct MarkerCost {
  const ToneEstimator::Sample* sample;
  bool linear;
  bool operator()(double const* const* parameters, double* residuals) const {
    cv::Mat y;
    Render(*sample, parameters[0], parameters[1], linear, &y);
    const double* model = y.ptr<double>();
    const double* seen = sample->observed.ptr<double>();
    for (size_t i = 0; i < sample->inner.size(); ++i) {
      const int p = sample->inner[i];
      residuals[i] = std::clamp(model[p], 0.0, 255.0) - seen[p];
    }
    return true;
  }
};

struct OrderFit {
  std::array<double, kShared> shared{};
  double cost = 0;  // robust cost
  double rms = 0;   // grey levels
  bool ok = false;
};

OrderFit FitOrder(const std::vector<ToneEstimator::Sample>& samples, bool linear) {
  OrderFit fit;
  fit.shared = {2.0, 0.3, 1.0};
  std::vector<std::array<double, kOwn>> own(samples.size());
  ceres::Problem problem;
  long long residuals = 0;
  for (size_t i = 0; i < samples.size(); ++i) {
    const ToneEstimator::Sample& s = samples[i];
    auto linearised = [&](double v) { return 255.0 * std::pow(std::max(v, 1.0) / 255.0, fit.shared[0]); };
    own[i] = {0.8, linearised(s.dark_mean), linearised(s.white_mean), linearised(s.outside_mean)};
    auto* cost = new ceres::DynamicNumericDiffCostFunction<MarkerCost>(new MarkerCost{&s, linear});
    cost->AddParameterBlock(kShared);
    cost->AddParameterBlock(kOwn);
    cost->SetNumResiduals(static_cast<int>(s.inner.size()));
    problem.AddResidualBlock(cost, new ceres::HuberLoss(10.0), fit.shared.data(), own[i].data());
    const double lower[kOwn] = {0.05, 0, 0, 0}, upper[kOwn] = {3.0, 400, 400, 400};
    for (int k = 0; k < kOwn; ++k) {
      problem.SetParameterLowerBound(own[i].data(), k, lower[k]);
      problem.SetParameterUpperBound(own[i].data(), k, upper[k]);
    }
    residuals += static_cast<long long>(s.inner.size());
  }
  const double lower[kShared] = {0.4, 0.0, 0.4}, upper[kShared] = {4.0, 3.0, 2.0};
  for (int k = 0; k < kShared; ++k) {
    problem.SetParameterLowerBound(fit.shared.data(), k, lower[k]);
    problem.SetParameterUpperBound(fit.shared.data(), k, upper[k]);
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_SCHUR;
  options.max_num_iterations = 40;
  options.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  fit.ok = summary.IsSolutionUsable();
  fit.cost = summary.final_cost;
  fit.rms = std::sqrt(2.0 * summary.final_cost / std::max(1LL, residuals));
  return fit;
}

}  // namespace

std::string ToneEstimate::Describe() const {
  char line[320];
  std::snprintf(line, sizeof(line),
                "gamma: %.2f, unsharp_amount: %.2f, unsharp_sigma: %.2f, unsharp_linear: %s (estimated from "
                "%d markers%s; rms %.2f grey levels; the other order %.2f / %.2f / %.2f px, rms %.2f)",
                gamma, unsharp_amount, unsharp_sigma, unsharp_linear ? "true" : "false", markers,
                ok ? "" : ", too few: not used", rms, other[0], other[1], other[2], rms_other);
  return line;
}

void ToneEstimate::Apply(DetectorOptions* options) const {
  if (!ok) return;
  options->gamma = std::abs(gamma - 1.0) < 0.1 ? 1.0 : gamma;
  const bool sharpened = unsharp_amount >= kToneMinAmount;
  options->unsharp_amount = sharpened ? unsharp_amount : 0.0;
  options->unsharp_sigma = unsharp_sigma;
  options->unsharp_linear = sharpened && unsharp_linear;
}

bool ToneEstimator::Add(const cv::Mat& gray, const std::array<cv::Point2d, 4>& corners, const cv::Mat& bits,
                        int cells) {
  double side = 0;
  for (int k = 0; k < 4; ++k) side += 0.25 * cv::norm(corners[(k + 1) % 4] - corners[k]);
  const double cell_px = side / cells;
  if (cell_px < 2.5) return false;
  std::vector<cv::Point2f> image, plane;
  for (int k = 0; k < 4; ++k)
    image.emplace_back(static_cast<float>(corners[k].x), static_cast<float>(corners[k].y));
  const cv::Rect box = cv::boundingRect(image);
  const cv::Rect roi(box.x - kPad, box.y - kPad, box.width + 2 * kPad, box.height + 2 * kPad);
  if ((roi & cv::Rect(0, 0, gray.cols, gray.rows)) != roi) return false;
  const float c = static_cast<float>(cells);
  plane = {{0, 0}, {c, 0}, {c, c}, {0, c}};
  const cv::Matx33d plane_from_image(cv::getPerspectiveTransform(image, plane));
  auto to_plane = [&](double x, double y) {
    const cv::Vec3d p = plane_from_image * cv::Vec3d(x, y, 1.0);
    return cv::Point2d(p[0] / p[2], p[1] / p[2]);
  };
  Sample s;
  gray(roi).convertTo(s.observed, CV_64F);
  s.white = cv::Mat::zeros(roi.size(), CV_64F);
  s.outside = cv::Mat::zeros(roi.size(), CV_64F);
  double sums[3] = {0, 0, 0}, counts[3] = {0, 0, 0};  // dark, white, outside
  for (int r = 0; r < roi.height; ++r)
    for (int q = 0; q < roi.width; ++q) {
      const double x = roi.x + q, y = roi.y + r;
      double white = 0, outside = 0;
      for (int a = 0; a < kSuper; ++a)
        for (int b = 0; b < kSuper; ++b) {
          const cv::Point2d p = to_plane(x - 0.5 + (b + 0.5) / kSuper, y - 0.5 + (a + 0.5) / kSuper);
          if (p.x < 0 || p.y < 0 || p.x >= cells || p.y >= cells) {
            outside += 1;
            continue;
          }
          const int col = static_cast<int>(p.x), row = static_cast<int>(p.y);
          if (row >= 1 && col >= 1 && row < cells - 1 && col < cells - 1 &&
              bits.at<uint8_t>(row - 1, col - 1))
            white += 1;
        }
      white /= kSuper * kSuper, outside /= kSuper * kSuper;
      s.white.at<double>(r, q) = white, s.outside.at<double>(r, q) = outside;
      const double v = s.observed.at<double>(r, q);
      const int kind = outside == 1 ? 2 : white == 1 ? 1 : white == 0 && outside == 0 ? 0 : -1;
      if (kind >= 0) sums[kind] += v, counts[kind] += 1;
      const cv::Point2d centre = to_plane(x, y);
      const double depth = std::min({centre.x, centre.y, cells - centre.x, cells - centre.y}) * cell_px;
      if (depth >= kToneInnerPx) s.inner.push_back(r * roi.width + q);
    }
  if (counts[0] == 0 || counts[1] == 0 || counts[2] == 0) return false;
  s.dark_mean = sums[0] / counts[0], s.white_mean = sums[1] / counts[1], s.outside_mean = sums[2] / counts[2];
  samples_.push_back(std::move(s));
  return true;
}

ToneEstimate ToneEstimator::Estimate() const {
  ToneEstimate e;
  e.markers = markers();
  if (e.markers < kToneMinMarkers) return e;
  const OrderFit linear = FitOrder(samples_, true), encoded = FitOrder(samples_, false);
  const bool use_linear = linear.ok && (!encoded.ok || linear.cost <= encoded.cost);
  const OrderFit& best = use_linear ? linear : encoded;
  e.ok = best.ok;
  e.gamma = best.shared[0], e.unsharp_amount = best.shared[1], e.unsharp_sigma = best.shared[2];
  e.unsharp_linear = use_linear;
  const OrderFit& other = use_linear ? encoded : linear;
  e.rms = best.rms, e.rms_other = other.rms;
  std::copy(other.shared.begin(), other.shared.end(), e.other.begin());
  return e;
}

}  // namespace mcmt

namespace mcmt {

// The largest markers of each frame (at most kTonePerFrame of them, spread over the frames) until
// tone_markers are in or tone_frames frames are seen, then the estimate, used from the next frame on.
void MarkerDetector::ObserveTone(const cv::Mat& gray, const std::vector<marker_t>& markers) {
  constexpr int kTonePerFrame = 4;
  ++tone_frames_seen_;
  auto side = [](const marker_t& m) {
    return std::hypot(m.corners[1][0] - m.corners[0][0], m.corners[1][1] - m.corners[0][1]) +
           std::hypot(m.corners[2][0] - m.corners[1][0], m.corners[2][1] - m.corners[1][1]);
  };
  std::vector<const marker_t*> order;
  for (const marker_t& m : markers) order.push_back(&m);
  std::sort(order.begin(), order.end(),
            [&](const marker_t* a, const marker_t* b) { return side(*a) > side(*b); });
  int added = 0;
  for (const marker_t* m : order) {
    if (added >= kTonePerFrame || tone_->markers() >= options_.tone_markers) break;
    std::array<cv::Point2d, 4> corners;
    for (int k = 0; k < 4; ++k) corners[k] = {m->corners[k][0], m->corners[k][1]};
    added += tone_->Add(gray, corners, MarkerBits(m->id), dictionary_->markerSize + 2);
  }
  const int collected = tone_->markers();
  if (collected < options_.tone_markers && tone_frames_seen_ < options_.tone_frames) return;
  if (collected < kToneMinMarkers) {
    tone_.reset();
    std::fprintf(stderr,
                 "detector: tone auto: %d markers fit for it in the first %d frames (tone_frames), fewer "
                 "than %d: the given tone is kept\n",
                 collected, tone_frames_seen_, kToneMinMarkers);
    return;
  }
  UseTone(tone_->Estimate());
  std::fprintf(stderr, "detector: tone auto after %d frames (%d markers): %s\n", tone_frames_seen_, collected,
               tone_estimate_.Describe().c_str());
}

void MarkerDetector::UseTone(const ToneEstimate& tone) {
  tone_estimate_ = tone;
  tone_.reset();
  tone_estimate_.Apply(&options_);
  gamma_lut_.release();  // built for the gamma in force at the first linearised region
}

}  // namespace mcmt
