// Viewer benchmark: scene build time, offscreen render time (EGL, software Mesa here), PNG encoding,
// live pose ingestion, and memory. Prints markdown tables.
//   build-viz/bench/bench_viz [--quick]
#include <mrpt/opengl/CFBORender.h>
#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "tests/viz/test_rig.h"
#include "viz/scene.h"

namespace {

using Clock = std::chrono::steady_clock;

double Ms(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

long MaxRssMb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss / 1024;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace mcmt::viz;
  const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
  const int renders = quick ? 5 : 30;

  std::printf("## mcmt-viz: scene build and offscreen render\n\n");
  std::printf("Software OpenGL (Mesa llvmpipe through EGL), %d renders per row after one warm-up.\n\n",
              renders);
  std::printf(
      "| cameras | markers | trajectory rows | size | panels | build ms | render ms (mean) | fps | PNG "
      "encode ms |\n");
  std::printf("|---:|---:|---:|---|---:|---:|---:|---:|---:|\n");
  struct Case {
    int cameras, frames, w, h, panels;
  };
  std::vector<Case> cases = {{4, 300, 640, 480, 1},   {4, 300, 1280, 720, 1},    {8, 3000, 1280, 720, 1},
                             {8, 3000, 1280, 720, 2}, {16, 20000, 1280, 720, 1}, {4, 300, 1920, 1080, 1}};
  if (quick) cases.resize(2);
  for (const auto& c : cases) {
    const auto rig = testing::MakeTestRig(c.cameras, c.frames);
    SceneOptions o;
    o.width = c.w;
    o.height = c.h;
    const auto t0 = Clock::now();
    VizScene scene(o);
    std::vector<PanelInput> panels;
    for (int p = 0; p < c.panels; ++p)
      panels.push_back(PanelInput{p == 0 ? "a" : "b", rig.map, rig.trajectory});
    scene.SetPanels(panels);
    const auto t1 = Clock::now();
    mrpt::opengl::CFBORender render(c.w, c.h);
    cv::Mat img = scene.Render(&render);  // warm-up: shaders, textures
    const auto t2 = Clock::now();
    for (int i = 0; i < renders; ++i) {
      scene.SetCurrentFrame(i % c.frames);
      img = scene.Render(&render);
    }
    const auto t3 = Clock::now();
    std::vector<uchar> png;
    const auto t4 = Clock::now();
    for (int i = 0; i < 5; ++i) cv::imencode(".png", img, png);
    const auto t5 = Clock::now();
    const double render_ms = Ms(t2, t3) / renders;
    std::printf("| %d | %zu | %d | %dx%d | %d | %.1f | %.1f | %.1f | %.1f |\n", c.cameras,
                rig.map.markers.size(), c.frames, c.w, c.h, c.panels, Ms(t0, t1), render_ms,
                1000.0 / render_ms, Ms(t4, t5) / 5);
  }

  std::printf("\n## Live pose ingestion (scene update per pose, no redraw)\n\n");
  std::printf("| poses | trail_max | total ms | us per pose | poses/s |\n|---:|---:|---:|---:|---:|\n");
  for (int trail_max : {2000, 20000}) {
    const auto rig = testing::MakeTestRig(4, 1);
    SceneOptions o;
    o.trail_max = trail_max;
    VizScene scene(o);
    scene.SetPanels({PanelInput{"live", rig.map, {}}});
    const int n = quick ? 5000 : 50000;
    mcmt::TrajectoryRow row = rig.trajectory[0];
    const auto t0 = Clock::now();
    for (int i = 0; i < n; ++i) {
      row.seq = i;
      row.utime += 1000;
      row.rig_from_object.translation().x() += 1e-5;
      scene.AddPose(row);
    }
    const auto t1 = Clock::now();
    std::printf("| %d | %d | %.1f | %.2f | %.0f |\n", n, trail_max, Ms(t0, t1), 1000.0 * Ms(t0, t1) / n,
                n / (Ms(t0, t1) / 1000.0));
  }
  std::printf("\nPeak RSS of this benchmark: %ld MB\n", MaxRssMb());
  return 0;
}
