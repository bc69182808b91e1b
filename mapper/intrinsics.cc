#include "mapper/intrinsics.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include "core/json.h"
#include "core/math.h"

namespace mcmt {

IntrinsicsRefinement IntrinsicsRefinementFromName(const std::string& name) {
  if (name == "none") return IntrinsicsRefinement::kNone;
  if (name == "focal") return IntrinsicsRefinement::kFocal;
  if (name == "focal_center") return IntrinsicsRefinement::kFocalCenter;
  if (name == "all") return IntrinsicsRefinement::kAll;
  throw std::invalid_argument("unknown '" + name + "' (none, focal, focal_center, all)");
}

std::string IntrinsicsRefinementName(IntrinsicsRefinement refinement) {
  switch (refinement) {
    case IntrinsicsRefinement::kNone:
      return "none";
    case IntrinsicsRefinement::kFocal:
      return "focal";
    case IntrinsicsRefinement::kFocalCenter:
      return "focal_center";
    case IntrinsicsRefinement::kAll:
      return "all";
  }
  return "none";
}

std::vector<int> RequestedIntrinsics(IntrinsicsRefinement refine, const CameraModel& model) {
  std::vector<int> out;
  if (refine == IntrinsicsRefinement::kNone) return out;
  out = {0, 1};
  if (refine == IntrinsicsRefinement::kFocal) return out;
  out.push_back(2);
  out.push_back(3);
  if (refine == IntrinsicsRefinement::kFocalCenter) return out;
  const int n = static_cast<int>(model.distortion.size());
  for (int i = 0; i < std::min(n, 5); ++i) out.push_back(4 + i);
  return out;
}

std::vector<double> PriorSigma(const IntrinsicsSigma& sigma, const CameraModel& model) {
  std::vector<double> s = {sigma.focal_rel * model.fx, sigma.focal_rel * model.fy, sigma.center_px,
                           sigma.center_px};
  for (size_t i = 0; i < model.distortion.size(); ++i) {
    const bool tangential = model.model == DistortionModel::kRadTan && (i == 2 || i == 3);
    s.push_back(tangential ? sigma.tangential : sigma.radial);
  }
  return s;
}

double ImageCoverage(const BundleProblem& bp, int camera, int* views) {
  const CameraModel model = bp.Model(camera);
  const Rigid3 cam_from_rig = RigidFromBlock(bp.cam_from_rig[camera].data());
  std::vector<char> cells(8 * 6, 0);
  std::set<int> frames;
  for (size_t k = 0; k < bp.observations.size(); ++k) {
    const BundleObservation& o = bp.observations[k];
    if (!bp.active[k] || o.camera != camera) continue;
    frames.insert(o.frame);
    for (const Eigen::Vector2d& pixel : o.corners) {
      const int cx = std::clamp(static_cast<int>(8 * (pixel.x() + 0.5) / model.width), 0, 7);
      const int cy = std::clamp(static_cast<int>(6 * (pixel.y() + 0.5) / model.height), 0, 5);
      cells[cy * 8 + cx] = 1;
    }
  }
  (void)cam_from_rig;
  if (views) *views = static_cast<int>(frames.size());
  return std::count(cells.begin(), cells.end(), 1) / 48.0;
}

namespace {

std::string HeldReason(const std::string& name, double posterior, double prior, double ratio, double coverage,
                       int views) {
  std::ostringstream why;
  why << std::setprecision(3) << name << ": held at the given value: the data would constrain it to +-"
      << posterior << " against the prior's +-" << prior << " (needs < " << ratio << " x the prior; " << views
      << " views, markers cover " << std::setprecision(2) << 100.0 * coverage << " % of the image)";
  return why.str();
}

// Holds, per camera, the least constrained free entry whose posterior sigma is not below ratio x its
// prior; returns false when every free entry passes.
bool HoldWorst(const std::vector<Eigen::MatrixXd>& covariance, double ratio,
               std::vector<IntrinsicsReport>* reports, BundleProblem* bp) {
  bool held = false;
  for (IntrinsicsReport& r : *reports) {
    BundleIntrinsics& in = bp->intrinsics[r.index];
    if (!in.refined || covariance[r.index].size() == 0) continue;
    int worst = -1;
    double worst_ratio = ratio;
    for (size_t k = 0; k < r.names.size(); ++k) {
      if (!r.is_refined[k]) continue;
      const double q = std::sqrt(std::max(0.0, covariance[r.index](k, k))) / r.prior_sigma[k];
      if (q >= worst_ratio) {
        worst_ratio = q;
        worst = static_cast<int>(k);
      }
    }
    if (worst < 0) continue;
    r.held.push_back(HeldReason(r.names[worst], worst_ratio * r.prior_sigma[worst], r.prior_sigma[worst],
                                ratio, r.coverage, r.views));
    r.is_refined[worst] = 0;
    in.constant.push_back(worst);
    std::sort(in.constant.begin(), in.constant.end());
    in.refined = std::count(r.is_refined.begin(), r.is_refined.end(), 1) > 0;
    held = true;
  }
  return held;
}

}  // namespace

std::vector<IntrinsicsReport> PlanIntrinsicsRefinement(const IntrinsicsSettings& settings,
                                                       const std::vector<std::string>& camera_names,
                                                       double sigma_px, BundleProblem* bp) {
  std::vector<IntrinsicsReport> reports;
  if (settings.refine == IntrinsicsRefinement::kNone) return reports;
  const int n_cameras = static_cast<int>(bp->cam_from_rig.size());
  bp->intrinsics.assign(n_cameras, BundleIntrinsics{});
  for (int c = 0; c < n_cameras; ++c) {
    const std::vector<std::string>& only = settings.cameras;
    if (!only.empty() && std::find(only.begin(), only.end(), camera_names[c]) == only.end()) continue;
    const CameraModel& model = *bp->models[c];
    IntrinsicsReport report;
    report.camera = camera_names[c];
    report.index = c;
    report.names = IntrinsicsNames(model);
    report.given = IntrinsicsVector(model);
    report.prior_sigma = PriorSigma(settings.sigma, model);
    report.coverage = ImageCoverage(*bp, c, &report.views);
    if (report.views == 0) continue;
    const int n = static_cast<int>(report.given.size());
    report.is_refined.assign(n, 0);
    for (int k : RequestedIntrinsics(settings.refine, model)) report.is_refined[k] = 1;
    BundleIntrinsics& in = bp->intrinsics[c];
    in.values = report.given;
    in.prior = report.given;
    in.sigma = report.prior_sigma;
    in.prior_scale_px = sigma_px;
    for (int k = 0; k < n; ++k)
      if (!report.is_refined[k]) in.constant.push_back(k);
    in.refined = static_cast<int>(in.constant.size()) < n;
    reports.push_back(report);
  }
  // One information matrix for every round: holding entries does not move the parameters (computing it
  // again each round took a tenth of bench_selfcal's everything row).
  const IntrinsicsInformation information = IntrinsicsInformationOf(bp);
  while (HoldWorst(IntrinsicsCovariance(information, *bp, sigma_px), settings.observability_ratio, &reports,
                   bp)) {
  }
  return reports;
}

namespace {

// 95 % two-sided level of a normal deviate: a change within 1.96 posterior sigmas agrees with the given
// value.
constexpr double kAgreeSigmas = 1.96;
constexpr double kAgreeLevel = 0.05;  // family-wise over the cameras refined

// The standard normal deviate exceeded with probability p (upper tail), by bisection on erfc.
double NormalQuantileUpper(double p) {
  double lo = 0.0, hi = 40.0;
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (0.5 * std::erfc(mid / std::sqrt(2.0)) > p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// The chi-square value with `dof` degrees of freedom exceeded with probability p (Wilson-Hilferty; within
// 1 % of the exact quantile for the 1-9 entries of a camera at these levels).
double ChiSquareQuantileUpper(int dof, double p) {
  const double k = dof, z = NormalQuantileUpper(p);
  const double c = 1.0 - 2.0 / (9.0 * k) + z * std::sqrt(2.0 / (9.0 * k));
  return k * c * c * c;
}

// Holds entry k of a camera's intrinsics at the given value, with the reason.
void HoldAtGiven(size_t k, const std::string& why, IntrinsicsReport* r, BundleIntrinsics* in) {
  r->held.push_back(why);
  in->values[k] = r->given[k];
  r->is_refined[k] = 0;
  in->constant.push_back(static_cast<int>(k));
}

}  // namespace

bool KeepAgreeingIntrinsics(double sigma_px, std::vector<IntrinsicsReport>* reports, BundleProblem* bp,
                            IntrinsicsInformation* information) {
  IntrinsicsInformation computed = IntrinsicsInformationOf(bp);
  const std::vector<Eigen::MatrixXd> covariance = IntrinsicsCovariance(computed, *bp, sigma_px);
  if (information) *information = std::move(computed);
  int tested = 0;
  for (const IntrinsicsReport& r : *reports)
    tested += bp->intrinsics[r.index].refined && covariance[r.index].size() > 0;
  bool held = false;
  for (IntrinsicsReport& r : *reports) {
    BundleIntrinsics& in = bp->intrinsics[r.index];
    if (!in.refined || covariance[r.index].size() == 0) continue;
    std::vector<int> free;
    for (size_t k = 0; k < r.given.size(); ++k)
      if (r.is_refined[k]) free.push_back(static_cast<int>(k));
    // The camera as a whole first: the changes' Mahalanobis distance against the chi-square level that
    // leaves 5 % of sessions with a right calibration changed anywhere (tested entry by entry, 1 - 0.95^21
    // = 66 % of the sessions freed one of the three exact cameras' 21 entries, and its position
    // fell to the data's own precision: 3 mm along its axis).
    const int n = static_cast<int>(free.size());
    Eigen::VectorXd change(n);
    Eigen::MatrixXd cov(n, n);
    for (int a = 0; a < n; ++a) {
      change(a) = in.values[free[a]] - r.given[free[a]];
      for (int b = 0; b < n; ++b) cov(a, b) = covariance[r.index](free[a], free[b]);
    }
    const double distance_sq = change.dot(cov.ldlt().solve(change));
    const double level = ChiSquareQuantileUpper(n, kAgreeLevel / std::max(1, tested));
    if (distance_sq < level) {
      std::ostringstream why;
      why << std::setprecision(3) << "all kept at the given values: the data agree with them (squared "
          << "Mahalanobis distance of the refined changes " << distance_sq << " < " << level
          << ", chi-square, " << n << " entries, family-wise 5 %)";
      for (int k : free) HoldAtGiven(k, r.names[k] + ": " + why.str(), &r, &in);
      held = true;
    }
    if (distance_sq >= level) {
      // A camera that differs: its entries the data agree with are held one at a time, the best agreeing
      // first, each test conditional on those held before (the change and covariance of the others given
      // the held entry at its given value). Testing every entry on its marginal sigma held truly changed
      // ones at their wrong given values: the quick calibration's cy, 6 px off, refined 2.4-3.5 px
      // against a marginal sigma of 2 px (inflated by p1, p2, which agree) and was held in 3 of 20
      // sessions (bench_selfcal --ablate 20), a camera 2.1 mm off.
      std::vector<int> left(n);
      for (int a = 0; a < n; ++a) left[a] = a;
      while (!left.empty()) {
        int best = -1;
        double best_z = kAgreeSigmas;
        for (int a : left) {
          const double z = std::abs(change(a)) / std::sqrt(std::max(1e-300, cov(a, a)));
          if (z < best_z) {
            best_z = z;
            best = a;
          }
        }
        if (best < 0) break;
        const int k = free[best];
        std::ostringstream why;
        why << std::setprecision(3) << r.names[k]
            << ": kept at the given value: the data agree with it (refined " << change(best)
            << " from it, within " << kAgreeSigmas << " x its posterior sigma " << std::sqrt(cov(best, best))
            << " given the entries held before)";
        HoldAtGiven(k, why.str(), &r, &in);
        held = true;
        left.erase(std::find(left.begin(), left.end(), best));
        const Eigen::VectorXd gain = cov.col(best) / cov(best, best);
        const Eigen::RowVectorXd row = cov.row(best);
        const double held_change = change(best);
        change -= gain * held_change;
        cov -= gain * row;
      }
    }
    std::sort(in.constant.begin(), in.constant.end());
    in.refined = std::count(r.is_refined.begin(), r.is_refined.end(), 1) > 0;
  }
  return held;
}

void FinishIntrinsicsReports(BundleProblem* bp, double sigma_px, std::vector<IntrinsicsReport>* reports,
                             const IntrinsicsInformation* information) {
  const std::vector<Eigen::MatrixXd> covariance =
      information ? IntrinsicsCovariance(*information, *bp, sigma_px) : IntrinsicsCovariance(bp, sigma_px);
  for (IntrinsicsReport& r : *reports) {
    r.refined = IntrinsicsVector(bp->Model(r.index));
    r.posterior_sigma.assign(r.given.size(), 0.0);
    if (covariance[r.index].size() == 0) continue;
    for (size_t k = 0; k < r.given.size(); ++k)
      if (r.is_refined[k]) r.posterior_sigma[k] = std::sqrt(std::max(0.0, covariance[r.index](k, k)));
  }
}

namespace {

std::string JsonList(const std::vector<double>& values) {
  std::ostringstream out;
  out << std::setprecision(10) << "[";
  for (size_t i = 0; i < values.size(); ++i) {
    out << (i ? ", " : "");
    if (std::isfinite(values[i])) {
      out << values[i];
    } else {
      out << "null";
    }
  }
  return out.str() + "]";
}

}  // namespace

std::string SelfCalibrationJson(const MapReport& report) {
  if (report.intrinsics.empty()) return "";
  std::ostringstream j;
  j << "  \"intrinsics\": [\n";
  for (size_t i = 0; i < report.intrinsics.size(); ++i) {
    const IntrinsicsReport& r = report.intrinsics[i];
    std::vector<std::string> refined, held;
    for (size_t k = 0; k < r.names.size(); ++k)
      if (k < r.is_refined.size() && r.is_refined[k]) refined.push_back(JsonString(r.names[k]));
    for (const std::string& h : r.held) held.push_back(JsonString(h));
    j << "    {\"camera\": " << JsonString(r.camera) << ", \"views\": " << r.views
      << ", \"coverage\": " << std::setprecision(4) << r.coverage << ", \"names\": [";
    for (size_t k = 0; k < r.names.size(); ++k) j << (k ? ", " : "") << JsonString(r.names[k]);
    j << "], \"given\": " << JsonList(r.given) << ", \"refined\": " << JsonList(r.refined)
      << ", \"prior_sigma\": " << JsonList(r.prior_sigma)
      << ", \"posterior_sigma\": " << JsonList(r.posterior_sigma) << ", \"refined_entries\": [";
    for (size_t k = 0; k < refined.size(); ++k) j << (k ? ", " : "") << refined[k];
    j << "], \"held\": [";
    for (size_t k = 0; k < held.size(); ++k) j << (k ? ", " : "") << held[k];
    j << "]}" << (i + 1 < report.intrinsics.size() ? "," : "") << "\n";
  }
  j << "  ],\n";
  return j.str();
}

}  // namespace mcmt
