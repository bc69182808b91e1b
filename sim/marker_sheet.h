// Printable marker sheets at exact size: PDF (vector page, each marker an image whose cells are scaled
// with interpolation off, so the printed side is exactly the requested length) or PNG whose pixel pitch
// makes every marker cell a whole number of pixels (the dpi is recorded in the PNG's pHYs chunk).
// Every page says what to measure with a ruler and carries a 100 mm scale bar. Inverted sheets
// (markers.inverted) print white-on-black markers on a black quiet zone.
#pragma once

#include <string>
#include <vector>

#include "core/config.h"

namespace mcmt {
namespace sim {

struct MarkerSheetOptions {
  std::string dictionary = "DICT_6X6_250";
  std::vector<int> ids;           // markers to print
  MarkerSizes sizes;              // side length per id, metres
  bool inverted = false;          // white-on-black markers (markers.inverted)
  std::string page = "a4";        // a4 | letter
  double margin_mm = 10.0;        // page margin
  double quiet_zone_cells = 1.0;  // border around each marker (white, black when inverted), in cells
  // PNG only: the resolution. With exact_dpi false it is a target: the sheet uses the nearest dpi at which
  // every marker cell is a whole number of pixels. With exact_dpi true a dpi at which some marker is not a
  // whole number of pixels is refused, naming the nearest exact dpi.
  double dpi = 600.0;
  bool exact_dpi = false;
};

// Parses "0-9,12,15-17" into ids; throws std::invalid_argument naming the bad part.
std::vector<int> ParseIdList(const std::string& text);

// The dpi a PNG sheet of these options is written at (see MarkerSheetOptions::dpi). Throws
// std::invalid_argument when exact_dpi is set and options.dpi is not exact, or when the sizes share no
// whole-pixel pitch near options.dpi (then only a PDF is exact).
double PngSheetDpi(const MarkerSheetOptions& options, int cells);

// Writes one or more pages (PDF: all pages in one file; PNG: NAME.png, NAME_2.png, ...). Returns the
// files written. Throws std::runtime_error when a marker does not fit on the page or an id is not in the
// dictionary, std::invalid_argument for a PNG dpi that cannot be exact (PngSheetDpi).
std::vector<std::string> WriteMarkerSheet(const std::string& path, const MarkerSheetOptions& options);

}  // namespace sim
}  // namespace mcmt
