// Thread CPU time of the search's thresholds + contours: cv::Mat images + findContours (conversion pass)
// against AdaptiveThresholdPairFramed + FramedContours, alternated, on caliscope frames.
#include <time.h>

#include <algorithm>
#include <cstdio>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <vector>

#include "detector/opencv_overrides.h"

static double Now() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

int main(int argc, char** argv) {
  mcmt::LinkOpenCvOverrides();
  cv::setNumThreads(1);
  cv::VideoCapture video(argv[1]);
  std::vector<cv::Mat> frames;
  cv::Mat frame, gray;
  while (frames.size() < 20 && video.read(frame)) {
    cv::cvtColor(frame, gray, cv::COLOR_BGR2GRAY);
    if (argc > 2) cv::resize(gray, gray, cv::Size(640, 480));
    frames.push_back(gray.clone());
  }
  std::printf("%zu frames %dx%d\n", frames.size(), frames[0].cols, frames[0].rows);
  const double rate = 0.03;
  const size_t floor = static_cast<size_t>(rate * std::max(frames[0].cols, frames[0].rows));
  std::vector<std::vector<cv::Point>> contours;
  cv::Mat a, b;
  mcmt::FramedBinary fa, fb;
  size_t check_old = 0, check_new = 0;
  std::vector<double> t_old, t_new;
  for (int round = 0; round < 12; ++round) {
    double t0 = Now();
    for (int rep = 0; rep < 10; ++rep)
      for (const cv::Mat& f : frames) {
        mcmt::AdaptiveThresholdPair(f, 5, 7.0, &a, &b);
        const mcmt::ArucoContourFloor floor_guard(rate, 0);
        cv::findContours(a, contours, cv::RETR_LIST, cv::CHAIN_APPROX_NONE);
        check_old += contours.size();
        cv::findContours(b, contours, cv::RETR_LIST, cv::CHAIN_APPROX_NONE);
        check_old += contours.size();
      }
    double t1 = Now();
    for (int rep = 0; rep < 10; ++rep)
      for (const cv::Mat& f : frames) {
        mcmt::AdaptiveThresholdPairFramed(f, 5, 7.0, &fa, &fb);
        mcmt::FramedContours(&fa, floor, &contours);
        check_new += contours.size();
        mcmt::FramedContours(&fb, floor, &contours);
        check_new += contours.size();
      }
    double t2 = Now();
    t_old.push_back((t1 - t0) * 1e3 / (10 * frames.size()));
    t_new.push_back((t2 - t1) * 1e3 / (10 * frames.size()));
  }
  std::sort(t_old.begin(), t_old.end());
  std::sort(t_new.begin(), t_new.end());
  std::printf(
      "ms per frame, median of 12 rounds: Mat+findContours %.4f (min %.4f)  framed %.4f (min %.4f)  "
      "contours %zu / %zu\n",
      t_old[6], t_old[0], t_new[6], t_new[0], check_old, check_new);
}
