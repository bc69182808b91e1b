// searchavx: thread CPU time of cv::adaptiveThreshold (mcmt's override) on a 640 x 480 blurred-noise image,
// windows 5 and 15 px, best of 7 x 200 calls. Not product. Built by hand against a worktree's build W/build:
// g++ -O2 -std=c++17 -IW -isystem /usr/include/opencv4 -isystem /usr/include/eigen3 THIS.cc
//     W/build/detector/libmcmt_detector.a W/build/core/libmcmt_core.a -lopencv_imgproc -lopencv_core -ldl
//     -rdynamic
// Run as is (AVX2 where the CPU has it) and with MCMT_NO_AVX2=1 (SSE2).
#include <time.h>

#include <cstdio>
#include <opencv2/imgproc.hpp>

#include "detector/opencv_overrides.h"
static double Cpu() {
  timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}
int main() {
  mcmt::LinkOpenCvOverrides();
  cv::Mat image(480, 640, CV_8U), out;
  cv::randu(image, 0, 256);
  cv::GaussianBlur(image, image, cv::Size(0, 0), 2.0);
  for (int k : {5, 15}) {
    for (int i = 0; i < 20; ++i)
      cv::adaptiveThreshold(image, out, 255, cv::ADAPTIVE_THRESH_MEAN_C, cv::THRESH_BINARY_INV, k, 7);
    double best = 1e9;
    for (int rep = 0; rep < 7; ++rep) {
      const double t0 = Cpu();
      for (int i = 0; i < 200; ++i)
        cv::adaptiveThreshold(image, out, 255, cv::ADAPTIVE_THRESH_MEAN_C, cv::THRESH_BINARY_INV, k, 7);
      best = std::min(best, (Cpu() - t0) / 200 * 1e6);
    }
    std::printf("window %d: %.1f us per 640x480 (best of 7 x 200)\n", k, best);
  }
}
