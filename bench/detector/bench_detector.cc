// Detection time per image on one thread (cv::setNumThreads(1)) at the paper's resolutions, in the
// accurate default mode and the fast mode (search near the previous frame's markers), on mcmt_sim
// sequences (30 fps, box object: 2-8 markers in view), plus peak memory. Prints markdown tables.
//   bench_detector [frames per camera (default 60)] [cameras (default 2)] [image width: only that size]
// (MCMT_BENCH_ONLY=accurate|fast|stock: only that detector; MCMT_BENCH_BLUR=sigma: renders blurred by a
// Gaussian of sigma px; MCMT_BENCH_DEBUG: markers whose fast-mode corners differ from the accurate mode's
// by more than 0.02 px, on stderr; MCMT_CANDIDATE_SEARCH=opencv|own: both modes' candidate_search;
// MCMT_BENCH_BAND=sides: fast mode's fast_band_sides; MCMT_BENCH_MISSES: the markers fast mode missed and
// how far they were from its markers of the frame before, on stderr; MCMT_CORNER_DUMP=FILE: every marker
// found, one line each: image width, camera, frame, mode (0 accurate, 1 fast), id and the four corners in
// hexadecimal floating point (%a), so that two builds' corners can be compared to the bit with cmp.)
#include <sys/resource.h>
#include <time.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <opencv2/core.hpp>
#include <string>

#include "detector/detector.h"
#include "sim/sim.h"
#include "tests/detector/sim_eval.h"

using namespace mcmt;

namespace {
// CPU time of this thread (the machine may be shared: wall time would count the others' load).
double ThreadSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}
double PeakRssMb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss / 1024.0;
}
// MCMT_BENCH_MISSES: the markers of the domain the accurate mode found and fast mode did not, with
// where they were in the frame before and how far they lie from the markers fast mode had then.
void PrintMisses(int camera, size_t frame, const std::vector<marker_t>& a, const std::vector<marker_t>& f,
                 const std::vector<marker_t>& previous_f, const std::vector<sim::MarkerView>& views,
                 const int size[2]) {
  auto box = [](const marker_t& m) {
    double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
    for (const auto& c : m.corners)
      x0 = std::min(x0, c[0]), x1 = std::max(x1, c[0]), y0 = std::min(y0, c[1]), y1 = std::max(y1, c[1]);
    return std::array<double, 4>{x0, y0, x1, y1};
  };
  for (const auto& r : a) {
    bool in_f = false;
    for (const auto& m : f) in_f = in_f || m.id == r.id;
    const sim::MarkerView* v = nullptr;
    for (const auto& w : views)
      if (w.id == r.id) v = &w;
    if (in_f || !v || !testing::InCornerTargetDomain(*v)) continue;
    const auto b = box(r);
    // Nearest previous marker: gap between boxes (px) and that marker's larger box side.
    double gap = 1e9, tracked_side = 0, union_gap = 1e9;
    double u0 = 1e9, v0 = 1e9, u1 = -1e9, v1 = -1e9;
    for (const auto& m : previous_f) {
      const auto p = box(m);
      const double g = std::max({p[0] - b[2], b[0] - p[2], p[1] - b[3], b[1] - p[3], 0.0});
      if (g < gap) gap = g, tracked_side = std::max(p[2] - p[0], p[3] - p[1]);
      u0 = std::min(u0, p[0]), v0 = std::min(v0, p[1]), u1 = std::max(u1, p[2]), v1 = std::max(v1, p[3]);
    }
    if (!previous_f.empty()) union_gap = std::max({u0 - b[2], b[0] - u1, v0 - b[3], b[1] - v1, 0.0});
    const double border = std::min({b[0], b[1], size[0] - 1 - b[2], size[1] - 1 - b[3]});
    std::fprintf(
        stderr,
        "miss cam %d frame %zu id %d size %.1f angle %.0f | nearest tracked gap %.0f px (%.2f of its "
        "side %.0f), union gap %.0f px, border %.0f px, tracked %zu\n",
        camera, frame, r.id, v->size_px, v->view_angle_deg, gap, gap / std::max(tracked_side, 1.0),
        tracked_side, union_gap, border, previous_f.size());
  }
}
}  // namespace

int main(int argc, char** argv) {
  const int frames = argc > 1 ? std::atoi(argv[1]) : 60;
  const int num_cameras = argc > 2 ? std::atoi(argv[2]) : 2;
  const int only_width = argc > 3 ? std::atoi(argv[3]) : 0;
  // MCMT_BENCH_ONLY=accurate|fast|stock: run only that detector (instruction counts per mode, callgrind).
  const std::string only = std::getenv("MCMT_BENCH_ONLY") ? std::getenv("MCMT_BENCH_ONLY") : "";
  FILE* corner_dump =
      std::getenv("MCMT_CORNER_DUMP") ? std::fopen(std::getenv("MCMT_CORNER_DUMP"), "w") : nullptr;
  cv::setNumThreads(1);
  const testing::DetectorBenchScene scene = testing::MakeDetectorBenchScene(
      frames, std::getenv("MCMT_BENCH_BLUR") ? std::atof(std::getenv("MCMT_BENCH_BLUR")) : 0.0);
  const sim::SimObject& object = scene.object;
  const std::vector<sim::SimFrame>& trajectory = scene.trajectory;
  const sim::Renderer& renderer = *scene.renderer;
  const MarkerConfig& mc = scene.markers;

  std::printf("## mcmt detector: time per image, one thread (thread CPU time)\n\n");
  std::printf(
      "%d frames x %d cameras per resolution (mcmt_sim, box object, 5 cm markers, cameras 1 m away, noise "
      "2).\n\n",
      frames, num_cameras);
  std::printf(
      "| resolution | markers/image (min-max) | accurate ms | accurate images/s | fast ms | fast images/s | "
      "fast full searches | markers found, fast / accurate (>= 15 px, <= 75 deg) | fast vs accurate corners, "
      "max px (>= 15 px, <= 75 deg) | the same, all sizes | "
      "stock detectMarkers ms | "
      "no clean edge fit (accurate/fast) |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  long long rereads = 0, rereads_found = 0;
  std::string all_found;  // per resolution
  const int sizes[4][2] = {{320, 240}, {640, 480}, {1280, 960}, {1920, 1440}};
  for (const auto& size : sizes) {
    if (only_width > 0 && size[0] != only_width) continue;
    const std::vector<sim::SimCamera> cameras = scene.Cameras(num_cameras, size[0], size[1]);
    std::vector<std::vector<cv::Mat>> images(num_cameras);
    for (int c = 0; c < num_cameras; ++c)
      for (const auto& f : trajectory)
        images[c].push_back(renderer.Render(cameras[c], c, f.seq, f.rig_from_object));
    double accurate_ms = 0, fast_ms = 0, stock_ms = 0, max_diff = 0, max_diff_all_sizes = 0;
    int min_markers = 1 << 30, max_markers = 0;
    long long full = 0, fails_a = 0, fails_f = 0, found_a = 0, found_f = 0, all_a = 0, all_f = 0;
    for (int c = 0; c < num_cameras; ++c) {
      DetectorOptions accurate_options, fast_options;
      if (std::getenv("MCMT_BENCH_REFINE"))
        accurate_options.corner_refinement = std::getenv("MCMT_BENCH_REFINE");
      if (std::getenv("MCMT_BENCH_SHARP"))
        accurate_options.sharp_smoothing = std::atof(std::getenv("MCMT_BENCH_SHARP"));
      if (std::getenv("MCMT_BENCH_PASSES"))
        accurate_options.edge_passes = std::atoi(std::getenv("MCMT_BENCH_PASSES"));
      fast_options.fast = true;
      if (std::getenv("MCMT_BENCH_BAND"))
        fast_options.fast_band_sides = std::atof(std::getenv("MCMT_BENCH_BAND"));
      if (const char* search = std::getenv("MCMT_CANDIDATE_SEARCH"))
        accurate_options.candidate_search = fast_options.candidate_search = search;
      MarkerDetector accurate(mc, accurate_options), fast(mc, fast_options);
      accurate.SetCamera(cameras[c].model);
      fast.SetCamera(cameras[c].model);
      auto dict = cv::aruco::getPredefinedDictionary(cv::aruco::DICT_6X6_250);
      auto params = cv::aruco::DetectorParameters::create();
      std::vector<marker_t> previous_f;
      for (const cv::Mat& image : images[c]) {
        auto t0 = ThreadSeconds();
        const auto a = only != "fast" && only != "stock" ? accurate.Detect(image) : std::vector<marker_t>();
        auto t1 = ThreadSeconds();
        const auto f = only != "accurate" && only != "stock" ? fast.Detect(image) : std::vector<marker_t>();
        auto t2 = ThreadSeconds();
        std::vector<std::vector<cv::Point2f>> corners;
        std::vector<int> ids;
        if (only.empty() || only == "stock") cv::aruco::detectMarkers(image, dict, corners, ids, params);
        auto t3 = ThreadSeconds();
        if (corner_dump)
          for (const auto* found : {&a, &f})
            for (const auto& m : *found) {
              std::fprintf(corner_dump, "%d %d %zu %d %d", size[0], c,
                           static_cast<size_t>(&image - &images[c][0]), found == &a ? 0 : 1, m.id);
              for (int k = 0; k < 4; ++k)
                std::fprintf(corner_dump, " %a %a", m.corners[k][0], m.corners[k][1]);
              std::fprintf(corner_dump, "\n");
            }
        accurate_ms += 1000 * (t1 - t0);
        fast_ms += 1000 * (t2 - t1);
        stock_ms += 1000 * (t3 - t2);
        min_markers = std::min<int>(min_markers, a.size());
        max_markers = std::max<int>(max_markers, a.size());
        if (std::getenv("MCMT_BENCH_DEBUG"))
          for (const auto& m : f)
            for (const auto& r : a)
              if (m.id == r.id && [&] {
                    double d = 0;
                    for (int k = 0; k < 4; ++k)
                      for (int x = 0; x < 2; ++x)
                        d = std::max(d, std::abs(m.corners[k][x] - r.corners[k][x]));
                    return d > 0.02;
                  }()) {
                const size_t fi = &image - &images[c][0];
                for (const auto& v : sim::ProjectMarkers(cameras[c], object, trajectory[fi].rig_from_object))
                  if (v.id == m.id)
                    std::fprintf(stderr,
                                 "cam %d frame %zu id %d angle %.0f size %.1f occl %d vis %d: truth %.2f "
                                 "%.2f %.2f %.2f acc %.2f %.2f %.2f %.2f fast %.2f %.2f %.2f %.2f\n",
                                 c, fi, m.id, v.view_angle_deg, v.size_px, v.occluded, v.fully_visible,
                                 v.corners[0].x(), v.corners[0].y(), v.corners[2].x(), v.corners[2].y(),
                                 r.corners[0][0], r.corners[0][1], r.corners[2][0], r.corners[2][1],
                                 m.corners[0][0], m.corners[0][1], m.corners[2][0], m.corners[2][1]);
              }
        const size_t frame_index = &image - &images[c][0];
        const auto views = sim::ProjectMarkers(cameras[c], object, trajectory[frame_index].rig_from_object);
        // Markers fully visible within 75 degrees; of those, the domain (at least 15 px).
        auto view_of = [&](int id) -> const sim::MarkerView* {
          for (const auto& v : views)
            if (v.id == id) return &v;
          return nullptr;
        };
        all_a += static_cast<long long>(a.size()), all_f += static_cast<long long>(f.size());
        for (const auto& r : a) found_a += view_of(r.id) && testing::InCornerTargetDomain(*view_of(r.id));
        if (std::getenv("MCMT_BENCH_MISSES") && frame_index > 0)
          PrintMisses(c, frame_index, a, f, previous_f, views, size);
        previous_f = f;
        for (const auto& m : f) found_f += view_of(m.id) && testing::InCornerTargetDomain(*view_of(m.id));
        for (const auto& m : f)
          for (const auto& r : a) {
            const sim::MarkerView* v = m.id == r.id ? view_of(m.id) : nullptr;
            if (!v || !testing::InCornerTargetDomain(*v, 0.0)) continue;
            double d = 0;
            for (int k = 0; k < 4; ++k)
              d = std::max({d, std::abs(m.corners[k][0] - r.corners[k][0]),
                            std::abs(m.corners[k][1] - r.corners[k][1])});
            max_diff_all_sizes = std::max(max_diff_all_sizes, d);
            if (testing::InCornerTargetDomain(*v)) max_diff = std::max(max_diff, d);
          }
      }
      full += fast.stats().full_searches;
      fails_a += accurate.stats().refine_failures;
      fails_f += fast.stats().refine_failures;
      rereads += accurate.stats().rereads, rereads_found += accurate.stats().rereads_found;
    }
    const int n = num_cameras * frames;
    std::printf(
        "| %dx%d | %d-%d | %.2f | %.0f | %.2f | %.0f | %lld of %d | %lld / %lld | %.3f | %.3f | %.2f | "
        "%lld/%lld |\n",
        size[0], size[1], min_markers, max_markers, accurate_ms / n, 1000.0 * n / accurate_ms, fast_ms / n,
        1000.0 * n / fast_ms, full, n, found_f, found_a, max_diff, max_diff_all_sizes, stock_ms / n, fails_a,
        fails_f);
    all_found += std::to_string(size[0]) + "x" + std::to_string(size[1]) + " " + std::to_string(all_f) +
                 " / " + std::to_string(all_a) + "; ";
    std::fflush(stdout);
  }
  std::printf("\nMarkers found, all sizes and angles (fast / accurate): %s\n", all_found.c_str());
  std::printf("\nRejected candidates read again (accurate mode): %lld, of which markers: %lld\n", rereads,
              rereads_found);
  std::printf(
      "\nPeak resident memory of this benchmark (all images of one resolution held in memory): %.0f MB\n",
      PeakRssMb());
  if (corner_dump) std::fclose(corner_dump);
  return 0;
}
