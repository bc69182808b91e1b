#include "core/dictionary.h"

#include <fstream>
#include <opencv2/core/persistence.hpp>
#include <sstream>
#include <stdexcept>

namespace mcmt {
namespace {

struct NamedDictionary {
  const char* name;
  cv::aruco::PREDEFINED_DICTIONARY_NAME id;
};

const NamedDictionary kDictionaries[] = {
    {"DICT_4X4_50", cv::aruco::DICT_4X4_50},
    {"DICT_4X4_100", cv::aruco::DICT_4X4_100},
    {"DICT_4X4_250", cv::aruco::DICT_4X4_250},
    {"DICT_4X4_1000", cv::aruco::DICT_4X4_1000},
    {"DICT_5X5_50", cv::aruco::DICT_5X5_50},
    {"DICT_5X5_100", cv::aruco::DICT_5X5_100},
    {"DICT_5X5_250", cv::aruco::DICT_5X5_250},
    {"DICT_5X5_1000", cv::aruco::DICT_5X5_1000},
    {"DICT_6X6_50", cv::aruco::DICT_6X6_50},
    {"DICT_6X6_100", cv::aruco::DICT_6X6_100},
    {"DICT_6X6_250", cv::aruco::DICT_6X6_250},
    {"DICT_6X6_1000", cv::aruco::DICT_6X6_1000},
    {"DICT_7X7_50", cv::aruco::DICT_7X7_50},
    {"DICT_7X7_100", cv::aruco::DICT_7X7_100},
    {"DICT_7X7_250", cv::aruco::DICT_7X7_250},
    {"DICT_7X7_1000", cv::aruco::DICT_7X7_1000},
    {"DICT_ARUCO_ORIGINAL", cv::aruco::DICT_ARUCO_ORIGINAL},
    {"DICT_APRILTAG_16h5", cv::aruco::DICT_APRILTAG_16h5},
    {"DICT_APRILTAG_25h9", cv::aruco::DICT_APRILTAG_25h9},
    {"DICT_APRILTAG_36h10", cv::aruco::DICT_APRILTAG_36h10},
    {"DICT_APRILTAG_36h11", cv::aruco::DICT_APRILTAG_36h11},
};

bool FileExists(const std::string& path) {
  std::ifstream in(path);
  return in.good();
}

}  // namespace

const std::vector<std::string>& PredefinedDictionaryNames() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> v;
    for (const auto& d : kDictionaries) v.push_back(d.name);
    return v;
  }();
  return names;
}

cv::Ptr<cv::aruco::Dictionary> LoadDictionary(const std::string& name_or_file) {
  for (const auto& d : kDictionaries)
    if (name_or_file == d.name) return cv::aruco::getPredefinedDictionary(d.id);
  const bool looks_like_file = name_or_file.find('/') != std::string::npos ||
                               name_or_file.find('.') != std::string::npos || FileExists(name_or_file);
  if (!looks_like_file) {
    std::string valid;
    for (const auto& n : PredefinedDictionaryNames()) valid += (valid.empty() ? "" : ", ") + n;
    throw std::invalid_argument("unknown dictionary '" + name_or_file + "' (valid: " + valid +
                                ", or a dictionary file)");
  }
  if (!FileExists(name_or_file)) throw std::invalid_argument(name_or_file + ": dictionary file not found");
  auto dictionary = cv::makePtr<cv::aruco::Dictionary>();
  bool ok = false;
  try {
    cv::FileStorage fs(name_or_file, cv::FileStorage::READ);
    if (!fs.isOpened()) throw std::invalid_argument(name_or_file + ": cannot read dictionary file");
    if (fs["nmarkers"].empty() || fs["markersize"].empty())
      throw std::invalid_argument(name_or_file +
                                  ": not a dictionary file (needs nmarkers, markersize, marker_0...)");
    const int nmarkers = static_cast<int>(fs["nmarkers"]);
    const int markersize = static_cast<int>(fs["markersize"]);
    if (nmarkers <= 0 || markersize <= 0)
      throw std::invalid_argument(name_or_file + ": nmarkers and markersize must be positive");
    for (int i = 0; i < nmarkers; ++i) {
      const std::string key = "marker_" + std::to_string(i);
      const cv::FileNode node = fs[key];
      if (node.empty()) throw std::invalid_argument(name_or_file + ": " + key + ": missing");
      const std::string bits = static_cast<std::string>(node);
      if (static_cast<int>(bits.size()) != markersize * markersize)
        throw std::invalid_argument(name_or_file + ": " + key + ": expected " +
                                    std::to_string(markersize * markersize) + " bits, got " +
                                    std::to_string(bits.size()));
      if (bits.find_first_not_of("01") != std::string::npos)
        throw std::invalid_argument(name_or_file + ": " + key + ": bits must be 0 or 1");
    }
    ok = dictionary->readDictionary(fs.root());
  } catch (const cv::Exception& e) {
    throw std::invalid_argument(name_or_file + ": malformed dictionary file: " + e.msg);
  }
  if (!ok || dictionary->bytesList.empty())
    throw std::invalid_argument(name_or_file + ": malformed dictionary file");
  return dictionary;
}

cv::Mat MarkerImage(const cv::aruco::Dictionary& dictionary, int id, int side_px) {
  if (id < 0 || id >= dictionary.bytesList.rows)
    throw std::invalid_argument("marker id " + std::to_string(id) + " not in the dictionary (0.." +
                                std::to_string(dictionary.bytesList.rows - 1) + ")");
  cv::Mat image;
  dictionary.drawMarker(id, side_px, image, 1);
  return image;
}

}  // namespace mcmt
