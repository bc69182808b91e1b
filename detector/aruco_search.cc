// mcmt's own cv::aruco::detectMarkers (aruco_search.h). OpenCV 4.6's steps as read in its aruco.cpp, written
// anew and checked against the installed library by CandidateSearch.DetectMarkersIsOpenCVs:
// 1. per window size w (min, min + step, ... <= max; even sizes made odd): the binary image of
//    cv::adaptiveThreshold(mean, THRESH_BINARY_INV, w, constant) and its borders (findContours, RETR_LIST,
//    CHAIN_APPROX_NONE); a border is a candidate where its point count lies within the perimeter range,
//    its approxPolyDP (epsilon = count * rate, closed) has 4 points and is convex, its sides are at least
//    count * minCornerDistanceRate long and its corners minDistanceToBorder from the image's edges;
// 2. the corners of each made clockwise (corners 1 and 3 swapped where the cross product is negative);
// 3. candidates whose mean squared corner distance (in any of 4 rotations) is below
//    (min point count * minMarkerDistanceRate)^2 grouped; of each group the one of largest area (the last
//    of equal areas) kept, groups in the order they were first formed (pairs whose centres are too far
//    apart for any pairing of corners to be near are skipped);
// 4. each kept candidate's cells read (getPerspectiveTransform, warpPerspective INTER_NEAREST, a flat
//    inner area read all 0 or all 1, else Otsu's threshold and each cell's majority), its border cells
//    counted and its code identified; markers turned to their rotation, the others rejected as they were.
// Steps 1 and 4 run in cv::parallel_for_, as OpenCV's; the lists are joined in OpenCV's order.
#include "detector/aruco_search.h"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <opencv2/imgproc.hpp>

#include "detector/candidates.h"
#include "detector/opencv_overrides.h"

namespace mcmt {
namespace {

struct Candidate {
  ArucoQuad quad;
  int points = 0;  // its border's point count
};

// Step 1 on one binary image: the borders of `binary` (cv::Mat, 0 and 255) or, where it is null, of
// `framed` (FramedBinary, 0 and 1; marked by the border follower), their candidates appended to *out.
void FindWindowCandidates(const cv::Mat* binary, FramedBinary* framed,
                          const cv::aruco::DetectorParameters& params,
                          std::vector<std::vector<cv::Point>>* contours, std::vector<cv::Point>* approx,
                          std::vector<Candidate>* out) {
  const cv::Size size = binary != nullptr ? binary->size() : cv::Size(framed->cols, framed->rows);
  const int longest = std::max(size.width, size.height);
  const auto min_points = static_cast<unsigned int>(params.minMarkerPerimeterRate * longest);
  const auto max_points = static_cast<unsigned int>(params.maxMarkerPerimeterRate * longest);
  if (binary != nullptr) {
    // The borders shorter than min_points are dropped below anyway: findContours leaves them out.
    const ArucoContourFloor floor(params.minMarkerPerimeterRate, 0);
    cv::findContours(*binary, *contours, cv::RETR_LIST, cv::CHAIN_APPROX_NONE);
  } else {
    FramedContours(framed, min_points, contours);  // the same borders, the same ones left out
  }
  const int border = params.minDistanceToBorder;
  for (const std::vector<cv::Point>& contour : *contours) {
    if (contour.size() < min_points || contour.size() > max_points) continue;
    cv::approxPolyDP(contour, *approx,
                     static_cast<double>(contour.size()) * params.polygonalApproxAccuracyRate, true);
    if (approx->size() != 4 || !cv::isContourConvex(*approx)) continue;
    const std::vector<cv::Point>& a = *approx;
    double shortest_squared = longest * longest;
    for (int j = 0; j < 4; ++j) {
      const double dx = static_cast<double>(a[j].x - a[(j + 1) % 4].x);
      const double dy = static_cast<double>(a[j].y - a[(j + 1) % 4].y);
      shortest_squared = std::min(shortest_squared, dx * dx + dy * dy);
    }
    const double min_side = static_cast<double>(contour.size()) * params.minCornerDistanceRate;
    if (shortest_squared < min_side * min_side) continue;
    bool near_edge = false;
    for (int j = 0; j < 4; ++j)
      near_edge = near_edge || a[j].x < border || a[j].y < border || a[j].x > size.width - 1 - border ||
                  a[j].y > size.height - 1 - border;
    if (near_edge) continue;
    Candidate c;
    for (int j = 0; j < 4; ++j)
      c.quad[j] = cv::Point2f(static_cast<float>(a[j].x), static_cast<float>(a[j].y));
    c.points = static_cast<int>(contour.size());
    out->push_back(c);
  }
}

// Step 3: the kept candidates' indices, in the groups' order.
void KeepLargestOfGroups(const std::vector<Candidate>& in, double min_distance_rate, std::vector<int>* kept) {
  const int n = static_cast<int>(in.size());
  std::vector<int> group_of(in.size(), -1);
  std::vector<std::vector<int>> groups;
  thread_local std::vector<float> sum_x, sum_y;  // of each candidate's corners (integers)
  sum_x.resize(in.size());
  sum_y.resize(in.size());
  for (int i = 0; i < n; ++i) {
    sum_x[i] = in[i].quad[0].x + in[i].quad[1].x + in[i].quad[2].x + in[i].quad[3].x;
    sum_y[i] = in[i].quad[0].y + in[i].quad[1].y + in[i].quad[2].y + in[i].quad[3].y;
  }
  for (int i = 0; i < n; ++i) {
    bool alone = true;
    for (int j = i + 1; j < n; ++j) {
      const double min_distance =
          static_cast<double>(std::min(in[i].points, in[j].points)) * min_distance_rate;
      // The mean squared corner distance is at least the squared distance of the centres, whichever
      // corners are paired: pairs whose centres lie that far apart are not near. Exact: the corners are
      // integers, so are their sums and squares here and in OpenCV's sum (below 2^53), and the quarters
      // and sixteenths of them.
      const double dx = static_cast<double>(sum_x[i]) - sum_x[j],
                   dy = static_cast<double>(sum_y[i]) - sum_y[j];
      if ((dx * dx + dy * dy) / 16. >= min_distance * min_distance) continue;
      for (int first = 0; first < 4; ++first) {
        double squared = 0;
        for (int c = 0; c < 4; ++c) {
          const cv::Point2f& p = in[i].quad[(c + first) % 4];
          const cv::Point2f& q = in[j].quad[c];
          // In float, as OpenCV's (its corners are Point2f), added up in double.
          squared += (p.x - q.x) * (p.x - q.x) + (p.y - q.y) * (p.y - q.y);
        }
        squared /= 4.;
        if (!(squared < min_distance * min_distance)) continue;
        alone = false;
        if (group_of[i] < 0 && group_of[j] < 0) {
          group_of[i] = group_of[j] = static_cast<int>(groups.size());
          groups.push_back({i, j});
        } else if (group_of[i] >= 0 && group_of[j] == -1) {
          group_of[j] = group_of[i];
          groups[group_of[i]].push_back(j);
        } else if (group_of[j] >= 0 && group_of[i] == -1) {
          group_of[i] = group_of[j];
          groups[group_of[j]].push_back(i);
        }
      }
    }
    if (alone && group_of[i] < 0) {
      group_of[i] = static_cast<int>(groups.size());
      groups.push_back({i});
    }
  }
  auto area = [&](int k) {
    return cv::contourArea(cv::Mat(4, 1, CV_32FC2, const_cast<cv::Point2f*>(in[k].quad.data())));
  };
  kept->clear();
  for (const std::vector<int>& group : groups) {
    int biggest = group[0];
    double biggest_area = area(biggest);
    for (size_t j = 1; j < group.size(); ++j) {
      const double a = area(group[j]);
      if (a >= biggest_area) biggest = group[j], biggest_area = a;
    }
    kept->push_back(biggest);
  }
}

// Step 4 for one candidate: its id and rotation, or false.
bool IdentifyCandidate(const cv::Mat& gray, const ArucoQuad& quad, const cv::aruco::Dictionary& dictionary,
                       const cv::aruco::DetectorParameters& params, int* id, int* rotation) {
  thread_local cv::Mat warped, mean, deviation, bits, code;
  const int cell = params.perspectiveRemovePixelPerCell;
  const int margin = static_cast<int>(params.perspectiveRemoveIgnoredMarginPerCell * cell);
  const int frame = params.markerBorderBits, size = dictionary.markerSize, cells = size + 2 * frame;
  const int side = cells * cell;
  const float last = static_cast<float>(side) - 1;
  const cv::Point2f square[4] = {{0, 0}, {last, 0}, {last, last}, {0, last}};
  const cv::Mat transform = cv::getPerspectiveTransform(quad.data(), square);
  cv::warpPerspective(gray, warped, transform, cv::Size(side, side), cv::INTER_NEAREST);
  bits.create(cells, cells, CV_8UC1);
  const cv::Mat inner = warped(cv::Range(cell / 2, side - cell / 2), cv::Range(cell / 2, side - cell / 2));
  cv::meanStdDev(inner, mean, deviation);
  if (deviation.ptr<double>()[0] < params.minOtsuStdDev) {
    bits.setTo(mean.ptr<double>()[0] > 127 ? 1 : 0);
  } else {
    cv::threshold(warped, warped, 125, 255, cv::THRESH_BINARY | cv::THRESH_OTSU);
    const int width = cell - 2 * margin;
    const size_t half = static_cast<size_t>(width) * static_cast<size_t>(width) / 2;
    for (int y = 0; y < cells; ++y)
      for (int x = 0; x < cells; ++x) {
        size_t on = 0;
        for (int r = 0; r < width; ++r) {
          const uint8_t* p = warped.ptr<uint8_t>(y * cell + margin + r) + x * cell + margin;
          if (width == 4) {  // 6 px cells, margins of 1 (mcmt's): a row in one word
            on += static_cast<size_t>(4 - ZeroBytesOf4(p));
            continue;
          }
          for (int k = 0; k < width; ++k) on += p[k] != 0;
        }
        bits.at<uint8_t>(y, x) = on > half ? 1 : 0;
      }
  }
  int border_errors = 0;
  for (int y = 0; y < cells; ++y)
    for (int k = 0; k < frame; ++k)
      border_errors += (bits.at<uint8_t>(y, k) != 0) + (bits.at<uint8_t>(y, cells - 1 - k) != 0);
  for (int x = frame; x < cells - frame; ++x)
    for (int k = 0; k < frame; ++k)
      border_errors += (bits.at<uint8_t>(k, x) != 0) + (bits.at<uint8_t>(cells - 1 - k, x) != 0);
  if (border_errors > static_cast<int>(size * size * params.maxErroneousBitsInBorderRate)) return false;
  bits(cv::Range(frame, cells - frame), cv::Range(frame, cells - frame)).copyTo(code);
  return dictionary.identify(code, *id, *rotation, params.errorCorrectionRate);
}

}  // namespace

bool DetectMarkersAsOpenCV(const cv::Mat& gray, const cv::aruco::Dictionary& dictionary,
                           const cv::aruco::DetectorParameters& params, std::vector<ArucoQuad>* corners,
                           std::vector<int>* ids, std::vector<ArucoQuad>* rejected) {
  const cv::aruco::DetectorParameters& p = params;
  const int cell = p.perspectiveRemovePixelPerCell;
  if (gray.type() != CV_8UC1 || gray.empty() || gray.dims != 2 || p.useAruco3Detection ||
      p.detectInvertedMarker || p.cornerRefinementMethod != cv::aruco::CORNER_REFINE_NONE ||
      p.markerBorderBits <= 0 || p.adaptiveThreshWinSizeMin < 3 || p.adaptiveThreshWinSizeMax < 3 ||
      p.adaptiveThreshWinSizeMax < p.adaptiveThreshWinSizeMin || p.adaptiveThreshWinSizeStep <= 0 ||
      !(p.minMarkerPerimeterRate > 0) || !(p.maxMarkerPerimeterRate > 0) ||
      !(p.polygonalApproxAccuracyRate > 0) || !(p.minCornerDistanceRate >= 0) || p.minDistanceToBorder < 0 ||
      !(p.minMarkerDistanceRate >= 0) || cell <= 0 || !(p.perspectiveRemoveIgnoredMarginPerCell >= 0) ||
      !(p.perspectiveRemoveIgnoredMarginPerCell <= 1) ||
      cell - 2 * static_cast<int>(p.perspectiveRemoveIgnoredMarginPerCell * cell) < 0 ||
      !(p.minOtsuStdDev >= 0) || dictionary.markerSize <= 0)
    return false;
  // The aruco module thresholds its own continuous copy (cv::adaptiveThreshold isolates a view's border
  // anyway); a view of a larger image is copied too, so that nothing depends on that.
  const cv::Mat image = gray.isSubmatrix() ? gray.clone() : gray;
  thread_local std::vector<std::vector<Candidate>> per_window;
  thread_local std::vector<Candidate> candidates;
  thread_local std::vector<int> kept, found_ids, rotations;
  const int windows =
      (p.adaptiveThreshWinSizeMax - p.adaptiveThreshWinSizeMin) / p.adaptiveThreshWinSizeStep + 1;
  per_window.resize(static_cast<size_t>(windows));
  // The lambdas name this thread's lists through references: a thread_local's name in a lambda is the
  // running thread's own.
  std::vector<std::vector<Candidate>>& window_lists = per_window;
  std::vector<Candidate>& all = candidates;
  const std::vector<int>& kept_list = kept;
  std::vector<int>& id_list = found_ids;
  std::vector<int>& rotation_list = rotations;
  // The windows and then the candidates in OpenCV's thread pool, as the aruco module runs them (one
  // thread: in this one); each thread has its own images.
  auto window_size = [&](int i) {
    const int window = p.adaptiveThreshWinSizeMin + i * p.adaptiveThreshWinSizeStep;
    return window % 2 == 0 ? window + 1 : window;
  };
  // Two windows of k and 3 k px (mcmt's 5 and 15): both binary images in one pass, the larger window's
  // sums from the smaller one's, written as the border follower reads them (AdaptiveThresholdPairFramed:
  // the same images as cv::adaptiveThreshold's, framed 0/1 images without findContours' conversion pass).
  thread_local FramedBinary pair_binary[2];
  const bool paired = windows == 2 && window_size(1) == 3 * window_size(0) &&
                      AdaptiveThresholdPairFramed(image, window_size(0), p.adaptiveThreshConstant,
                                                  &pair_binary[0], &pair_binary[1]);
  FramedBinary* const pair_images = pair_binary;
  cv::parallel_for_(cv::Range(0, windows), [&](const cv::Range& range) {
    thread_local cv::Mat binary;
    thread_local std::vector<std::vector<cv::Point>> contours;
    thread_local std::vector<cv::Point> approx;
    for (int i = range.start; i < range.end; ++i) {
      if (!paired)
        cv::adaptiveThreshold(image, binary, 255, cv::ADAPTIVE_THRESH_MEAN_C, cv::THRESH_BINARY_INV,
                              window_size(i), p.adaptiveThreshConstant);
      window_lists[i].clear();
      FindWindowCandidates(paired ? nullptr : &binary, paired ? &pair_images[i] : nullptr, p, &contours,
                           &approx, &window_lists[i]);
    }
  });
  candidates.clear();
  for (const std::vector<Candidate>& in_window : per_window)
    candidates.insert(candidates.end(), in_window.begin(), in_window.end());
  for (Candidate& c : candidates) MakeClockwise(&c.quad);  // step 2
  KeepLargestOfGroups(candidates, p.minMarkerDistanceRate, &kept);
  found_ids.assign(kept.size(), -1);
  rotations.assign(kept.size(), 0);
  cv::parallel_for_(cv::Range(0, static_cast<int>(kept.size())), [&](const cv::Range& range) {
    for (int i = range.start; i < range.end; ++i)
      if (!IdentifyCandidate(image, all[kept_list[i]].quad, dictionary, p, &id_list[i], &rotation_list[i]))
        id_list[i] = -1;
  });
  corners->clear();
  ids->clear();
  rejected->clear();
  for (size_t i = 0; i < kept.size(); ++i) {
    const ArucoQuad& quad = candidates[kept[i]].quad;
    if (found_ids[i] >= 0) {
      ArucoQuad turned;
      for (int c = 0; c < 4; ++c) turned[c] = quad[(c + 4 - rotations[i]) % 4];
      corners->push_back(turned);
      ids->push_back(found_ids[i]);
    } else {
      rejected->push_back(quad);
    }
  }
  return true;
}

}  // namespace mcmt
