// Thread CPU time of AdaptiveThresholdPair (5 and 15 px) alone, on caliscope frames at 640 x 480.
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
  cv::VideoCapture video(argv[1]);
  std::vector<cv::Mat> frames;
  cv::Mat frame, gray;
  while (frames.size() < 20 && video.read(frame)) {
    cv::cvtColor(frame, gray, cv::COLOR_BGR2GRAY);
    cv::resize(gray, gray, cv::Size(640, 480));
    frames.push_back(gray.clone());
  }
  cv::Mat a, b;
  std::vector<double> t;
  size_t check = 0;
  for (int round = 0; round < 15; ++round) {
    double t0 = Now();
    for (int rep = 0; rep < 10; ++rep)
      for (const cv::Mat& f : frames) {
        mcmt::AdaptiveThresholdPair(f, 5, 7.0, &a, &b);
        check += a.at<uint8_t>(100, 100) + b.at<uint8_t>(200, 200);
      }
    t.push_back((Now() - t0) * 1e3 / (10 * frames.size()));
  }
  std::sort(t.begin(), t.end());
  std::printf("AdaptiveThresholdPair ms per frame, median of 15: %.4f (min %.4f) %zu\n", t[7], t[0], check);
}
