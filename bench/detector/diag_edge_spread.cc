// The caliscope board's edge-spread function (issue 15, bench/results/2026-12-06-cam1width.md): is a
// camera's point-spread function Gaussian, as the side model assumes? Edges that no other edge disturbs:
// where a solid (white) square meets the dark frame around the board, the middle 60 % of each such side,
// located by the chessboard's homography (tests/detector/chessboard_truth.h). Each pixel within 6 px of
// the edge gives (u, value): u its signed distance from the edge (px, positive into the square), the value
// made linear with the gamma given. Per edge a Gaussian edge (dark, bright, u0, sigma) is fitted; all
// edges' samples, normalised to 0..1 and shifted by u0, give the camera's edge-spread function. Fitted to
// it: one Gaussian, and two (a core and a second Gaussian of weight f: f > 0 a halo, f < 0 a sharpening's
// undershoot). Prints both fits, the binned profile with each fit's residual, and the line-spread
// function's weight beyond 1, 2 and 3 px. Also the noise of the solid squares' middles (the middle 40 % of
// each side; sd of horizontal neighbours' differences / sqrt 2, encoded levels): a webcam's denoising
// shows as little noise.
// On the real caliscope board this finds no clean edge: its outline is a thin dark strip (about 0.6 of a
// cell) with white paper beyond, not a dark frame, so the per-edge fits fail there (rms 0.37-0.51 of the
// contrast); the render mode checks the method (blur 0.7 / 0.9 give sigma 0.750 / 0.945 px, expected
// 0.757 / 0.945 with the pixel's width). The noise figure is sound on both.
//   diag_edge_spread RIG_YAML [max frames (all)] [camera ("-": all)] [gamma (1.85)]
//   diag_edge_spread render GAMMA IMAGE.png...   (diag_charuco_board's renders, MCMT_BOARD_SAVE)
#include <cstdio>
#include <cstdlib>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <string>

#include "bench/detector/diag_support.h"
#include "tests/detector/chessboard_truth.h"

using namespace mcmt;

namespace {

constexpr double kSquareM = 0.054;
constexpr double kReachPx = 6.0;  // samples within this distance of the edge

struct Sample {
  double u, value;
};

using diag::Phi;

// Levenberg-Marquardt on `params` for sum over samples of (model(params, u) - value)^2, numeric Jacobian.
template <typename Model>
void Fit(const std::vector<Sample>& samples, const Model& model, std::vector<double>* params) {
  const int np = static_cast<int>(params->size());
  double lambda = 1e-3;
  auto cost = [&](const std::vector<double>& p) {
    double c = 0;
    for (const Sample& s : samples) c += std::pow(model(p, s.u) - s.value, 2);
    return c;
  };
  double c0 = cost(*params);
  for (int iter = 0; iter < 60; ++iter) {
    cv::Mat JtJ = cv::Mat::zeros(np, np, CV_64F), Jtr = cv::Mat::zeros(np, 1, CV_64F);
    for (const Sample& s : samples) {
      const double r = model(*params, s.u) - s.value;
      std::vector<double> J(np);
      for (int k = 0; k < np; ++k) {
        std::vector<double> q = *params;
        const double h = 1e-6 * std::max(1.0, std::abs(q[k]));
        q[k] += h;
        J[k] = (model(q, s.u) - model(*params, s.u)) / h;
      }
      for (int a = 0; a < np; ++a) {
        Jtr.at<double>(a) += J[a] * r;
        for (int b = 0; b < np; ++b) JtJ.at<double>(a, b) += J[a] * J[b];
      }
    }
    bool improved = false;
    while (lambda < 1e6 && !improved) {
      cv::Mat A = JtJ.clone();
      for (int k = 0; k < np; ++k) A.at<double>(k, k) *= 1 + lambda;
      cv::Mat step;
      cv::solve(A, -Jtr, step, cv::DECOMP_SVD);
      std::vector<double> q = *params;
      for (int k = 0; k < np; ++k) q[k] += step.at<double>(k);
      const double c1 = cost(q);
      if (c1 < c0) {
        improved = true, lambda *= 0.3;
        const bool done = c0 - c1 < 1e-10 * c0;
        *params = q, c0 = c1;
        if (done) return;
      } else {
        lambda *= 10;
      }
    }
    if (!improved) return;
  }
}

// A Gaussian edge: dark + (bright - dark) Phi((u - u0) / sigma); params {dark, bright, u0, sigma}.
double GaussianEdge(const std::vector<double>& p, double u) {
  return p[0] + (p[1] - p[0]) * Phi((u - p[2]) / std::abs(p[3]));
}
// Normalised, one Gaussian: {u0, sigma}.
double OneGaussian(const std::vector<double>& p, double u) { return Phi((u - p[0]) / std::abs(p[1])); }
// Normalised, two: (1 - f) Phi((u - u0) / s1) + f Phi((u - u0) / s2); {u0, s1, s2, f}.
double TwoGaussians(const std::vector<double>& p, double u) {
  return (1 - p[3]) * Phi((u - p[0]) / std::abs(p[1])) + p[3] * Phi((u - p[0]) / std::abs(p[2]));
}

// The edge-spread function's samples, normalised (0 dark, 1 bright) and centred on each edge's u0.
class EdgeSpread {
 public:
  explicit EdgeSpread(double gamma) : gamma_(gamma) {
    const auto board = testing::CaliscopeCharucoBoard();
    for (const auto& obj : board->objPoints) {
      cv::Point3f c(0, 0, 0);
      for (const auto& p : obj) c += 0.25 * p;
      marked_.insert({static_cast<int>(c.x / kSquareM), static_cast<int>(c.y / kSquareM)});
    }
  }

  // The board's outer edges of solid squares in `gray`, `raw_from_board` mapping board metres to pixels.
  void Add(const cv::Mat& gray, const std::function<Eigen::Vector2d(double, double)>& raw_from_board) {
    for (int sx = 0; sx < 4; ++sx)
      for (int sy = 0; sy < 5; ++sy) {
        if (marked_.count({sx, sy})) continue;
        AddNoise(gray, sx, sy, raw_from_board);
        const int dx[4] = {1, -1, 0, 0}, dy[4] = {0, 0, 1, -1};
        for (int k = 0; k < 4; ++k) {
          const int nx = sx + dx[k], ny = sy + dy[k];
          if (nx >= 0 && ny >= 0 && nx < 4 && ny < 5) continue;  // not on the board's outline
          const double cx = (sx + 0.5 + 0.5 * dx[k]) * kSquareM, cy = (sy + 0.5 + 0.5 * dy[k]) * kSquareM;
          auto along = [&](double t) {  // t in -0.5..0.5 along the side
            return raw_from_board(cx + (dx[k] == 0 ? t * kSquareM : 0), cy + (dy[k] == 0 ? t * kSquareM : 0));
          };
          const Eigen::Vector2d a = along(-0.3), b = along(0.3);
          const Eigen::Vector2d inside = raw_from_board((sx + 0.5) * kSquareM, (sy + 0.5) * kSquareM);
          AddEdge(gray, a, b, inside);
        }
      }
  }

  void Report() const {
    std::printf("solid squares' middles: %.0f pixel pairs, mean level %.1f, noise sd %.3f (encoded levels)\n",
                noise_n_, noise_level_ / std::max(noise_n_, 1.0),
                std::sqrt(noise_sq_ / std::max(noise_n_, 1.0) / 2));
    std::printf("edges %d (of %d tried), samples %zu; per edge: median sigma %.3f px, median contrast %.1f\n",
                edges_, tried_, samples_.size(), Median(sigmas_), Median(contrasts_));
    std::vector<double> one = {0.0, 0.8}, two = {0.0, 0.7, 2.0, 0.05};
    Fit(samples_, OneGaussian, &one);
    Fit(samples_, TwoGaussians, &two);
    auto rms = [&](double (*model)(const std::vector<double>&, double), const std::vector<double>& p) {
      double c = 0;
      for (const Sample& s : samples_) c += std::pow(model(p, s.u) - s.value, 2);
      return std::sqrt(c / std::max<size_t>(1, samples_.size()));
    };
    std::printf("one Gaussian: u0 %+.3f sigma %.3f px, rms %.4f\n", one[0], std::abs(one[1]),
                rms(OneGaussian, one));
    std::printf(
        "two Gaussians: u0 %+.3f core sigma %.3f px, second sigma %.3f px of weight f %+.3f, rms %.4f\n",
        two[0], std::abs(two[1]), std::abs(two[2]), two[3], rms(TwoGaussians, two));
    // Binned profile (0.25 px) with each fit's residual.
    constexpr int kBins = 48;
    std::vector<double> sum(kBins, 0), r1(kBins, 0), r2(kBins, 0), n(kBins, 0);
    for (const Sample& s : samples_) {
      const int b = static_cast<int>(std::floor((s.u + kReachPx) / 0.25));
      if (b < 0 || b >= kBins) continue;
      sum[b] += s.value, n[b] += 1;
      r1[b] += s.value - OneGaussian(one, s.u), r2[b] += s.value - TwoGaussians(two, s.u);
    }
    std::printf("u px    ESF     n     ESF - one   ESF - two\n");
    for (int b = 0; b < kBins; ++b)
      if (n[b] > 0)
        std::printf("%+5.2f  %7.4f  %5.0f  %+8.4f  %+8.4f\n", -kReachPx + 0.25 * (b + 0.5), sum[b] / n[b],
                    n[b], r1[b] / n[b], r2[b] / n[b]);
    // The line-spread function's weight beyond d: 1 - ESF(d) + ESF(-d), from the binned profile's means
    // over |u| in [d, d + 0.5).
    for (double d : {1.0, 2.0, 3.0}) {
      double hi = 0, lo = 0, nh = 0, nl = 0;
      for (const Sample& s : samples_) {
        if (s.u >= d && s.u < d + 0.5) hi += s.value, ++nh;
        if (s.u <= -d && s.u > -d - 0.5) lo += s.value, ++nl;
      }
      std::printf("weight beyond %.0f px: measured %.4f, one Gaussian %.4f\n", d,
                  1 - hi / std::max(nh, 1.0) + lo / std::max(nl, 1.0),
                  2 * Phi(-(d + 0.25) / std::abs(one[1])));
    }
  }

 private:
  static double Median(std::vector<double> v) {
    if (v.empty()) return NAN;
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  }

  // The pixels of a solid square's middle (board points (sx, sy) + 0.3..0.7 of a square, on a fine grid,
  // rounded to pixels) whose right neighbour is one of them too: their level and the squared differences.
  void AddNoise(const cv::Mat& gray, int sx, int sy,
                const std::function<Eigen::Vector2d(double, double)>& raw_from_board) {
    std::set<std::pair<int, int>> inside;
    constexpr int kSteps = 80;
    for (int i = 0; i <= kSteps; ++i)
      for (int j = 0; j <= kSteps; ++j) {
        const Eigen::Vector2d p = raw_from_board((sx + 0.3 + 0.4 * i / kSteps) * kSquareM,
                                                 (sy + 0.3 + 0.4 * j / kSteps) * kSquareM);
        const int x = static_cast<int>(std::lround(p.x())), y = static_cast<int>(std::lround(p.y()));
        if (x >= 0 && y >= 0 && x < gray.cols && y < gray.rows) inside.insert({x, y});
      }
    for (const auto& [x, y] : inside) {
      if (!inside.count({x + 1, y})) continue;
      const double v = gray.at<uint8_t>(y, x), w = gray.at<uint8_t>(y, x + 1);
      if (v >= 250 || w >= 250) continue;  // saturated
      noise_sq_ += (v - w) * (v - w), noise_level_ += v, noise_n_ += 1;
    }
  }

  // One edge from a to b (raw px), the solid square on the side of `inside`.
  void AddEdge(const cv::Mat& gray, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
               const Eigen::Vector2d& inside) {
    ++tried_;
    const Eigen::Vector2d t = (b - a).normalized();
    Eigen::Vector2d n(-t.y(), t.x());
    if (n.dot(inside - a) < 0) n = -n;
    const double length = (b - a).norm();
    if (length < 10) return;
    std::vector<Sample> edge;
    const int x0 = static_cast<int>(std::floor(std::min(a.x(), b.x()) - kReachPx)),
              x1 = static_cast<int>(std::ceil(std::max(a.x(), b.x()) + kReachPx)),
              y0 = static_cast<int>(std::floor(std::min(a.y(), b.y()) - kReachPx)),
              y1 = static_cast<int>(std::ceil(std::max(a.y(), b.y()) + kReachPx));
    if (x0 < 0 || y0 < 0 || x1 >= gray.cols || y1 >= gray.rows) return;
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const Eigen::Vector2d p(x, y);
        const double s = t.dot(p - a), u = n.dot(p - a);
        if (s < 0 || s > length || std::abs(u) > kReachPx) continue;
        edge.push_back({u, 255.0 * std::pow(gray.at<uint8_t>(y, x) / 255.0, gamma_)});
      }
    std::vector<double> p = {0, 0, 0, 0.8};
    double lo = 1e9, hi = -1e9;
    for (const Sample& s : edge) lo = std::min(lo, s.value), hi = std::max(hi, s.value);
    p[0] = lo, p[1] = hi;
    Fit(edge, GaussianEdge, &p);
    const double contrast = p[1] - p[0], sigma = std::abs(p[3]);
    // Edges that the fit does not find (low contrast, saturated, or far from the homography's line).
    if (contrast < 20 || sigma > 3 || std::abs(p[2]) > 2 || p[1] > 250) return;
    ++edges_;
    sigmas_.push_back(sigma), contrasts_.push_back(contrast);
    for (const Sample& s : edge) samples_.push_back({s.u - p[2], (s.value - p[0]) / contrast});
  }

  double gamma_;
  std::set<std::pair<int, int>> marked_;
  std::vector<Sample> samples_;
  std::vector<double> sigmas_, contrasts_;
  int edges_ = 0, tried_ = 0;
  double noise_sq_ = 0, noise_level_ = 0, noise_n_ = 0;
};

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr,
                 "usage: diag_edge_spread RIG_YAML [max frames] [camera] [gamma] | render GAMMA PNG...\n");
    return 2;
  }
  if (std::string(argv[1]) == "render") {
    EdgeSpread spread(std::atof(argv[2]));
    const auto board = testing::CaliscopeCharucoBoard();
    for (int i = 3; i < argc; ++i) {
      const cv::Mat gray = cv::imread(argv[i], cv::IMREAD_GRAYSCALE);
      const testing::CharucoDetection d = testing::DetectCharuco(gray, board, cv::Mat(), cv::Mat());
      if (d.corners.size() < 6) continue;
      std::vector<cv::Point2d> plane, image;
      for (size_t k = 0; k < d.corners.size(); ++k) {
        const cv::Point3f p = board->chessboardCorners[d.corner_ids[k]];
        plane.emplace_back(p.x, p.y), image.emplace_back(d.corners[k].x, d.corners[k].y);
      }
      const testing::BoardHomography h(plane, image);
      if (h.ok) spread.Add(gray, h);
    }
    spread.Report();
    return 0;
  }
  const RigConfig rig = LoadRigConfig(argv[1]);
  EdgeSpread spread(argc > 4 ? std::atof(argv[4]) : 1.85);
  testing::CompareWithChessboard(rig, argc > 2 ? std::atoi(argv[2]) : -1,
                                 argc > 3 && std::string(argv[3]) != "-" ? argv[3] : "",
                                 [&](const std::string&, const cv::Mat& gray,
                                     const std::function<Eigen::Vector2d(double, double)>& raw_from_board) {
                                   spread.Add(gray, raw_from_board);
                                 });
  spread.Report();
  return 0;
}
