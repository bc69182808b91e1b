#include "sim/marker_sheet.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <set>
#include <sstream>
#include <stdexcept>

#include "core/dictionary.h"
#include "core/files.h"

namespace mcmt {
namespace sim {
namespace {

constexpr double kPointsPerMm = 72.0 / 25.4;
constexpr double kMmPerInch = 25.4;
// The band at the top of every page: three lines of instructions, then the scale bar.
constexpr double kTextLineMm[3] = {3.0, 6.0, 9.0};  // baselines below the top margin
constexpr double kBarTopMm = 11.0, kBarThickMm = 1.0, kTickMm = 2.0, kTickWidthMm = 0.3;
constexpr double kBarLengthMm = 100.0;
constexpr double kHeaderMm = 17.0;
constexpr double kLabelMm = 5.0;  // label line under each marker

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

std::string Mm(double v, int decimals = 2) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.*f", decimals, v);
  return text;
}

// What every page says: how to print it and what to measure with a ruler.
std::vector<std::string> Instructions(const MarkerSheetOptions& o) {
  const std::string square = o.inverted ? "white" : "black";
  return {o.dictionary + (o.inverted ? " inverted (white-on-black)" : "") +
              " markers. Print at 100 % (actual size, no fit-to-page).",
          "Check with a ruler: the bar below must be " + Mm(kBarLengthMm, 0) + " mm long, and each marker's",
          square + " square, outer edge to outer edge, the size printed under it."};
}

// Shelf packing, row by row, each marker with its quiet zone and a label line under it, below the
// instructions band.
std::vector<Placement> Layout(const MarkerSheetOptions& o, int cells, int* num_pages) {
  double pw, ph;
  PageSizeMm(o.page, &pw, &ph);
  const double top = o.margin_mm + kHeaderMm;
  std::vector<Placement> out;
  double x = o.margin_mm, y = top, row_h = 0;
  int page = 0;
  for (int id : o.ids) {
    const double side = o.sizes.Get(id) * 1000.0;
    if (!(side > 0)) throw std::invalid_argument("marker " + std::to_string(id) + ": size must be positive");
    const double quiet = side / cells * o.quiet_zone_cells;
    const double cell_w = side + 2 * quiet + 4.0, cell_h = side + 2 * quiet + kLabelMm;
    if (cell_w > pw - 2 * o.margin_mm || cell_h > ph - o.margin_mm - top)
      throw std::runtime_error("marker " + std::to_string(id) + " (" + Mm(side) + " mm) does not fit on a " +
                               o.page + " page");
    if (x + cell_w > pw - o.margin_mm) {
      x = o.margin_mm;
      y += row_h;
      row_h = 0;
    }
    if (y + cell_h > ph - o.margin_mm) {
      ++page;
      x = o.margin_mm;
      y = top;
      row_h = 0;
    }
    out.push_back({id, side, x + quiet, y + quiet, page});
    x += cell_w;
    row_h = std::max(row_h, cell_h);
  }
  *num_pages = out.empty() ? 0 : out.back().page + 1;
  return out;
}

// The marker's cells (border included), one byte per cell: 0 black / 255 white, swapped when inverted.
cv::Mat MarkerCells(const cv::aruco::Dictionary& dict, int id, bool inverted) {
  const int cells = dict.markerSize + 2;
  cv::Mat m = MarkerImage(dict, id, cells);
  if (inverted) m = 255 - m;
  return m;
}

std::string Label(const MarkerSheetOptions& o, const Placement& pl) {
  return o.dictionary + " id " + std::to_string(pl.id) + ": " + Mm(pl.side_mm) + " mm";
}

// ---- PDF ------------------------------------------------------------------------------------------------

std::string PdfNumber(double v) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(4);
  s << v;
  return s.str();
}

std::string PdfText(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '(' || c == ')' || c == '\\') out += '\\';
    out += c;
  }
  return out;
}

// A filled black rectangle, in millimetres from the page's top-left.
std::string PdfRect(double x_mm, double y_mm, double w_mm, double h_mm, double page_h_mm) {
  return "0 g " + PdfNumber(x_mm * kPointsPerMm) + " " + PdfNumber((page_h_mm - y_mm - h_mm) * kPointsPerMm) +
         " " + PdfNumber(w_mm * kPointsPerMm) + " " + PdfNumber(h_mm * kPointsPerMm) + " re f\n";
}

std::string PdfTextAt(double x_mm, double y_mm, double page_h_mm, int points, const std::string& text) {
  return "BT /F1 " + std::to_string(points) + " Tf " + PdfNumber(x_mm * kPointsPerMm) + " " +
         PdfNumber((page_h_mm - y_mm) * kPointsPerMm) + " Td (" + PdfText(text) + ") Tj ET\n";
}

// The instructions and the scale bar (bar and ticks, one connected black shape), top of every page.
std::string PdfHeader(const MarkerSheetOptions& o, double ph) {
  std::string c;
  const std::vector<std::string> lines = Instructions(o);
  for (size_t i = 0; i < lines.size(); ++i)
    c += PdfTextAt(o.margin_mm, o.margin_mm + kTextLineMm[i], ph, 7, lines[i]);
  const double bar_y = o.margin_mm + kBarTopMm;
  c += PdfRect(o.margin_mm, bar_y, kBarLengthMm, kBarThickMm, ph);
  for (int k = 0; k <= 10; ++k) {
    const double x = o.margin_mm + std::min(k * kBarLengthMm / 10, kBarLengthMm - kTickWidthMm);
    c += PdfRect(x, bar_y, kTickWidthMm, kBarThickMm + (k % 5 == 0 ? 1.5 : 1.0) * kTickMm, ph);
  }
  c += PdfTextAt(o.margin_mm + kBarLengthMm + 3.0, bar_y + kBarThickMm + 1.0, ph, 7,
                 Mm(kBarLengthMm, 0) + " mm");
  return c;
}

// One page's content stream; adds the page's images to `resources`.
std::string PdfPage(const MarkerSheetOptions& o, int cells, const std::vector<Placement>& placed,
                    const std::vector<int>& image_obj, int page, double ph, std::ostringstream* resources) {
  std::ostringstream content;
  content << PdfHeader(o, ph);
  for (size_t i = 0; i < placed.size(); ++i) {
    const Placement& pl = placed[i];
    if (pl.page != page) continue;
    *resources << " /M" << i << " " << image_obj[i] << " 0 R";
    const double quiet = pl.side_mm / cells * o.quiet_zone_cells;
    if (o.inverted)  // white-on-black markers need a dark surround
      content << PdfRect(pl.x_mm - quiet, pl.y_mm - quiet, pl.side_mm + 2 * quiet, pl.side_mm + 2 * quiet,
                         ph);
    const double s = pl.side_mm * kPointsPerMm;
    const double x = pl.x_mm * kPointsPerMm;
    const double y = (ph - pl.y_mm - pl.side_mm) * kPointsPerMm;  // PDF origin is bottom-left
    content << "q " << PdfNumber(s) << " 0 0 " << PdfNumber(s) << " " << PdfNumber(x) << " " << PdfNumber(y)
            << " cm /M" << i << " Do Q\n";
    content << PdfTextAt(pl.x_mm, pl.y_mm + pl.side_mm + quiet + 3.0, ph, 7, Label(o, pl));
  }
  return content.str();
}

std::string PdfFile(const std::vector<std::string>& objects) {
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
  return pdf;
}

void WritePdf(const std::string& path, const MarkerSheetOptions& o, const cv::aruco::Dictionary& dict,
              const std::vector<Placement>& placed, int pages) {
  double pw, ph;
  PageSizeMm(o.page, &pw, &ph);
  const int cells = dict.markerSize + 2;
  // Objects: 1 catalog, 2 pages, 3 font, then per marker an image, then per page (content, page).
  std::vector<std::string> objects;
  auto add = [&](const std::string& body) {
    objects.push_back(body);
    return static_cast<int>(objects.size());
  };
  add("<< /Type /Catalog /Pages 2 0 R >>");
  add("");  // pages, filled later
  const int font = add("<< /Type /Font /Subtype /Type1 /BaseFont /Helvetica >>");
  std::vector<int> image_obj(placed.size());
  for (size_t i = 0; i < placed.size(); ++i) {
    cv::Mat m = MarkerCells(dict, placed[i].id, o.inverted);
    std::string data(reinterpret_cast<const char*>(m.data), m.total());
    image_obj[i] =
        add("<< /Type /XObject /Subtype /Image /Width " + std::to_string(cells) + " /Height " +
            std::to_string(cells) + " /ColorSpace /DeviceGray /BitsPerComponent 8 /Interpolate false" +
            " /Length " + std::to_string(data.size()) + " >>\nstream\n" + data + "\nendstream");
  }
  std::ostringstream kids;
  for (int p = 0; p < pages; ++p) {
    std::ostringstream resources;
    resources << "<< /Font << /F1 " << font << " 0 R >> /XObject <<";
    const std::string c = PdfPage(o, cells, placed, image_obj, p, ph, &resources);
    resources << " >> >>";
    const int content_obj = add("<< /Length " + std::to_string(c.size()) + " >>\nstream\n" + c + "endstream");
    kids << add("<< /Type /Page /Parent 2 0 R /MediaBox [0 0 " + PdfNumber(pw * kPointsPerMm) + " " +
                PdfNumber(ph * kPointsPerMm) + "] /Resources " + resources.str() + " /Contents " +
                std::to_string(content_obj) + " 0 R >>")
         << " 0 R ";
  }
  objects[1] = "<< /Type /Pages /Kids [" + kids.str() + "] /Count " + std::to_string(pages) + " >>";
  WriteFileAtomic(path, PdfFile(objects));
}

// ---- PNG ------------------------------------------------------------------------------------------------

double CellPixels(double side_mm, int cells, double dpi) { return side_mm / cells * dpi / kMmPerInch; }

// Is every marker cell a whole number of pixels at this dpi (the marker's side within 1 µm)?
bool ExactAt(const std::set<double>& sides_mm, int cells, double dpi, double* bad_side_mm) {
  for (double side : sides_mm) {
    const double px = CellPixels(side, cells, dpi);
    if (std::abs(px - std::round(px)) * cells * kMmPerInch / dpi > 1e-3 || std::round(px) < 1) {
      if (bad_side_mm) *bad_side_mm = side;
      return false;
    }
  }
  return true;
}

// The dpi nearest `target` at which every size is whole cells; 0 when none within a factor of two.
double NearestExactDpi(const std::set<double>& sides_mm, int cells, double target) {
  const double cell_mm = *sides_mm.begin() / cells;
  const long n0 = std::max(1L, std::lround(target * cell_mm / kMmPerInch));
  for (long step = 0; step <= n0 / 2 + 1; ++step) {
    for (long n : {n0 - step, n0 + step}) {
      if (n < 1) continue;
      const double dpi = n * kMmPerInch / cell_mm;
      if (ExactAt(sides_mm, cells, dpi, nullptr)) return dpi;
    }
  }
  return 0.0;
}

// PNG's chunk CRC (ISO 3309 / ITU-T V.42, as the PNG specification gives it).
uint32_t PngCrc(const std::string& bytes) {
  uint32_t c = 0xFFFFFFFFu;
  for (unsigned char b : bytes) {
    c ^= b;
    for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
  }
  return c ^ 0xFFFFFFFFu;
}

std::string BigEndian32(uint32_t v) {
  return {static_cast<char>(v >> 24), static_cast<char>(v >> 16), static_cast<char>(v >> 8),
          static_cast<char>(v)};
}

// The encoded PNG with a pHYs chunk (pixels per metre) after IHDR, so viewers and printers know its size.
std::string WithPhysicalSize(const std::vector<uchar>& png, double dpi) {
  const uint32_t per_metre = static_cast<uint32_t>(std::lround(dpi / 0.0254));
  const std::string body = "pHYs" + BigEndian32(per_metre) + BigEndian32(per_metre) + std::string(1, '\1');
  const std::string chunk = BigEndian32(9) + body + BigEndian32(PngCrc(body));
  const size_t after_ihdr = 8 + 4 + 4 + 13 + 4;
  std::string out(png.begin(), png.end());
  out.insert(after_ihdr, chunk);
  return out;
}

void PngText(cv::Mat* page, const std::string& text, double x_mm, double y_mm, double px_per_mm,
             double cap_mm) {
  const double scale = cap_mm * px_per_mm / 22.0;  // FONT_HERSHEY_SIMPLEX capitals are ~22 units high
  cv::putText(*page, text, cv::Point(static_cast<int>(x_mm * px_per_mm), static_cast<int>(y_mm * px_per_mm)),
              cv::FONT_HERSHEY_SIMPLEX, scale, cv::Scalar(0),
              std::max(1, static_cast<int>(cap_mm * px_per_mm / 12)));
}

void PngRect(cv::Mat* page, double x_mm, double y_mm, double w_mm, double h_mm, double px_per_mm) {
  const int x = static_cast<int>(std::lround(x_mm * px_per_mm)),
            y = static_cast<int>(std::lround(y_mm * px_per_mm));
  const int w = static_cast<int>(std::lround(w_mm * px_per_mm)),
            h = static_cast<int>(std::lround(h_mm * px_per_mm));
  cv::rectangle(*page, cv::Rect(x, y, std::max(1, w), std::max(1, h)), cv::Scalar(0), cv::FILLED);
}

void PngHeader(cv::Mat* page, const MarkerSheetOptions& o, double px_per_mm) {
  const std::vector<std::string> lines = Instructions(o);
  for (size_t i = 0; i < lines.size(); ++i)
    PngText(page, lines[i], o.margin_mm, o.margin_mm + kTextLineMm[i], px_per_mm, 1.6);
  const double bar_y = o.margin_mm + kBarTopMm;
  PngRect(page, o.margin_mm, bar_y, kBarLengthMm, kBarThickMm, px_per_mm);
  for (int k = 0; k <= 10; ++k) {
    const double x = o.margin_mm + std::min(k * kBarLengthMm / 10, kBarLengthMm - kTickWidthMm);
    PngRect(page, x, bar_y, kTickWidthMm, kBarThickMm + (k % 5 == 0 ? 1.5 : 1.0) * kTickMm, px_per_mm);
  }
  PngText(page, Mm(kBarLengthMm, 0) + " mm", o.margin_mm + kBarLengthMm + 3.0, bar_y + kBarThickMm + 1.0,
          px_per_mm, 1.6);
}

// One marker with its quiet zone (black when inverted), cells of whole pixels.
void PngMarker(cv::Mat* page, const MarkerSheetOptions& o, const cv::aruco::Dictionary& dict,
               const Placement& pl, double px_per_mm) {
  const int cells = dict.markerSize + 2;
  const int cell_px = static_cast<int>(std::lround(pl.side_mm * px_per_mm / cells));
  cv::Mat m;
  cv::resize(MarkerCells(dict, pl.id, o.inverted), m, cv::Size(cells * cell_px, cells * cell_px), 0, 0,
             cv::INTER_NEAREST);
  const int x = static_cast<int>(std::lround(pl.x_mm * px_per_mm));
  const int y = static_cast<int>(std::lround(pl.y_mm * px_per_mm));
  const int quiet = static_cast<int>(std::lround(cell_px * o.quiet_zone_cells));
  if (o.inverted)
    cv::rectangle(*page, cv::Rect(x - quiet, y - quiet, m.cols + 2 * quiet, m.rows + 2 * quiet),
                  cv::Scalar(0), cv::FILLED);
  m.copyTo((*page)(cv::Rect(x, y, m.cols, m.rows)));
  PngText(page, Label(o, pl), pl.x_mm, (y + m.rows + quiet) / px_per_mm + 3.0, px_per_mm, 1.6);
}

std::vector<std::string> WritePng(const std::string& path, const MarkerSheetOptions& o,
                                  const cv::aruco::Dictionary& dict, const std::vector<Placement>& placed,
                                  int pages) {
  double pw, ph;
  PageSizeMm(o.page, &pw, &ph);
  const double dpi = PngSheetDpi(o, dict.markerSize + 2);
  const double px_per_mm = dpi / kMmPerInch;
  std::vector<std::string> files;
  const std::string stem = path.size() > 4 ? path.substr(0, path.size() - 4) : path;
  for (int p = 0; p < pages; ++p) {
    cv::Mat page(static_cast<int>(std::lround(ph * px_per_mm)), static_cast<int>(std::lround(pw * px_per_mm)),
                 CV_8UC1, cv::Scalar(255));
    PngHeader(&page, o, px_per_mm);
    for (const Placement& pl : placed)
      if (pl.page == p) PngMarker(&page, o, dict, pl, px_per_mm);
    const std::string file = p == 0 ? path : stem + "_" + std::to_string(p + 1) + ".png";
    std::vector<uchar> buffer;
    if (!cv::imencode(".png", page, buffer)) throw std::runtime_error(file + ": cannot encode PNG");
    WriteFileAtomic(file, WithPhysicalSize(buffer, dpi));
    files.push_back(file);
  }
  return files;
}

}  // namespace

double PngSheetDpi(const MarkerSheetOptions& o, int cells) {
  if (!(o.dpi > 0)) throw std::invalid_argument("dpi must be positive");
  std::set<double> sides;
  for (int id : o.ids) sides.insert(o.sizes.Get(id) * 1000.0);
  if (sides.empty()) return o.dpi;
  double bad = 0;
  if (ExactAt(sides, cells, o.dpi, &bad)) return o.dpi;
  const double nearest = NearestExactDpi(sides, cells, o.dpi);
  if (nearest == 0.0)
    throw std::invalid_argument("the marker sizes share no pixel pitch near " + Mm(o.dpi, 0) +
                                " dpi at which every cell is whole pixels: write a PDF (exact at any size)");
  if (!o.exact_dpi) return nearest;
  const double px = CellPixels(bad, cells, o.dpi);
  throw std::invalid_argument("dpi " + Mm(o.dpi, 4) + ": a " + Mm(bad) + " mm marker would be " +
                              std::to_string(cells) + " cells of " + Mm(px, 3) +
                              " px (PNG cells are whole pixels, so it would print " +
                              Mm(std::round(px) * cells / o.dpi * kMmPerInch, 3) +
                              " mm); the nearest exact dpi is " + Mm(nearest, 4) + " (or write a PDF)");
}

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
