#include "sim/marker_sheet.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <stdexcept>

#include "core/dictionary.h"
#include "core/files.h"

namespace mcmt {
namespace sim {
namespace {

constexpr double kPointsPerMm = 72.0 / 25.4;

struct Placement {
  int id;
  double side_mm;
  double x_mm, y_mm;  // top-left of the marker (without quiet zone), from the page's top-left
  int page;
};

void PageSizeMm(const std::string& page, double* w, double* h) {
  if (page == "a4") {
    *w = 210.0;
    *h = 297.0;
  } else if (page == "letter") {
    *w = 215.9;
    *h = 279.4;
  } else {
    throw std::invalid_argument("page: expected a4 or letter, got '" + page + "'");
  }
}

// Shelf packing, row by row, each marker with its quiet zone and a label line under it.
std::vector<Placement> Layout(const MarkerSheetOptions& o, int cells, int* num_pages) {
  double pw, ph;
  PageSizeMm(o.page, &pw, &ph);
  const double label_mm = 5.0;
  std::vector<Placement> out;
  double x = o.margin_mm, y = o.margin_mm, row_h = 0;
  int page = 0;
  for (int id : o.ids) {
    const double side = o.sizes.Get(id) * 1000.0;
    if (!(side > 0)) throw std::invalid_argument("marker " + std::to_string(id) + ": size must be positive");
    const double quiet = side / cells * o.quiet_zone_cells;
    const double cell_w = side + 2 * quiet + 4.0, cell_h = side + 2 * quiet + label_mm;
    if (cell_w > pw - 2 * o.margin_mm || cell_h > ph - 2 * o.margin_mm)
      throw std::runtime_error("marker " + std::to_string(id) + " (" + std::to_string(side) +
                               " mm) does not fit on a " + o.page + " page");
    if (x + cell_w > pw - o.margin_mm) {
      x = o.margin_mm;
      y += row_h;
      row_h = 0;
    }
    if (y + cell_h > ph - o.margin_mm) {
      ++page;
      x = o.margin_mm;
      y = o.margin_mm;
      row_h = 0;
    }
    out.push_back({id, side, x + quiet, y + quiet, page});
    x += cell_w;
    row_h = std::max(row_h, cell_h);
  }
  *num_pages = out.empty() ? 0 : out.back().page + 1;
  return out;
}

// The marker's cells (black border included), one byte per cell, 0 black / 255 white.
cv::Mat MarkerCells(const cv::aruco::Dictionary& dict, int id) {
  const int cells = dict.markerSize + 2;
  return MarkerImage(dict, id, cells);
}

std::string PdfNumber(double v) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(4);
  s << v;
  return s.str();
}

void WritePdf(const std::string& path, const MarkerSheetOptions& o, const cv::aruco::Dictionary& dict,
              const std::vector<Placement>& placed, int pages) {
  double pw, ph;
  PageSizeMm(o.page, &pw, &ph);
  const int cells = dict.markerSize + 2;
  // Objects: 1 catalog, 2 pages, 3 font, then per page (page, content), then per marker an image.
  std::vector<std::string> objects;
  auto add = [&](const std::string& body) {
    objects.push_back(body);
    return static_cast<int>(objects.size());
  };
  add("");  // catalog, filled later
  add("");  // pages, filled later
  const int font = add("<< /Type /Font /Subtype /Type1 /BaseFont /Helvetica >>");
  std::vector<int> image_obj(placed.size());
  for (size_t i = 0; i < placed.size(); ++i) {
    cv::Mat m = MarkerCells(dict, placed[i].id);
    std::string data(reinterpret_cast<const char*>(m.data), m.total());
    image_obj[i] =
        add("<< /Type /XObject /Subtype /Image /Width " + std::to_string(cells) + " /Height " +
            std::to_string(cells) + " /ColorSpace /DeviceGray /BitsPerComponent 8 /Interpolate false" +
            " /Length " + std::to_string(data.size()) + " >>\nstream\n" + data + "\nendstream");
  }
  std::vector<int> page_objs;
  for (int p = 0; p < pages; ++p) {
    std::ostringstream content, resources;
    resources << "<< /Font << /F1 " << font << " 0 R >> /XObject <<";
    for (size_t i = 0; i < placed.size(); ++i) {
      const Placement& pl = placed[i];
      if (pl.page != p) continue;
      resources << " /M" << i << " " << image_obj[i] << " 0 R";
      const double s = pl.side_mm * kPointsPerMm;
      const double x = pl.x_mm * kPointsPerMm;
      const double y = (ph - pl.y_mm - pl.side_mm) * kPointsPerMm;  // PDF origin is bottom-left
      content << "q " << PdfNumber(s) << " 0 0 " << PdfNumber(s) << " " << PdfNumber(x) << " " << PdfNumber(y)
              << " cm /M" << i << " Do Q\n";
      const double quiet = pl.side_mm / cells * o.quiet_zone_cells;
      content << "BT /F1 7 Tf " << PdfNumber(x) << " " << PdfNumber(y - (quiet + 3.0) * kPointsPerMm)
              << " Td (" << o.dictionary << " id " << pl.id << ", " << PdfNumber(pl.side_mm)
              << " mm) Tj ET\n";
    }
    resources << " >> >>";
    const std::string c = content.str();
    const int content_obj = add("<< /Length " + std::to_string(c.size()) + " >>\nstream\n" + c + "endstream");
    page_objs.push_back(add("<< /Type /Page /Parent 2 0 R /MediaBox [0 0 " + PdfNumber(pw * kPointsPerMm) +
                            " " + PdfNumber(ph * kPointsPerMm) + "] /Resources " + resources.str() +
                            " /Contents " + std::to_string(content_obj) + " 0 R >>"));
  }
  objects[0] = "<< /Type /Catalog /Pages 2 0 R >>";
  std::ostringstream kids;
  for (int k : page_objs) kids << k << " 0 R ";
  objects[1] = "<< /Type /Pages /Kids [" + kids.str() + "] /Count " + std::to_string(pages) + " >>";

  std::string pdf = "%PDF-1.4\n%\xE2\xE3\xCF\xD3\n";
  std::vector<size_t> offsets;
  for (size_t i = 0; i < objects.size(); ++i) {
    offsets.push_back(pdf.size());
    pdf += std::to_string(i + 1) + " 0 obj\n" + objects[i] + "\nendobj\n";
  }
  const size_t xref = pdf.size();
  pdf += "xref\n0 " + std::to_string(objects.size() + 1) + "\n0000000000 65535 f \n";
  for (size_t off : offsets) {
    char line[32];
    std::snprintf(line, sizeof(line), "%010zu 00000 n \n", off);
    pdf += line;
  }
  pdf += "trailer\n<< /Size " + std::to_string(objects.size() + 1) + " /Root 1 0 R >>\nstartxref\n" +
         std::to_string(xref) + "\n%%EOF\n";
  WriteFileAtomic(path, pdf);
}

std::vector<std::string> WritePng(const std::string& path, const MarkerSheetOptions& o,
                                  const cv::aruco::Dictionary& dict, const std::vector<Placement>& placed,
                                  int pages) {
  double pw, ph;
  PageSizeMm(o.page, &pw, &ph);
  const double px_per_mm = o.dpi / 25.4;
  const int cells = dict.markerSize + 2;
  std::vector<std::string> files;
  const std::string stem = path.size() > 4 ? path.substr(0, path.size() - 4) : path;
  for (int p = 0; p < pages; ++p) {
    cv::Mat page(static_cast<int>(std::lround(ph * px_per_mm)), static_cast<int>(std::lround(pw * px_per_mm)),
                 CV_8UC1, cv::Scalar(255));
    for (const Placement& pl : placed) {
      if (pl.page != p) continue;
      // Whole pixels per cell so every cell prints the same; the side is then within one cell's rounding.
      const int cell_px = std::max(1, static_cast<int>(std::lround(pl.side_mm * px_per_mm / cells)));
      cv::Mat m;
      cv::resize(MarkerCells(dict, pl.id), m, cv::Size(cells * cell_px, cells * cell_px), 0, 0,
                 cv::INTER_NEAREST);
      const int x = static_cast<int>(std::lround(pl.x_mm * px_per_mm));
      const int y = static_cast<int>(std::lround(pl.y_mm * px_per_mm));
      if (x + m.cols > page.cols || y + m.rows > page.rows) continue;
      m.copyTo(page(cv::Rect(x, y, m.cols, m.rows)));
      const double quiet = pl.side_mm / cells * o.quiet_zone_cells;
      cv::putText(page,
                  "id " + std::to_string(pl.id) + "  " +
                      std::to_string(cells * cell_px / px_per_mm).substr(0, 5) + " mm",
                  cv::Point(x, y + m.rows + static_cast<int>((quiet + 3.0) * px_per_mm)),
                  cv::FONT_HERSHEY_SIMPLEX, o.dpi / 300.0, cv::Scalar(0),
                  std::max(1, static_cast<int>(o.dpi / 300)));
    }
    const std::string file = p == 0 ? path : stem + "_" + std::to_string(p + 1) + ".png";
    std::vector<uchar> buffer;
    if (!cv::imencode(".png", page, buffer)) throw std::runtime_error(file + ": cannot encode PNG");
    WriteFileAtomic(file, std::string(buffer.begin(), buffer.end()));
    files.push_back(file);
  }
  return files;
}

}  // namespace

std::vector<int> ParseIdList(const std::string& text) {
  std::vector<int> ids;
  std::stringstream ss(text);
  std::string part;
  while (std::getline(ss, part, ',')) {
    if (part.empty()) continue;
    try {
      size_t dash = part.find('-', 1);
      if (dash == std::string::npos) {
        size_t used = 0;
        ids.push_back(std::stoi(part, &used));
        if (used != part.size()) throw std::invalid_argument(part);
      } else {
        size_t u1 = 0, u2 = 0;
        const int a = std::stoi(part.substr(0, dash), &u1), b = std::stoi(part.substr(dash + 1), &u2);
        if (u1 != dash || u2 != part.size() - dash - 1 || b < a) throw std::invalid_argument(part);
        for (int i = a; i <= b; ++i) ids.push_back(i);
      }
    } catch (const std::exception&) {
      throw std::invalid_argument("ids: cannot read '" + part + "' (expected e.g. 0-9,12)");
    }
  }
  return ids;
}

std::vector<std::string> WriteMarkerSheet(const std::string& path, const MarkerSheetOptions& options) {
  if (options.ids.empty()) throw std::invalid_argument("no marker ids to print");
  cv::Ptr<cv::aruco::Dictionary> dict = LoadDictionary(options.dictionary);
  for (int id : options.ids)
    if (id < 0 || id >= dict->bytesList.rows)
      throw std::invalid_argument("id " + std::to_string(id) + " is not in " + options.dictionary + " (0.." +
                                  std::to_string(dict->bytesList.rows - 1) + ")");
  int pages = 0;
  const std::vector<Placement> placed = Layout(options, dict->markerSize + 2, &pages);
  auto ends_with = [&](const std::string& suffix) {
    return path.size() >= suffix.size() &&
           path.compare(path.size() - suffix.size(), suffix.size(), suffix) == 0;
  };
  if (ends_with(".pdf")) {
    WritePdf(path, options, *dict, placed, pages);
    return {path};
  }
  if (ends_with(".png")) return WritePng(path, options, *dict, placed, pages);
  throw std::invalid_argument(path + ": expected a .pdf or .png output");
}

}  // namespace sim
}  // namespace mcmt
