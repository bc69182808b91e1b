// bench_core: speed of the core building blocks, as markdown tables.
//   build-core/bench/bench_core [--quick]
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <functional>
#include <random>
#include <string>

#include "core/camera.h"
#include "core/files.h"
#include "core/frame_sync.h"
#include "core/ippe.h"
#include "core/lcm_util.h"
#include "core/medoid.h"

namespace {

using namespace mcmt;
using Clock = std::chrono::steady_clock;

volatile double g_sink = 0;

// Runs fn(i) for i in [0, n) repeatedly for at least min_seconds; returns seconds per call.
double TimePerCall(int n, const std::function<void(int)>& fn, double min_seconds) {
  int rounds = 0;
  const auto start = Clock::now();
  double elapsed = 0;
  do {
    for (int i = 0; i < n; ++i) fn(i);
    ++rounds;
    elapsed = std::chrono::duration<double>(Clock::now() - start).count();
  } while (elapsed < min_seconds);
  return elapsed / (static_cast<double>(rounds) * n);
}

CameraModel Camera(DistortionModel model) {
  CameraModel c;
  c.width = 1280;
  c.height = 720;
  c.fx = 894.5;
  c.fy = 896.9;
  c.cx = 624.0;
  c.cy = 361.3;
  c.model = model;
  if (model == DistortionModel::kRadTan) c.distortion = {-0.338, 0.0967, -0.00135, 0.00316, -0.00375};
  if (model == DistortionModel::kFisheye) c.distortion = {0.03, -0.01, 0.004, -0.001};
  return c;
}

}  // namespace

int main(int argc, char** argv) {
  const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
  const double t = quick ? 0.05 : 0.3;
  std::mt19937_64 rng(1);

  std::printf(
      "## Camera model (per point)\n\n| model | Project | Project + Jacobian | Unproject "
      "|\n|---|---|---|---|\n");
  for (auto model : {DistortionModel::kNone, DistortionModel::kRadTan, DistortionModel::kFisheye}) {
    const CameraModel cam = Camera(model);
    std::vector<Eigen::Vector3d> points;
    std::vector<Eigen::Vector2d> pixels;
    std::uniform_real_distribution<double> u(-0.6, 0.6), v(-0.35, 0.35);
    for (int i = 0; i < 1000; ++i) {
      points.emplace_back(u(rng), v(rng), 1.0);
      pixels.push_back(cam.Project(points.back()));
    }
    const double p = TimePerCall(
        1000, [&](int i) { g_sink = g_sink + cam.Project(points[i]).x(); }, t);
    const double pj = TimePerCall(
        1000,
        [&](int i) {
          Eigen::Vector2d px;
          Eigen::Matrix<double, 2, 3> j;
          cam.Project(points[i], &px, &j);
          g_sink = g_sink + j(0, 0);
        },
        t);
    const double up = TimePerCall(
        1000, [&](int i) { g_sink = g_sink + cam.Unproject(pixels[i]).x(); }, t);
    std::printf("| %s | %.0f ns | %.0f ns | %.0f ns |\n", DistortionModelName(model).c_str(), p * 1e9,
                pj * 1e9, up * 1e9);
  }

  std::printf(
      "\n## IPPE square pose (per marker, both hypotheses + errors)\n\n| model | time |\n|---|---|\n");
  for (auto model : {DistortionModel::kNone, DistortionModel::kRadTan}) {
    const CameraModel cam = Camera(model);
    std::vector<MarkerCorners2d> squares;
    for (int i = 0; i < 200; ++i) {
      Rigid3 cam_from_marker = RandomRigid(rng, 0.1);
      cam_from_marker.linear() =
          RigidFromRvecTvec(Eigen::Vector3d(3.0 + 0.3 * (i % 5 - 2) / 2, 0.2, 0.1), Eigen::Vector3d::Zero())
              .linear();
      cam_from_marker.translation().z() = 1.0 + (i % 7) * 0.2;
      MarkerCorners2d c;
      const auto corners = MarkerCornersInMarker(0.05);
      for (int k = 0; k < 4; ++k) c[k] = cam.Project(cam_from_marker * corners[k]);
      squares.push_back(c);
    }
    const double s = TimePerCall(
        200, [&](int i) { g_sink = g_sink + EstimateSquarePose(cam, squares[i], 0.05).ratio; }, t);
    std::printf("| %s | %.1f us |\n", DistortionModelName(model).c_str(), s * 1e6);
  }

  std::printf(
      "\n## Transform medoid\n\n| candidates | exact (max_exact=100000) | default (max_exact=400) "
      "|\n|---|---|---|\n");
  for (int n : {10, 100, 400, 1000, 4000, 20000}) {
    std::vector<Rigid3> c;
    for (int i = 0; i < n; ++i) c.push_back(RandomRigid(rng, 1.0));
    MedoidOptions exact;
    exact.max_exact = 100000;
    const double te = n <= 4000 ? TimePerCall(
                                      1, [&](int) { g_sink = g_sink + TransformMedoid(c, exact).index; }, t)
                                : -1;
    const double td = TimePerCall(
        1, [&](int) { g_sink = g_sink + TransformMedoid(c).index; }, t);
    if (te >= 0)
      std::printf("| %d | %.3f ms | %.3f ms |\n", n, te * 1e3, td * 1e3);
    else
      std::printf("| %d | (skipped) | %.3f ms |\n", n, td * 1e3);
  }

  std::printf("\n## LCM detections_t (30 markers)\n\n| step | time |\n|---|---|\n");
  {
    detections_t d;
    d.utime = 1;
    d.seq = 2;
    d.camera = "cam0";
    d.dictionary = "DICT_6X6_250";
    d.camera_model = ToCameraModelMsg(Camera(DistortionModel::kRadTan));
    d.num_markers = 30;
    d.markers.resize(30);
    d.detection_ms = 1;
    const std::vector<uint8_t> bytes = Encode(d);
    const double enc = TimePerCall(
        1, [&](int) { g_sink = g_sink + Encode(d).size(); }, t);
    const double dec = TimePerCall(
        1,
        [&](int) {
          detections_t out;
          g_sink = g_sink + Decode(bytes.data(), bytes.size(), &out);
        },
        t);
    std::string err;
    const double chk = TimePerCall(
        1, [&](int) { g_sink = g_sink + CheckEncoded(bytes.data(), bytes.size(), &d, &err); }, t);
    std::printf(
        "| Encode (%zu bytes) | %.2f us |\n| Decode incl. check | %.2f us |\n| structural check alone | %.2f "
        "us |\n",
        bytes.size(), enc * 1e6, dec * 1e6, chk * 1e6);
  }

  std::printf("\n## FrameSynchronizer (4 cameras)\n\n| step | time |\n|---|---|\n");
  {
    FrameSyncOptions o;
    o.cameras = {"cam0", "cam1", "cam2", "cam3"};
    FrameSynchronizer sync(o);
    std::vector<detections_t> views(4);
    for (int k = 0; k < 4; ++k) views[k].camera = o.cameras[k];
    int64_t frame = 0;
    const double add = TimePerCall(
        4,
        [&](int k) {
          views[k].utime = 1000000 + frame * 33333;
          g_sink = g_sink + sync.Add(views[k], 0).size();
          if (k == 3) ++frame;
        },
        t);
    std::printf("| Add (per view) | %.2f us |\n", add * 1e6);
  }

  std::printf("\n## map.yaml (20 cameras, 200 markers)\n\n| step | time |\n|---|---|\n");
  {
    RigMap map;
    map.dictionary = "DICT_6X6_250";
    map.reference_camera = "cam0";
    for (int i = 0; i < 20; ++i) {
      MapCamera c;
      c.name = "cam" + std::to_string(i);
      c.model = Camera(DistortionModel::kRadTan);
      c.rig_from_cam = RandomRigid(rng, 2.0);
      map.cameras.push_back(c);
    }
    for (int i = 0; i < 200; ++i) {
      MapMarker m;
      m.id = i;
      m.size = 0.05;
      m.object_from_marker = RandomRigid(rng, 0.2);
      map.markers.push_back(m);
    }
    const std::string path = "/tmp/bench_core_map." + std::to_string(::getpid()) + ".yaml";
    const double w = TimePerCall(
        1, [&](int) { WriteMap(path, map); }, t);
    const double r = TimePerCall(
        1, [&](int) { g_sink = g_sink + ReadMap(path).markers.size(); }, t);
    std::remove(path.c_str());
    std::printf("| WriteMap (atomic, fsync) | %.2f ms |\n| ReadMap | %.2f ms |\n", w * 1e3, r * 1e3);
  }
  return 0;
}
