// Tracking speed against resolution, as the paper's Table 5 measures it: detection + object pose per frame,
// on one thread and on all threads, at 320x240, 640x480, 1280x960 and 1920x1440. Images rendered by
// mcmt_sim (the paper's rig: 5 cameras on a 1 m circle, the four-sided object with 4 cm markers); the map is
// the ground truth, so only the per-frame work is timed: MarkerDetector::Detect on every camera's image
// (accurate default mode, and the fast mode that searches near the previous frame's markers), then
// PoseEstimator::Solve from the previous pose. Wall time (run it on an idle machine).
//   bench_tracking_speed [--quick] [--frames N]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <future>
#include <opencv2/core.hpp>
#include <string>
#include <thread>
#include <vector>

#include "detector/detector.h"
#include "sim/eval.h"
#include "sim/sim.h"
#include "tracker/tracker.h"

using namespace mcmt;

namespace {

using Clock = std::chrono::steady_clock;

struct Session {
  std::vector<sim::SimCamera> cameras;
  std::vector<sim::SimFrame> frames;
  std::vector<std::vector<cv::Mat>> images;  // [frame][camera]
  RigMap map;                                // the ground truth in cam0's and marker 0's frames
  std::vector<TrajectoryRow> truth;          // rig_from_object per frame in those frames
  double marker_px = 0;                      // mean apparent side of the fully visible markers, pixels
};

Session Render(const sim::SimObject& object, int width, int height, int frames) {
  Session s;
  sim::RigOptions ro;
  ro.width = width;
  ro.height = height;
  s.cameras = sim::MakeRig(ro);
  sim::TrajectoryOptions to;
  to.frames = frames;
  s.frames = sim::MakeTrajectory(to);
  sim::Renderer renderer(object, "DICT_6X6_250");
  int visible = 0;
  for (const sim::SimFrame& f : s.frames) {
    for (const sim::SimCamera& c : s.cameras)
      for (const sim::MarkerView& v : sim::ProjectMarkers(c, object, f.rig_from_object))
        if (v.fully_visible) {
          s.marker_px += v.size_px;
          ++visible;
        }
    std::vector<cv::Mat> row;
    for (size_t c = 0; c < s.cameras.size(); ++c)
      row.push_back(renderer.Render(s.cameras[c], static_cast<int>(c), f.seq, f.rig_from_object));
    s.images.push_back(std::move(row));
  }
  if (visible > 0) s.marker_px /= visible;
  sim::GroundTruth truth;
  truth.cameras = s.cameras;
  truth.markers = object.markers;
  truth.frames = s.frames;
  s.map = sim::MapFromGroundTruth(truth, 0, 0, &s.truth);
  return s;
}

struct Result {
  double ms_per_frame = 0;    // wall time per rig frame (all cameras detected + pose)
  double detect_ms = 0;       // mean detection time per camera image (one thread) / per frame (parallel)
  double pose_ms = 0;         // mean pose solve time per frame
  double tracked = 0;         // fraction of frames with a pose
  double translation_mm = 0;  // mean translation error against ground truth
};

// parallel: every camera detected in its own task (and OpenCV's own threads on); else one thread.
Result Track(const Session& s, const sim::SimObject& object, bool fast, bool parallel) {
  cv::setNumThreads(parallel ? -1 : 1);
  MarkerConfig markers;
  markers.dictionary = "DICT_6X6_250";
  markers.size = 0.04;
  for (const auto& m : object.markers) markers.ids.push_back(m.id);
  DetectorOptions options;
  options.fast = fast;
  std::vector<std::unique_ptr<MarkerDetector>> detectors;
  for (const sim::SimCamera& c : s.cameras) {
    detectors.push_back(std::make_unique<MarkerDetector>(markers, options));
    detectors.back()->SetCamera(c.model);
  }
  const PoseEstimator estimator(s.map);
  Result r;
  double detect_s = 0, pose_s = 0, error_sum = 0;
  int tracked = 0;
  Rigid3 previous;
  bool have_previous = false;
  const auto t0 = Clock::now();
  for (size_t f = 0; f < s.frames.size(); ++f) {
    std::vector<detections_t> views(s.cameras.size());
    const auto d0 = Clock::now();
    auto detect = [&](size_t c) {
      views[c].utime = s.frames[f].utime;
      views[c].seq = s.frames[f].seq;
      views[c].camera = s.cameras[c].name;
      views[c].markers = detectors[c]->Detect(s.images[f][c]);
      views[c].num_markers = static_cast<int32_t>(views[c].markers.size());
    };
    if (parallel) {
      std::vector<std::future<void>> tasks;
      for (size_t c = 0; c < s.cameras.size(); ++c)
        tasks.push_back(std::async(std::launch::async, detect, c));
      for (auto& t : tasks) t.get();
    } else {
      for (size_t c = 0; c < s.cameras.size(); ++c) detect(c);
    }
    const auto p0 = Clock::now();
    const PoseSolution sol =
        estimator.Solve(ObservationsFromViews(views), have_previous ? &previous : nullptr);
    const auto p1 = Clock::now();
    detect_s += std::chrono::duration<double>(p0 - d0).count();
    pose_s += std::chrono::duration<double>(p1 - p0).count();
    have_previous = sol.ok();
    if (sol.ok()) {
      previous = sol.rig_from_object;
      ++tracked;
      // The map is the ground truth in the estimator's frames: poses compare directly (translation of the
      // object frame's origin, marker 0's centre).
      error_sum +=
          1000 * (sol.rig_from_object.translation() - s.truth[f].rig_from_object.translation()).norm();
    }
  }
  const double total = std::chrono::duration<double>(Clock::now() - t0).count();
  const double n = static_cast<double>(s.frames.size());
  r.ms_per_frame = 1000 * total / n;
  r.detect_ms = 1000 * detect_s / (parallel ? n : n * s.cameras.size());
  r.pose_ms = 1000 * pose_s / n;
  r.tracked = tracked / n;
  r.translation_mm = tracked ? error_sum / tracked : 0;
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  int frames = 30;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--quick")) {
      frames = 8;
    } else if (!std::strcmp(argv[i], "--frames") && i + 1 < argc) {
      frames = std::max(2, std::atoi(argv[++i]));
    } else {
      std::fprintf(stderr, "usage: bench_tracking_speed [--quick] [--frames N]\n");
      return 2;
    }
  }
  sim::ObjectOptions oo;  // the paper's four-sided object, 4 cm markers
  const sim::SimObject object = sim::MakeObject(oo);
  const int cameras = 5;
  const unsigned threads = std::max(1u, std::thread::hardware_concurrency());
  std::printf("## Tracking speed against resolution (the paper's Table 5)\n\n");
  std::printf(
      "Detection of every camera's image + the object's pose, per rig frame of %d cameras (%d frames per "
      "resolution, four-sided object, 4 cm markers, cameras 1 m away; wall time). One thread: "
      "cv::setNumThreads(1), cameras one after the other. All threads (%u): cameras detected in parallel. "
      "Accurate = the default detector; fast = search near the previous frame's markers (detector.fast). "
      "The paper: one thread, detection + pose, frames per second. At 320x240 this rig's 4 cm markers are "
      "about 7 px "
      "wide, barely one pixel per cell: they cannot be decoded, so nothing is tracked there (the time is the "
      "search alone).\n\n",
      cameras, frames, threads);
  std::printf(
      "| resolution | marker side px | mode | detect ms / image (1 thread) | pose ms | one thread: frames/s "
      "(images/s) | all "
      "threads: frames/s (images/s) | tracked | translation error mm | paper frames/s |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  const struct {
    int w, h, paper;
  } sizes[] = {{320, 240, 234}, {640, 480, 128}, {1280, 960, 68}, {1920, 1440, 38}};
  for (const auto& size : sizes) {
    const Session s = Render(object, size.w, size.h, frames);
    for (const bool fast : {false, true}) {
      const Result one = Track(s, object, fast, false);
      const Result all = Track(s, object, fast, true);
      std::printf("| %dx%d | %.0f | %s | %.2f | %.3f | %.1f (%.0f) | %.1f (%.0f) | %.0f %% | %.3f | %d |\n",
                  size.w, size.h, s.marker_px, fast ? "fast" : "accurate", one.detect_ms, one.pose_ms,
                  1000 / one.ms_per_frame, cameras * 1000 / one.ms_per_frame, 1000 / all.ms_per_frame,
                  cameras * 1000 / all.ms_per_frame, 100 * one.tracked, one.translation_mm, size.paper);
      std::fflush(stdout);
    }
  }
  return 0;
}
