// mcmt's definitions of four OpenCV functions in OpenCV's place (opencv_overrides.cc): the same results
// bit for bit, cheaper, for the calls cv::aruco::detectMarkers makes.
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>

namespace mcmt {

// Does nothing. MarkerDetector calls it so that every program that detects markers links
// opencv_overrides.cc from the mcmt_detector archive: nothing else names that file's symbols, and the
// linker takes an archive member only for a symbol something references.
void LinkOpenCvOverrides();

// *dst (8-bit, src's size, not src) = `below` where src - mean <= at, else `above`, the mean exactly
// cv::blur(src, mean, Size(k, k))'s (BORDER_REPLICATE; for a view, its whole image's pixels beyond it
// count), computed from window sums without the mean image. False (nothing written) unless src is
// 8-bit with k odd, 3 to 15, and |at| <= 256.
bool ThresholdBelowBlur(const cv::Mat& src, int k, int at, uint8_t below, uint8_t above, cv::Mat* dst);

}  // namespace mcmt
