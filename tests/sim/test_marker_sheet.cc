// mcmt-markers: sheets are detectable, at the requested size, and bad requests are refused clearly.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/aruco.hpp>
#include <opencv2/imgcodecs.hpp>
#include <regex>
#include <set>
#include <sstream>

#include "core/dictionary.h"
#include "sim/marker_sheet.h"

namespace fs = std::filesystem;
using mcmt::sim::MarkerSheetOptions;

namespace {
fs::path TempDir() {
  fs::path d = fs::temp_directory_path() / ("mcmt_sheet_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}
}  // namespace

TEST(MarkerSheet, ParseIdList) {
  EXPECT_EQ(mcmt::sim::ParseIdList("0-3,7,9-10"), (std::vector<int>{0, 1, 2, 3, 7, 9, 10}));
  EXPECT_THROW(mcmt::sim::ParseIdList("3-1"), std::invalid_argument);
  EXPECT_THROW(mcmt::sim::ParseIdList("a"), std::invalid_argument);
}

TEST(MarkerSheet, PngMarkersAreDetectedAtTheRequestedSize) {
  MarkerSheetOptions o;
  o.dictionary = "DICT_4X4_50";
  o.ids = {0, 1, 2, 3, 4, 5, 6, 7, 8};
  o.sizes.default_size = 0.03;
  o.sizes.overrides[4] = 0.05;
  o.dpi = 300;
  const fs::path png = TempDir() / "sheet.png";
  const auto files = mcmt::sim::WriteMarkerSheet(png.string(), o);
  ASSERT_EQ(files.size(), 1u);
  cv::Mat page = cv::imread(files[0], cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(page.empty());
  EXPECT_NEAR(page.cols, 210.0 / 25.4 * 300, 1.0);  // A4 width at 300 dpi
  std::vector<int> ids;
  std::vector<std::vector<cv::Point2f>> corners;
  cv::aruco::detectMarkers(page, mcmt::LoadDictionary(o.dictionary), corners, ids);
  ASSERT_EQ(std::set<int>(ids.begin(), ids.end()), std::set<int>(o.ids.begin(), o.ids.end()));
  for (size_t i = 0; i < ids.size(); ++i) {
    const double side_px = cv::norm(corners[i][1] - corners[i][0]);
    const double side_mm = side_px / 300.0 * 25.4;
    // Whole pixels per cell: within one cell's rounding (0.5 px per cell, 6 cells) plus detection.
    EXPECT_NEAR(side_mm, o.sizes.Get(ids[i]) * 1000.0, 6 * 0.5 / 300 * 25.4 + 0.2) << "id " << ids[i];
  }
}

TEST(MarkerSheet, PdfPlacesEachMarkerAtExactSize) {
  MarkerSheetOptions o;
  o.ids = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19};
  o.sizes.default_size = 0.06;
  const fs::path pdf = TempDir() / "sheet.pdf";
  mcmt::sim::WriteMarkerSheet(pdf.string(), o);
  std::ifstream in(pdf, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
  ASSERT_EQ(text.rfind("%PDF-1.4", 0), 0u);
  ASSERT_NE(text.find("%%EOF"), std::string::npos);
  // Every marker is drawn with "s 0 0 s x y cm /Mi Do": s must be 60 mm in points.
  std::regex draw(R"(q ([0-9.]+) 0 0 ([0-9.]+) [0-9.]+ [0-9.]+ cm /M[0-9]+ Do Q)");
  int count = 0;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), draw); it != std::sregex_iterator(); ++it) {
    EXPECT_NEAR(std::stod((*it)[1]), 60.0 * 72.0 / 25.4, 1e-3);
    EXPECT_NEAR(std::stod((*it)[2]), 60.0 * 72.0 / 25.4, 1e-3);
    ++count;
  }
  EXPECT_EQ(count, 20);
  // 20 markers of 60 mm do not fit on one A4 page.
  std::regex count_re(R"(/Type /Pages /Kids \[[^\]]*\] /Count ([0-9]+))");
  std::smatch m;
  ASSERT_TRUE(std::regex_search(text, m, count_re));
  EXPECT_GT(std::stoi(m[1]), 1);
}

TEST(MarkerSheet, BadRequestsNameTheProblem) {
  MarkerSheetOptions o;
  o.dictionary = "DICT_4X4_50";
  o.ids = {60};
  o.sizes.default_size = 0.04;
  try {
    mcmt::sim::WriteMarkerSheet((TempDir() / "x.pdf").string(), o);
    FAIL() << "expected an error";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("id 60 is not in DICT_4X4_50"), std::string::npos) << e.what();
  }
  o.ids = {1};
  o.sizes.default_size = 0.4;
  EXPECT_THROW(mcmt::sim::WriteMarkerSheet((TempDir() / "x.pdf").string(), o), std::runtime_error);
  o.sizes.default_size = 0.04;
  EXPECT_THROW(mcmt::sim::WriteMarkerSheet((TempDir() / "x.svg").string(), o), std::invalid_argument);
}
