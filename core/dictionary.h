// Marker dictionaries: OpenCV predefined names or a dictionary file (OpenCV's dictionary YAML:
// nmarkers, markersize, maxCorrectionBits, marker_0 ... as cv::aruco::Dictionary::readDictionary reads).
#pragma once

#include <opencv2/aruco.hpp>
#include <string>
#include <vector>

namespace mcmt {

// "DICT_4X4_50" ... "DICT_7X7_1000", "DICT_ARUCO_ORIGINAL", "DICT_APRILTAG_16h5" ... "DICT_APRILTAG_36h11".
const std::vector<std::string>& PredefinedDictionaryNames();

// Name or file -> dictionary. Unknown names throw std::invalid_argument listing the valid names;
// an unreadable or malformed file throws naming the file.
cv::Ptr<cv::aruco::Dictionary> LoadDictionary(const std::string& name_or_file);

// The marker's bit image with a one-cell black border (as cv::aruco::drawMarker), side_px pixels.
cv::Mat MarkerImage(const cv::aruco::Dictionary& dictionary, int id, int side_px);

}  // namespace mcmt
