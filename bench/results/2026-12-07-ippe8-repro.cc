// ippe8 reproduction (2026-12-07-ippe8.md): EstimateSquarePose vs cv::solvePnPGeneric(IPPE_SQUARE) with K on
// pixels, squares of 5 cm at 0.5/1/2 m tilted 0-20 deg about random in-plane axes. Usage: repro NOISE_PX
// [VERBOSE]. g++ -O2 -std=c++17 -I. -isystem /usr/include/opencv4 -isystem /usr/include/eigen3 THIS.cc
// build/core/libmcmt_core.a $(pkg-config --libs opencv4)
#include <cstdio>
#include <opencv2/calib3d.hpp>
#include <random>

#include "core/ippe.h"
#include "core/se3.h"

using namespace mcmt;
constexpr double kDeg = M_PI / 180;

// Marker normal direction (marker +z) in the camera; the marker faces the camera: +z points to the camera.
Rigid3 MakeTruth(std::mt19937_64& rng, double dist, double tilt_deg, const CameraModel& cam) {
  std::uniform_real_distribution<double> u(-1, 1);
  // position: random within 80% of the image at depth such that |p| = dist
  Eigen::Vector3d ray((u(rng) * 0.4 * cam.width) / cam.fx, (u(rng) * 0.4 * cam.height) / cam.fy, 1.0);
  const Eigen::Vector3d p = ray.normalized() * dist;
  const Eigen::Vector3d v = -p.normalized();  // from marker to camera
  // frame with z = v
  Eigen::Vector3d a = v.unitOrthogonal();
  Eigen::Matrix3d facing;
  facing.col(2) = v;
  facing.col(0) = a;
  facing.col(1) = v.cross(a);
  // random in-plane rotation, then tilt about a random in-plane axis
  const double spin = u(rng) * M_PI, axis_angle = u(rng) * M_PI;
  const Eigen::Vector3d axis_m(std::cos(axis_angle), std::sin(axis_angle), 0);
  Eigen::Matrix3d R = facing * Eigen::AngleAxisd(tilt_deg * kDeg, axis_m).toRotationMatrix() *
                      Eigen::AngleAxisd(spin, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  Rigid3 t = Rigid3::Identity();
  t.linear() = R;
  t.translation() = p;
  return t;
}

double Rms(const CameraModel& cam, const Rigid3& T, const MarkerCorners2d& c, double side) {
  const auto c3 = MarkerCornersInMarker(side);
  double s = 0;
  for (int i = 0; i < 4; ++i) s += (cam.Project(T * c3[i]) - c[i]).squaredNorm();
  return std::sqrt(s / 4);
}

// The near-mirror: normal reflected about the line of sight, turned about the centre.
double MirrorAngle(const Rigid3& truth, const Rigid3& h) {
  const Eigen::Vector3d v = -truth.translation().normalized();
  const Eigen::Vector3d n = truth.linear().col(2);
  const Eigen::Vector3d n2 = 2 * n.dot(v) * v - n;
  return std::acos(std::min(1.0, n2.dot(h.linear().col(2)))) / kDeg;
}

int main(int argc, char** argv) {
  const double noise = argc > 1 ? atof(argv[1]) : 0.0;
  const int verbose = argc > 2 ? atoi(argv[2]) : 0;
  const CameraModel cam = CameraModel::Pinhole(1280, 960, 1000, 639.5, 479.5);
  const double side = 0.05;
  std::mt19937_64 rng(7);
  std::normal_distribution<double> nd(0, 1);
  printf("noise %.2f px\n", noise);
  printf(
      "dist tilt | ours: best_err best_px  2nd_err 2nd_px 2nd_vs_mirror ratio | cv(K): best_err best_px "
      "2nd_err 2nd_px\n");
  double worst_best_exact = 0, worst_second_mirror = 0;
  int best_wrong = 0, n = 0;
  for (double dist : {0.5, 1.0, 2.0}) {
    for (int tilt = 0; tilt <= 20; ++tilt) {
      for (int rep = 0; rep < 5; ++rep) {
        const Rigid3 truth = MakeTruth(rng, dist, tilt, cam);
        const auto c3 = MarkerCornersInMarker(side);
        MarkerCorners2d c;
        for (int i = 0; i < 4; ++i)
          c[i] = cam.Project(truth * c3[i]) + noise * Eigen::Vector2d(nd(rng), nd(rng));
        const SquarePose sp = EstimateSquarePose(cam, c, side);
        // OpenCV on pixels with K
        std::vector<cv::Point3d> op;
        std::vector<cv::Point2d> ip;
        for (int i = 0; i < 4; ++i) {
          op.emplace_back(c3[i].x(), c3[i].y(), c3[i].z());
          ip.emplace_back(c[i].x(), c[i].y());
        }
        cv::Mat K = (cv::Mat_<double>(3, 3) << cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1);
        std::vector<cv::Mat> rv, tv;
        cv::solvePnPGeneric(op, ip, K, cv::noArray(), rv, tv, false, cv::SOLVEPNP_IPPE_SQUARE);
        double cve[2] = {NAN, NAN}, cvp[2] = {NAN, NAN};
        for (size_t k = 0; k < rv.size() && k < 2; ++k) {
          const Rigid3 T = RigidFromRvecTvec(
              Eigen::Vector3d(rv[k].at<double>(0), rv[k].at<double>(1), rv[k].at<double>(2)),
              Eigen::Vector3d(tv[k].at<double>(0), tv[k].at<double>(1), tv[k].at<double>(2)));
          cve[k] = RotationAngle(T, truth) / kDeg;
          cvp[k] = Rms(cam, T, c, side);
        }
        const double e0 = RotationAngle(sp.hypotheses[0].cam_from_marker, truth) / kDeg;
        const double e1 = RotationAngle(sp.hypotheses[1].cam_from_marker, truth) / kDeg;
        const double m1 = MirrorAngle(truth, sp.hypotheses[1].cam_from_marker);
        ++n;
        if (noise == 0) worst_best_exact = std::max(worst_best_exact, sp.hypotheses[0].error_px);
        if (tilt >= 1 && noise == 0) worst_second_mirror = std::max(worst_second_mirror, m1);
        if (e0 > e1 + 1e-9) ++best_wrong;
        if (verbose || (noise == 0 && (sp.hypotheses[0].error_px > 1e-6 || m1 > 1.0 || e0 > 1e-4)))
          printf("%.1f %2d | %8.4f %9.2e  %8.3f %8.4f %7.3f %9.3g | %8.4f %9.2e %8.3f %8.4f\n", dist, tilt,
                 e0, sp.hypotheses[0].error_px, e1, sp.hypotheses[1].error_px, m1, sp.ratio, cve[0], cvp[0],
                 cve[1], cvp[1]);
      }
    }
  }
  printf(
      "n %d  worst best-hypothesis rms on exact corners %.3g px, worst 2nd-vs-mirror normal %.3g deg, best "
      "further from truth than 2nd: %d\n",
      n, worst_best_exact, worst_second_mirror, best_wrong);
}
