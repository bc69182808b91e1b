// mcmt's definitions of OpenCV functions in OpenCV's place (opencv_overrides.cc): the same results
// bit for bit, cheaper, for the calls cv::aruco::detectMarkers makes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <opencv2/core.hpp>
#include <vector>

namespace mcmt {

// Does nothing. MarkerDetector calls it so that every program that detects markers links
// opencv_overrides.cc from the mcmt_detector archive: nothing else names that file's symbols, and the
// linker takes an archive member only for a symbol something references.
void LinkOpenCvOverrides();

// The zero bytes among the 4 at p, by one word's arithmetic (the aruco module's cells are 4 px rows: its
// countNonZero calls and mcmt's own detectMarkers count them so). Per byte b, (b & 0x7f) + 0x7f has its top
// bit set unless b & 0x7f is 0 (no carry leaves the byte), so with b's own top bit or-ed in, the top bit is
// clear exactly where b is 0.
inline int ZeroBytesOf4(const uint8_t* p) {
  uint32_t w;
  std::memcpy(&w, p, 4);
  const uint32_t zero_tops = ~(((w & 0x7f7f7f7fu) + 0x7f7f7f7fu) | w | 0x7f7f7f7fu);
  return static_cast<int>(((zero_tops >> 7) * 0x01010101u) >> 24);
}

// *dst (8-bit, src's size, not src) = `below` where src - mean <= at, else `above`, the mean exactly
// cv::blur(src, mean, Size(k, k))'s (BORDER_REPLICATE; for a view, its whole image's pixels beyond it
// count), computed from window sums without the mean image. False (nothing written) unless src is
// 8-bit with k odd, 3 to 15, and |at| <= 256.
bool ThresholdBelowBlur(const cv::Mat& src, int k, int at, uint8_t below, uint8_t above, cv::Mat* dst);

// *small and *large = cv::adaptiveThreshold(src, 255, ADAPTIVE_THRESH_MEAN_C, THRESH_BINARY_INV, w, delta)
// for w = k and w = 3 k, bit for bit (test_detector_unit, CandidateSearch.AdaptiveThresholdPairIsOpenCVs), in
// one pass: the 3k window's sums from the k window's (detectMarkers' 5 and 15 px windows). False (nothing
// written) unless src is 8-bit with k 3 or 5. The three images must be distinct.
bool AdaptiveThresholdPair(const cv::Mat& src, int k, double delta, cv::Mat* small, cv::Mat* large);

// A 0/1 image framed by zeros (a row above and below, a column left and right), as mcmt's findContours
// follows borders in it: row y (0 .. rows - 1) of the image at Row(y), cols bytes; 32 zero bytes after the
// bottom row for the scan's 32-pixel reads.
struct FramedBinary {
  int cols = 0, rows = 0;
  // (rows + 2) x (cols + 2), then 32; capacity bytes allocated, not cleared (every byte used is written).
  std::unique_ptr<int8_t[]> bytes;
  size_t capacity = 0;
  int8_t* Row(int y) { return bytes.get() + static_cast<std::ptrdiff_t>(y + 1) * (cols + 2) + 1; }
};

// AdaptiveThresholdPair with its images written as FramedBinary's: 1 where AdaptiveThresholdPair's is 255,
// 0 where it is 0, for FramedContours without a conversion pass. False (nothing written) where
// AdaptiveThresholdPair would be false, or where small is large.
bool AdaptiveThresholdPairFramed(const cv::Mat& src, int k, double delta, FramedBinary* small,
                                 FramedBinary* large);

// *contours = cv::findContours(the image, RETR_LIST, CHAIN_APPROX_NONE) (mcmt's, the same as OpenCV's bit
// for bit: the same borders in the same order) less the borders of fewer than min_points points (0: none
// left out; as under ArucoContourFloor). The image is marked as the border follower goes: read it once.
void FramedContours(FramedBinary* image, size_t min_points, std::vector<std::vector<cv::Point>>* contours);

// cv::aruco::detectMarkers (OpenCV 4.6, _findMarkerContours) drops every border cv::findContours returns
// with fewer points than (unsigned)(minMarkerPerimeterRate * max(cols, rows)) of its binary image, or than
// 4 minSideLengthCanonicalImg where it passes that (ArUco3), before looking at it. While one lives, mcmt's
// findContours (RETR_LIST, in this thread) leaves out the borders shorter than the smaller of the two: the
// aruco module sees the same candidates in the same order, without a vector allocated, copied and freed
// for each speck of the binary image (26,194 borders in bench_detector's 10 accurate frames, a few dozen
// of them long enough; sideray). Other callers of findContours are not affected; neither are OpenCV's
// worker threads where it runs detectMarkers' windows in parallel (they see no floor).
class ArucoContourFloor {
 public:
  ArucoContourFloor(double min_perimeter_rate, int min_side_canonical);
  ~ArucoContourFloor();
  ArucoContourFloor(const ArucoContourFloor&) = delete;
  ArucoContourFloor& operator=(const ArucoContourFloor&) = delete;

 private:
  double previous_rate_;
  int previous_side_;
};

}  // namespace mcmt
