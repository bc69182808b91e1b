// Sustained recording rate of the real mcmt-logger process: 8 simulated cameras publish detections_t at
// 60 fps over LCM udpm on loopback (optionally plus one image-sized message per camera frame); the log is
// read back and every message counted against what was sent. Prints markdown tables.
//   bench_logger [--quick] [--seconds S]
#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "core/lcm_util.h"
#include "core/log_writer.h"
#include "logger/session_logger.h"

using namespace mcmt;
using Clock = std::chrono::steady_clock;

namespace {

detections_t Detections(const std::string& camera, int64_t seq, int markers) {
  detections_t d;
  d.utime = 1700000000000000LL + seq * 16667;
  d.seq = seq;
  d.camera = camera;
  d.dictionary = "DICT_6X6_250";
  d.camera_model.width = 1280;
  d.camera_model.height = 720;
  d.camera_model.fx = d.camera_model.fy = 900;
  d.camera_model.cx = 640;
  d.camera_model.cy = 360;
  d.camera_model.distortion_model = "radtan";
  d.camera_model.distortion = {0.1, -0.2, 0.001, 0.002, 0.05};
  d.camera_model.num_distortion = 5;
  for (int i = 0; i < markers; ++i) {
    marker_t m;
    m.id = i;
    for (int k = 0; k < 4; ++k) {
      m.corners[k][0] = 100.0 + 37.1 * i + k + 0.01 * static_cast<double>(seq);
      m.corners[k][1] = 200.0 + 11.3 * k;
    }
    d.markers.push_back(m);
  }
  d.num_markers = markers;
  d.detection_ms = 3.0;
  return d;
}

struct Child {
  pid_t pid = -1;
  rusage usage{};
  int status = 0;
};

Child StartLogger(const std::string& out, const std::string& url, const std::string& recv_buf_mb) {
  Child c;
  c.pid = fork();
  if (c.pid == 0) {
    int devnull = open("/dev/null", O_WRONLY);
    dup2(devnull, 1);
    dup2(devnull, 2);
    const std::string bin = std::string(MCMT_BIN_DIR) + "/mcmt-logger";
    execl(bin.c_str(), bin.c_str(), "--out", out.c_str(), "--lcm-url", url.c_str(), "--status-seconds", "0",
          "--recv-buf-mb", recv_buf_mb.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  return c;
}

bool Exists(const std::string& p) {
  struct stat st;
  return stat(p.c_str(), &st) == 0;
}

struct Result {
  std::string name;
  double seconds = 0;
  long long sent = 0, recorded = 0;
  double mb = 0;
  double cpu_percent = 0;
  double max_rss_mb = 0;
  long long missing_seq = 0;
};

// cameras x fps for `seconds`; image_bytes > 0 adds one such message per camera frame. fps <= 0: no pacing.
Result RunScenario(const std::string& name, const std::string& dir, int port, int cameras, double fps,
                   int image_bytes, double seconds, long long max_frames,
                   const std::string& recv_buf_mb = "16") {
  Result r;
  r.name = name;
  const std::string url = "udpm://239.255.76.67:" + std::to_string(port) + "?ttl=0";
  const std::string log = dir + "/" + std::to_string(port) + ".lcmlog";
  Child logger = StartLogger(log, url, recv_buf_mb);
  const std::string sidecar = SidecarPath(log);
  for (int i = 0; i < 1000 && !Exists(sidecar); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  lcm::LCM lcm(url);
  std::vector<std::vector<uint8_t>> payloads;
  std::vector<std::string> det_channels, image_channels;
  for (int c = 0; c < cameras; ++c) {
    det_channels.push_back(DetectionsChannel("cam" + std::to_string(c)));
    image_channels.push_back(ImageChannel("cam" + std::to_string(c)));
  }
  std::vector<uint8_t> image(static_cast<size_t>(image_bytes));
  for (size_t i = 0; i < image.size(); ++i) image[i] = static_cast<uint8_t>(i * 131);
  const auto start = Clock::now();
  long long frames = 0;
  for (;; ++frames) {
    const auto tick = start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(
                                  fps > 0 ? static_cast<double>(frames) / fps : 0.0));
    if (fps > 0) {
      if (tick - start >= std::chrono::duration<double>(seconds)) break;
      std::this_thread::sleep_until(tick);
    } else if (frames >= max_frames) {
      break;
    }
    for (int c = 0; c < cameras; ++c) {
      const std::vector<uint8_t> d = Encode(Detections("cam" + std::to_string(c), frames, 12));
      lcm.publish(det_channels[c], d.data(), static_cast<unsigned>(d.size()));
      ++r.sent;
      if (image_bytes > 0) {
        image[0] = static_cast<uint8_t>(frames);
        lcm.publish(image_channels[c], image.data(), static_cast<unsigned>(image.size()));
        ++r.sent;
      }
    }
  }
  r.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  std::this_thread::sleep_for(std::chrono::milliseconds(700));  // let the logger drain
  kill(logger.pid, SIGINT);
  wait4(logger.pid, &logger.status, 0, &logger.usage);
  const double cpu =
      static_cast<double>(logger.usage.ru_utime.tv_sec + logger.usage.ru_stime.tv_sec) +
      1e-6 * static_cast<double>(logger.usage.ru_utime.tv_usec + logger.usage.ru_stime.tv_usec);
  r.cpu_percent = 100.0 * cpu / r.seconds;  // the logger's CPU over the publishing time (+ start/drain)
  r.max_rss_mb = static_cast<double>(logger.usage.ru_maxrss) / 1024.0;
  std::map<std::string, int64_t> last_seq;
  for (const LogEvent& e : ReadEventLog(log)) {
    ++r.recorded;
    if (e.channel.rfind(kDetectionsChannelPrefix, 0) == 0) {
      detections_t d;
      if (Decode(e.data.data(), e.data.size(), &d)) {
        auto it = last_seq.find(d.camera);
        if (it != last_seq.end() && d.seq > it->second + 1) r.missing_seq += d.seq - it->second - 1;
        last_seq[d.camera] = d.seq;
      }
    }
  }
  struct stat st;
  stat(log.c_str(), &st);
  r.mb = static_cast<double>(st.st_size) / 1e6;
  unlink(log.c_str());
  unlink(sidecar.c_str());
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  double seconds = 10;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--quick"))
      seconds = 3;
    else if (!std::strcmp(argv[i], "--seconds") && i + 1 < argc)
      seconds = std::atof(argv[++i]);
    else {
      std::fprintf(stderr, "usage: bench_logger [--quick] [--seconds S]\n");
      return 2;
    }
  }
  // udpm ports base..base+4 (MCMT_BENCH_PORT: bench/run --port-base).
  const int base = std::getenv("MCMT_BENCH_PORT") ? std::atoi(std::getenv("MCMT_BENCH_PORT")) : 7770;
  char dir_template[] = "/tmp/mcmt_bench_logger_XXXXXX";
  const std::string dir = mkdtemp(dir_template);
  std::vector<Result> results;
  results.push_back(
      RunScenario("8 cameras x 60 fps, detections (12 markers)", dir, base + 0, 8, 60, 0, seconds, 0));
  results.push_back(RunScenario("8 cameras x 60 fps, detections + 1 image msg (50 kB) per camera frame", dir,
                                base + 1, 8, 60, 50000, seconds, 0));
  results.push_back(
      RunScenario("burst: 8 cameras, unpaced, 2000 frames of detections", dir, base + 2, 8, 0, 0, 0, 2000));
  // The same two heavy loads with the kernel's default socket buffer (--recv-buf-mb 0): why the logger raises
  // it.
  results.push_back(RunScenario("as row 2, --recv-buf-mb 0 (kernel default buffer)", dir, base + 3, 8, 60,
                                50000, seconds, 0, "0"));
  results.push_back(
      RunScenario("as row 3, --recv-buf-mb 0 (kernel default buffer)", dir, base + 4, 8, 0, 0, 0, 2000, "0"));
  rmdir(dir.c_str());

  std::printf(
      "mcmt-logger recording over LCM udpm on loopback (publisher in this process, logger a separate "
      "process, default options: flush + fdatasync every 200 ms, socket receive buffer raised to "
      "min(16 MB, net.core.rmem_max = %lld B)). Lost = sent - recorded; msgs/s and MB/s over the publishing "
      "time; CPU = the logger "
      "process's CPU time over the publishing time.\n\n",
      KernelReceiveBufferMax());
  std::printf(
      "| scenario | seconds | sent | recorded | lost | zero loss | msgs/s | MB/s | log MB | logger CPU %% | "
      "logger max RSS MB |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const Result& r : results) {
    const long long lost = r.sent - r.recorded;
    std::printf(
        "| %s | %.2f | %lld | %lld | %lld | %s | %.0f | %.2f | %.2f | %.1f | %.1f |\n", r.name.c_str(),
        r.seconds, r.sent, r.recorded, lost, lost == 0 && r.missing_seq == 0 ? "yes" : "**NO**",
        static_cast<double>(r.recorded) / r.seconds, r.mb / r.seconds, r.mb, r.cpu_percent, r.max_rss_mb);
  }
  return 0;
}
