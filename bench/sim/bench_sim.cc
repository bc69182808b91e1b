// Simulator speed: rendering (one thread, per image), a rendered session on 1 vs 2 threads, and the
// detections-only mode (messages per second, peak memory). Prints markdown tables.
//   bench_sim [--quick]
#include <time.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "sim/sim.h"

namespace fs = std::filesystem;
using namespace mcmt;
using namespace mcmt::sim;
using Clock = std::chrono::steady_clock;

namespace {

double Seconds(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

double ThreadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

// VmHWM (peak resident set) in MiB, or -1.
double PeakRssMiB() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  return -1;
}

double RssMiB() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  return -1;
}

// Resets VmHWM to the current RSS (Linux >= 4.0); false when not allowed.
bool ResetPeakRss() {
  std::ofstream out("/proc/self/clear_refs");
  out << "5";
  out.flush();
  return static_cast<bool>(out);
}

std::string TempDir(const std::string& tag) {
  return (fs::temp_directory_path() / ("mcmt_bench_sim_" + tag + "_" + std::to_string(::getpid()))).string();
}

struct RenderRow {
  std::string what;
  int images = 0;
  double wall = 0, cpu = 0;
};

RenderRow BenchRender(int width, int height, bool motion_blur, int images) {
  RigOptions ro;
  ro.width = width;
  ro.height = height;
  const std::vector<SimCamera> cams = MakeRig(ro);
  const SimObject object = MakeObject(ObjectOptions());
  TrajectoryOptions to;
  to.frames = images + 1;
  const std::vector<SimFrame> frames = MakeTrajectory(to);
  RenderOptions opts;
  if (motion_blur) opts.motion_blur_samples = 5;
  const Renderer renderer(object, "DICT_6X6_250", opts);
  // One warm-up image (tables, texture).
  renderer.Render(cams[0], 0, 0, frames[0].rig_from_object);
  RenderRow row;
  row.what =
      std::to_string(width) + "x" + std::to_string(height) + (motion_blur ? ", motion blur (5 poses)" : "");
  row.images = images;
  const auto t0 = Clock::now();
  const double c0 = ThreadCpuSeconds();
  long long checksum = 0;
  for (int i = 0; i < images; ++i) {
    const int k = i % static_cast<int>(cams.size());
    const cv::Mat image = renderer.Render(cams[k], k, frames[i + 1].seq, frames[i + 1].rig_from_object,
                                          &frames[i].rig_from_object);
    checksum += image.at<uint8_t>(height / 2, width / 2);
  }
  row.cpu = ThreadCpuSeconds() - c0;
  row.wall = Seconds(t0);
  if (checksum < 0) std::printf("impossible\n");
  return row;
}

double ProcessCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

std::string LoadAverage() {
  std::ifstream in("/proc/loadavg");
  std::string a, b, c;
  in >> a >> b >> c;
  return a + " " + b + " " + c;
}

// CPU seconds per wall second that two busy threads actually get (2.0 on two free cores): how much
// parallelism the machine offers right now.
double AvailableCores() {
  const auto t0 = Clock::now();
  const double c0 = ProcessCpuSeconds();
  std::vector<std::thread> threads;
  for (int t = 0; t < 2; ++t)
    threads.emplace_back([] {
      volatile double x = 0;
      const auto start = Clock::now();
      while (Seconds(start) < 0.5)
        for (int i = 0; i < 10000; ++i) x = x + 1e-9 * i;
    });
  for (auto& t : threads) t.join();
  return (ProcessCpuSeconds() - c0) / Seconds(t0);
}

struct SessionRow {
  double wall = 0, cpu = 0;
};

SessionRow BenchSession(int frames, int cameras, int threads) {
  DatasetOptions o;
  o.out_dir = TempDir("session_t" + std::to_string(threads));
  o.trajectory.frames = frames;
  o.rig.num_cameras = cameras;
  o.threads = threads;
  SessionRow row;
  const auto t0 = Clock::now();
  const double c0 = ProcessCpuSeconds();
  const DatasetSummary s = GenerateDataset(o);
  row.cpu = ProcessCpuSeconds() - c0;
  row.wall = Seconds(t0);
  if (s.images_written != static_cast<int64_t>(frames) * cameras)
    std::fprintf(stderr, "bench_sim: %lld images written, expected %d\n",
                 static_cast<long long>(s.images_written), frames * cameras);
  fs::remove_all(o.out_dir);
  return row;
}

struct DetRow {
  int frames = 0, cameras = 0;
  int64_t messages = 0;
  double wall = 0, peak_mib = 0, start_mib = 0, log_mib = 0;
};

DetRow BenchDetections(int frames, int cameras) {
  DatasetOptions o;
  o.out_dir = TempDir("detections");
  o.trajectory.frames = frames;
  o.rig.num_cameras = cameras;
  o.detections_only = true;
  DetRow row;
  row.frames = frames;
  row.cameras = cameras;
  row.start_mib = RssMiB();
  const auto t0 = Clock::now();
  const DatasetSummary s = GenerateDataset(o);
  row.wall = Seconds(t0);
  row.peak_mib = PeakRssMiB();
  row.messages = s.messages_written;
  row.log_mib = fs::file_size(fs::path(o.out_dir) / "detections.lcmlog") / (1024.0 * 1024.0);
  fs::remove_all(o.out_dir);
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--quick") == 0) {
      quick = true;
    } else {
      std::fprintf(stderr, "usage: bench_sim [--quick]\n");
      return 2;
    }
  }
  std::printf("# mcmt simulator benchmark%s (%u hardware threads, load average %s at start)\n\n",
              quick ? " (--quick)" : "", std::thread::hardware_concurrency(), LoadAverage().c_str());

  // Detections-only first, so the peak memory is not the renderer's (and reset before each run).
  std::printf(
      "## Detections-only sessions (GenerateDataset, four_sided, default options; whole session)\n\n");
  std::printf(
      "| frames x cameras | messages | wall s | camera frames / s | log MiB | peak RSS MiB | peak - start "
      "MiB |\n");
  std::printf("|---|---|---|---|---|---|---|\n");
  std::vector<std::pair<int, int>> det_sizes = {{300, 5}, {1000, 5}, {10000, 8}};
  if (quick) det_sizes = {{300, 5}, {1000, 5}, {2000, 8}};
  bool reset_ok = true;
  for (const auto& [frames, cameras] : det_sizes) {
    reset_ok = ResetPeakRss() && reset_ok;
    const DetRow r = BenchDetections(frames, cameras);
    std::printf("| %d x %d | %lld | %.2f | %.0f | %.1f | %.1f | %.1f |\n", r.frames, r.cameras,
                static_cast<long long>(r.messages), r.wall, r.frames * r.cameras / r.wall, r.log_mib,
                r.peak_mib, r.peak_mib - r.start_mib);
    std::fflush(stdout);
  }
  std::printf(
      "\nPeak RSS: VmHWM of the whole process%s; start: VmRSS just before the run (libraries, earlier "
      "runs).\n\n",
      reset_ok ? ", reset before each run" : " (could not be reset: cumulative)");

  std::printf(
      "## Rendering speed, one thread (four_sided, default options: exact area anti-aliasing, noise 2)\n\n");
  std::printf("| image size | images | ms / image (wall) | images / s | ms / image (thread CPU) |\n");
  std::printf("|---|---|---|---|---|\n");
  const int n = quick ? 10 : 60;
  for (bool blur : {false, true}) {
    for (const auto& [w, h] : std::vector<std::pair<int, int>>{{640, 480}, {1280, 960}}) {
      const int images = blur ? std::max(5, n / 3) : (w > 640 ? n / 2 : n);
      const RenderRow r = BenchRender(w, h, blur, images);
      std::printf("| %s | %d | %.1f | %.1f | %.1f |\n", r.what.c_str(), r.images, 1000.0 * r.wall / r.images,
                  r.images / r.wall, 1000.0 * r.cpu / r.images);
      std::fflush(stdout);
    }
  }

  const int frames = quick ? 20 : 60;
  std::printf(
      "\n## Rendered session, %d frames x 5 cameras, 640x480 PNG (GenerateDataset: render, encode, "
      "write)\n\n",
      frames);
  std::printf("| threads | wall s | images / s | process CPU s | speed-up (wall) |\n");
  std::printf("|---|---|---|---|---|\n");
  const SessionRow t1 = BenchSession(frames, 5, 1);
  std::printf("| 1 | %.2f | %.1f | %.2f | 1.00 |\n", t1.wall, frames * 5 / t1.wall, t1.cpu);
  std::fflush(stdout);
  const SessionRow t2 = BenchSession(frames, 5, 2);
  std::printf("| 2 | %.2f | %.1f | %.2f | %.2f |\n", t2.wall, frames * 5 / t2.wall, t2.cpu,
              t1.wall / t2.wall);
  std::printf(
      "\nSpeed-up is bounded by the cores actually free: two busy threads got %.2f CPU-seconds per second "
      "just "
      "after.\n",
      AvailableCores());
  return 0;
}
