// Printable marker sheets at exact size: PDF (vector page, each marker an image whose cells are scaled
// with interpolation off, so the printed side is exactly the requested length) or PNG at a chosen DPI.
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
  std::string page = "a4";        // a4 | letter
  double margin_mm = 10.0;        // page margin
  double quiet_zone_cells = 1.0;  // white border around each marker, in marker cells
  double dpi = 600.0;             // PNG only
};

// Parses "0-9,12,15-17" into ids; throws std::invalid_argument naming the bad part.
std::vector<int> ParseIdList(const std::string& text);

// Writes one or more pages (PDF: all pages in one file; PNG: NAME.png, NAME_2.png, ...). Returns the
// files written. Throws std::runtime_error when a marker does not fit on the page or an id is not in the
// dictionary.
std::vector<std::string> WriteMarkerSheet(const std::string& path, const MarkerSheetOptions& options);

}  // namespace sim
}  // namespace mcmt
