// mcmt's own cv::aruco::detectMarkers (OpenCV 4.6) for the parameters mcmt's "opencv" candidate search
// passes: the same steps on the same data, calling the same (detector/opencv_overrides.cc) OpenCV functions,
// without the aruco module's copies of the image (its grey copy of an already grey image, a copy of each
// window's binary image before findContours) and its Mats per candidate and per cell.
#pragma once

#include <array>
#include <opencv2/aruco.hpp>
#include <opencv2/core.hpp>
#include <vector>

namespace mcmt {

// A candidate's four corners, as cv::aruco::detectMarkers returns them (pixels).
using ArucoQuad = std::array<cv::Point2f, 4>;

// What cv::aruco::detectMarkers(gray, dictionary, corners, ids, params, rejected) returns, bit for bit:
// the markers' corners and ids in its order, and its rejected candidates (test_detector_unit,
// CandidateSearch.DetectMarkersIsOpenCVs). For an 8-bit one-channel image, without ArUco3, inverted
// markers or corner refinement (CORNER_REFINE_NONE), and parameters OpenCV accepts; false (nothing
// written) otherwise. The windows and then the candidates run in OpenCV's thread pool (cv::parallel_for_),
// as in the aruco module; the lists are the same with any number of threads.
bool DetectMarkersAsOpenCV(const cv::Mat& gray, const cv::aruco::Dictionary& dictionary,
                           const cv::aruco::DetectorParameters& params, std::vector<ArucoQuad>* corners,
                           std::vector<int>* ids, std::vector<ArucoQuad>* rejected);

}  // namespace mcmt
