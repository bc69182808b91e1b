// The marker detector's own candidate search (DetectorOptions::candidate_search "own"): quadrilaterals
// in an 8-bit image, found in binary images whose threshold does not depend on scale.
//
// The image is cut into square tiles; each tile's minimum and maximum over it and its 8 neighbours give
// the threshold, a level between them (AprilTag's scheme; one binary image per level). Pixels of tiles
// whose contrast is below `min_contrast` are not dark. Only boxes of tiles with contrast are thresholded
// and searched (QuadFinder); the outer boundaries of the dark connected components are followed there
// (cv::findContours); a boundary whose points all lie near the polygon of its
// four extreme points becomes a quad, each side a line fitted to the boundary points between two
// corners (a sixth of them left out at each end), the corners the intersections of adjacent lines.
#pragma once

#include <array>
#include <cstdint>
#include <opencv2/core.hpp>
#include <utility>
#include <vector>

namespace mcmt {

struct QuadSearch {
  int tile_px = 4;                     // threshold tile side, pixels
  int min_contrast = 30;               // grey levels: tiles (with their neighbours) below this are skipped
  std::vector<double> levels = {0.5};  // one binary image per level: dark below min + level (max - min)
  double min_perimeter = 40;           // boundary length range of a quad, pixels
  double max_perimeter = 1e9;
  double max_deviation_rate = 0.05;  // boundary points' distance to the quad, relative to the perimeter
  double min_side_rate = 0.05;       // shortest side, relative to the perimeter
  int min_distance_to_border = 1;    // corners at least this far inside the image, pixels
};

// Each t x t tile's minimum and maximum over it and its 8 neighbours (within the image), row-major,
// (cols + t - 1) / t tiles wide: the ranges the threshold levels lie in.
void TileRanges(const cv::Mat& gray, int t, std::vector<uint8_t>* lo, std::vector<uint8_t>* hi);

// A quad's corners in OpenCV's candidate order: corners 1 and 3 swapped where (c1 - c0) x (c2 - c0) < 0
// in image coordinates (clockwise on screen), computed as the aruco module does (each difference in the
// points' own type, the product in double): FindQuads' quads and mcmt's own detectMarkers.
template <typename Point>
void MakeClockwise(std::array<Point, 4>* q) {
  const double dx1 = (*q)[1].x - (*q)[0].x, dy1 = (*q)[1].y - (*q)[0].y;
  const double dx2 = (*q)[2].x - (*q)[0].x, dy2 = (*q)[2].y - (*q)[0].y;
  if (dx1 * dy2 - dy1 * dx2 < 0.0) std::swap((*q)[1], (*q)[3]);
}

// Quads of dark-bordered shapes in `gray` (8-bit, one channel), from every level's binary image, corners
// in image pixels (pixel centres at integer coordinates), ordered with (c1 - c0) x (c2 - c0) >= 0 in
// image coordinates (clockwise on screen, OpenCV's candidate order).
std::vector<std::array<cv::Point2d, 4>> FindQuads(const cv::Mat& gray, const QuadSearch& search);

// The same search one level at a time, the tiles' ranges computed once: a caller that reads each
// level's quads covers the markers it found (Cover), and later levels look only at the tiles left.
class QuadFinder {
 public:
  QuadFinder(const cv::Mat& gray, const QuadSearch& search);
  // Quads of the binary image at `level` (search.levels are not used), outside covered tiles.
  std::vector<std::array<cv::Point2d, 4>> Find(double level);
  // Quads of the binary image dark below the mean of a `window_px` square less `offset` grey levels
  // (OpenCV's adaptive threshold), outside covered tiles and tiles below min_contrast.
  std::vector<std::array<cv::Point2d, 4>> FindBelowMean(int window_px, double offset);
  // The tiles the quad touches (its bounding box grown by `grow_px`) are searched no more.
  void Cover(const std::array<cv::Point2d, 4>& quad, double grow_px);

 private:
  cv::Mat gray_;
  QuadSearch search_;
  int tiles_wide_ = 0, tiles_high_ = 0;
  std::vector<uint8_t> lo_, hi_;  // per tile: range of its 3 x 3 tiles; covered tiles: lo_ 255, hi_ 0
  // Tile i (row-major) is searched: its range reaches min_contrast (a covered tile's never does).
  bool HasContrast(int i) const { return hi_[i] - lo_[i] >= search_.min_contrast; }
  std::vector<cv::Rect> regions_;  // tiles: disjoint boxes of whole components of tiles with contrast
  cv::Mat binary_, mean_;          // written in the regions searched only
  // Quads of the binary image (dark below `level` of the range, or with window_px below the mean less
  // `offset`) in each region's box of uncovered tiles with contrast.
  std::vector<std::array<cv::Point2d, 4>> Quads(double level, int window_px, double offset);
  cv::Rect Uncovered(const cv::Rect& region) const;  // the box of its uncovered tiles with contrast
  // binary_ over `px` (the pixels of `tiles`): dark pixels 255 in uncovered tiles with contrast.
  void Threshold(const cv::Rect& tiles, const cv::Rect& px, double level, int window_px, double offset);
  std::vector<std::vector<cv::Point>> contours_;
  std::vector<cv::Vec4i> hierarchy_;
};

}  // namespace mcmt
