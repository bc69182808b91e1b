// The caliscope board's marker corners against its ChArUco chessboard corners
// (tests/detector/chessboard_truth.h): the signed offsets (px, outward) and relative size errors of mcmt's
// corners and of stock OpenCV's, per camera, per marker id and per marker size; per camera split by
// marker size, view angle, distance from the image centre and brightness, with the size error against
// two other predictions (a homography from the nearby X-corners only; one in raw pixels, without the lens
// model) and the offsets of the horizontal and vertical sides apart. Then maps the detections as
// test_mapper_realdata does, once as detected and once with every marker's corners replaced by the
// chessboard's prediction, and prints the board's marker spacing / marker size of both maps (1.88562).
//   diag_charuco RIG_YAML [max frames per camera (all)] [camera ("-": all)] [per-marker CSV]
// The CSV's side{s}_clean columns (tilttruth): per side, the 24 model-pass rays (4 per cell) as 0/1, 1 where
// the ray is next to clean code cells (SampleSide's CleanNeighbour on the marker's dictionary bits, the
// ray's place t from the detected side's length), from the side's start corner s to corner s + 1.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <map>

#include "mapper/mapper.h"
#include "tests/detector/chessboard_truth.h"

using namespace mcmt;
using testing::ChessboardMarker;

namespace {
void Print(const std::string& what, const std::vector<ChessboardMarker>& markers,
           const std::function<bool(const ChessboardMarker&)>& take) {
  const testing::ChessboardMean m = testing::MeanOf(markers, take);
  if (m.n)
    std::printf(
        "%-22s %5d markers: offset %+.4f px  size %+.3f %% (local %+.3f %% of %d, raw %+.3f %%)  "
        "horizontal sides %+.4f px, vertical %+.4f px\n",
        what.c_str(), m.n, m.offset_px, 100 * m.size_rel, 100 * m.size_rel_local, m.n_local,
        100 * m.size_rel_raw, m.horizontal_px, m.vertical_px);
}

// Per camera, markers split into bands of `width` of `value`.
void PrintSplit(const RigConfig& rig, const std::vector<ChessboardMarker>& markers, const std::string& name,
                double width, const std::function<double(const ChessboardMarker&)>& value) {
  for (const CameraConfig& cam : rig.cameras)
    for (int b = 0; b < 20; ++b)
      Print(cam.name + " " + name + " " + std::to_string(static_cast<int>(b * width)) + "+", markers,
            [&](const ChessboardMarker& m) {
              return m.camera == cam.name && static_cast<int>(value(m) / width) == b;
            });
}

// Side `side`'s model-pass rays next to clean code cells (as SampleSide: 4 rays per cell, `cells` with
// the border), for a side of `length_px`: '1' clean, '0' not, from the side's start corner.
std::string CleanRays(const cv::Mat& bits, int cells, int side, double length_px) {
  uint8_t flags[16];
  for (int j = 0; j < cells; ++j) {
    const int row = side == 0 ? 1 : side == 1 ? j : side == 2 ? cells - 2 : cells - 1 - j;
    const int col = side == 0 ? j : side == 1 ? cells - 2 : side == 2 ? cells - 1 - j : 1;
    flags[j] = row <= 0 || col <= 0 || row >= cells - 1 || col >= cells - 1
                   ? 0
                   : (bits.at<uint8_t>(row - 1, col - 1) ? 1 : 0);
  }
  const double margin = std::min(0.3, std::max(0.6 * length_px / cells, 1.5) / length_px);
  const int n = 4 * cells;
  std::string out;
  for (int i = 0; i < n; ++i) {
    const double u = (margin + (1.0 - 2.0 * margin) * (i + 0.5) / n) * cells;
    bool clean = true;
    for (double du : {-0.5, 0.0, 0.5})
      if (flags[std::clamp(static_cast<int>(u + du), 0, cells - 1)]) clean = false;
    out += clean ? '1' : '0';
  }
  return out;
}

void WriteCsv(const std::string& path, const std::vector<ChessboardMarker>& markers) {
  std::ofstream out(path);
  out << "camera,frame,id,side_px,offset_px,size_rel,size_rel_local,size_rel_raw,x_px,y_px,view_deg,white,"
         "size_rel_centres,size_rel_stock_centres";
  for (int k = 0; k < 4; ++k) out << ",gx" << k << ",gy" << k << ",wx" << k << ",wy" << k;
  for (int s = 0; s < 4; ++s) out << ",side" << s << "_px,side" << s << "_horizontal";
  for (int s = 0; s < 4; ++s) out << ",side" << s << "_stock_px";
  for (int s = 0; s < 4; ++s) out << ",side" << s << "_clean";
  out << "\n";
  const cv::Ptr<cv::aruco::Dictionary> dictionary =
      cv::aruco::getPredefinedDictionary(cv::aruco::DICT_4X4_1000);
  for (const ChessboardMarker& m : markers) {
    out << m.camera << "," << m.frame << "," << m.id << "," << m.side_px << "," << m.offset_px << ","
        << m.size_rel << "," << m.size_rel_local << "," << m.size_rel_raw << "," << m.x_px << "," << m.y_px
        << "," << m.view_deg << "," << m.white << "," << m.size_rel_centres << ","
        << m.size_rel_stock_centres;
    for (int k = 0; k < 4; ++k)
      out << "," << m.got_ideal[k].x() << "," << m.got_ideal[k].y() << "," << m.want_ideal[k].x() << ","
          << m.want_ideal[k].y();
    for (int s = 0; s < 4; ++s) out << "," << m.side_offset_px[s] << "," << m.side_horizontal[s];
    for (int s = 0; s < 4; ++s) out << "," << m.side_offset_stock_px[s];
    const cv::Mat bits = cv::aruco::Dictionary::getBitsFromByteList(
        dictionary->bytesList.rowRange(m.id, m.id + 1), dictionary->markerSize);
    for (int s = 0; s < 4; ++s)
      out << ","
          << CleanRays(bits, dictionary->markerSize + 2, s,
                       (m.got_ideal[(s + 1) % 4] - m.got_ideal[s]).norm());
    out << "\n";
  }
}
}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: diag_charuco RIG_YAML [max frames per camera] [camera|-] [csv]\n");
    return 2;
  }
  const RigConfig rig = LoadRigConfig(argv[1]);
  const std::string camera = argc > 3 && std::string(argv[3]) != "-" ? argv[3] : "";
  const testing::ChessboardComparison c =
      testing::CompareWithChessboard(rig, argc > 2 ? std::atoi(argv[2]) : -1, camera);
  if (argc > 4) WriteCsv(argv[4], c.mcmt);
  std::printf("homography rms on chessboard corners: %.3f px (mean of %d frames)\n", c.homography_rms_px,
              c.frames);
  for (const CameraConfig& cam : rig.cameras)
    Print(cam.name, c.mcmt, [&](const ChessboardMarker& m) { return m.camera == cam.name; });
  Print("mcmt all", c.mcmt, [](const ChessboardMarker&) { return true; });
  Print("stock all", c.stock, [](const ChessboardMarker&) { return true; });
  for (int id = 0; id < 10; ++id)
    Print("id " + std::to_string(id), c.mcmt, [&](const ChessboardMarker& m) { return m.id == id; });
  for (int b = 1; b < 8; ++b)
    Print(std::to_string(10 * b) + "-" + std::to_string(10 * b + 10) + " px", c.mcmt,
          [&](const ChessboardMarker& m) { return static_cast<int>(m.side_px / 10) == b; });
  PrintSplit(rig, c.mcmt, "side px", 10, [](const ChessboardMarker& m) { return m.side_px; });
  PrintSplit(rig, c.mcmt, "view deg", 15, [](const ChessboardMarker& m) { return m.view_deg; });
  PrintSplit(rig, c.mcmt, "radius px", 150,
             [](const ChessboardMarker& m) { return std::hypot(m.x_px - 640, m.y_px - 360); });
  PrintSplit(rig, c.mcmt, "white", 40, [](const ChessboardMarker& m) { return m.white; });
  for (int variant = 0; variant < 2; ++variant) {
    Mapper mapper(MapperOptions::FromConfig(rig));
    for (const auto& d : variant == 0 ? c.detected : c.predicted) mapper.Add(d);
    try {
      const MapResult result = mapper.Solve();
      const double r = testing::BoardSpacingOverSize(result.map);
      std::printf("map of %s: %zu markers, spacing / size %.5f (%+.3f %%)\n",
                  variant == 0 ? "the detected corners" : "the chessboard-predicted corners",
                  result.map.markers.size(), r, 100 * (r / 1.885618 - 1));
    } catch (const std::exception& e) {
      std::printf("map %d: %s\n", variant, e.what());
    }
  }
  return 0;
}
