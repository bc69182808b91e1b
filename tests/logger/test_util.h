// Helpers for the logger tests: temporary folders, child processes, deterministic messages.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "core/log_writer.h"
#include "mcmt/detections_t.hpp"
#include "mcmt/object_pose_t.hpp"
#include "tests/support/process.h"
#include "tests/support/temp_dir.h"
#include "tests/support/udpm.h"

namespace mcmt_test {

inline std::string MakeTempDir(const std::string& tag) { return mcmt::test::MakeTempDir("logger_" + tag); }

inline void RemoveTree(const std::string& dir) {
  if (dir.find("/mcmt_logger_") == std::string::npos) return;
  std::error_code ec;
  std::filesystem::remove_all(dir, ec);
}

inline bool FileExists(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0;
}

inline long long FileSize(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0 ? static_cast<long long>(st.st_size) : -1;
}

using mcmt::test::ReadText;

inline void WriteText(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

using mcmt::test::Bin;

using mcmt::test::UdpmUrl;

using mcmt::test::Child;  // stdout and stderr into files (tests/support)

// Runs a program to completion; returns its exit code (-1 on timeout).
inline int RunProgram(const std::vector<std::string>& argv, std::string* out = nullptr,
                      std::string* err = nullptr, double timeout_s = 60) {
  char out_path[] = "/tmp/mcmt_logger_runout_XXXXXX";
  char err_path[] = "/tmp/mcmt_logger_runerr_XXXXXX";
  int fo = mkstemp(out_path), fe = mkstemp(err_path);
  close(fo);
  close(fe);
  int code;
  {
    Child c(argv, out_path, err_path);
    code = c.Wait(timeout_s);
  }
  if (out) *out = ReadText(out_path);
  if (err) *err = ReadText(err_path);
  unlink(out_path);
  unlink(err_path);
  return code;
}

inline bool WaitFor(const std::string& path, double timeout_s) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (!FileExists(path)) {
    if (std::chrono::steady_clock::now() > end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return true;
}

constexpr char kProbeChannel[] = "MCMT_PROBE";

// Events in `file` other than probes (a cut-short last event is not counted).
inline size_t CountNonProbeEvents(const std::string& file) {
  size_t n = 0;
  if (!FileExists(file)) return 0;
  mcmt::EventLogReader reader(file);
  mcmt::LogEvent e;
  while (reader.Next(&e))
    if (e.channel != kProbeChannel) ++n;
  return n;
}

// lcm-logger has no readiness signal and flushes only when a message arrives: publish probes on `port`
// until `file` holds at least `count` non-probe events (count 0: until it holds anything). Up to 20 s.
inline bool ProbeUntilRecorded(int port, const std::string& file, size_t count = 0) {
  lcm::LCM lcm(UdpmUrl(port));
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  for (;;) {
    if (count == 0 ? FileSize(file) > 0 : CountNonProbeEvents(file) >= count) return true;
    if (std::chrono::steady_clock::now() > until) return false;
    lcm.publish(kProbeChannel, "p", 1);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
}

// lcm-logger (LCM 1.3.1) subscribes with LCM's default queue of 30 messages and has no option to raise
// it: a message that arrives while 30 wait for its main loop is dropped without a word (seen on a loaded
// machine: 105 of 123 recorded, no UDP receive-buffer error). So `messages` (anything with .channel and
// .data) go to it in batches of kLcmLoggerBatch, each waited for in `file` before the next: whatever the
// scheduling, fewer than 30 wait at any time. False if a batch is not recorded within ProbeUntilRecorded's
// time.
constexpr size_t kLcmLoggerBatch = 16;
template <typename Messages>
bool PublishIntoLcmLogger(int port, const std::string& file, const Messages& messages) {
  lcm::LCM lcm(UdpmUrl(port));
  if (!lcm.good() || !ProbeUntilRecorded(port, file)) return false;
  for (size_t i = 0; i < messages.size(); ++i) {
    lcm.publish(messages[i].channel, messages[i].data.data(), static_cast<unsigned>(messages[i].data.size()));
    const bool batch_end = (i + 1) % kLcmLoggerBatch == 0 || i + 1 == messages.size();
    if (batch_end && !ProbeUntilRecorded(port, file, i + 1)) return false;
  }
  return true;
}

// Deterministic detections of one camera frame.
inline mcmt::detections_t MakeDetections(const std::string& camera, int64_t seq, int num_markers) {
  mcmt::detections_t d;
  d.utime = 1700000000000000LL + seq * 16667;
  d.seq = seq;
  d.camera = camera;
  d.dictionary = "DICT_6X6_250";
  d.camera_model.width = 640;
  d.camera_model.height = 480;
  d.camera_model.fx = 500;
  d.camera_model.fy = 501;
  d.camera_model.cx = 319.5;
  d.camera_model.cy = 239.5;
  d.camera_model.distortion_model = "radtan";
  d.camera_model.distortion = {0.01, -0.02, 0.001, 0.002, 0.003};
  d.camera_model.num_distortion = 5;
  for (int i = 0; i < num_markers; ++i) {
    mcmt::marker_t m;
    m.id = (i * 7 + static_cast<int>(seq)) % 50;
    for (int k = 0; k < 4; ++k) {
      m.corners[k][0] = 100.0 + i * 40 + k * 10.123456789012345 + seq * 0.1 / 3.0;
      m.corners[k][1] = 200.0 - k * 9.87654321 + i * 1e-9 + seq / 7.0;
    }
    d.markers.push_back(m);
  }
  d.num_markers = num_markers;
  d.detection_ms = 1.25 + seq * 0.001;
  return d;
}

inline mcmt::object_pose_t MakePose(int64_t seq, int8_t status) {
  mcmt::object_pose_t p;
  p.utime = 1700000000000000LL + seq * 16667;
  p.seq = seq;
  p.object = "cube";
  p.rig_from_object.position[0] = 0.1 * seq;
  p.rig_from_object.position[1] = -0.2 + seq / 3.0;
  p.rig_from_object.position[2] = 1.5;
  const double a = 0.01 * seq;  // rotation about z
  p.rig_from_object.orientation[0] = std::cos(a / 2);
  p.rig_from_object.orientation[1] = 0;
  p.rig_from_object.orientation[2] = 0;
  p.rig_from_object.orientation[3] = std::sin(a / 2);
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) p.covariance[r][c] = r == c ? 1e-6 : 0.0;
  p.rms_px = 0.3 + seq * 0.01;
  p.num_cameras = 2;
  p.cameras = {"cam0", "cam1"};
  p.num_markers = 3;
  p.markers = {0, 1, 2};
  p.num_rejected = 0;
  p.status = status;
  p.latency_ms = 2.0;
  return p;
}

}  // namespace mcmt_test
