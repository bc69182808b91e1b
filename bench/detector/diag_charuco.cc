// The caliscope board's marker corners against its ChArUco chessboard corners
// (tests/detector/chessboard_truth.h): the signed offsets (px, outward) and relative size errors of mcmt's
// corners and of stock OpenCV's, per camera, per marker id and per marker size. Then maps the detections
// as test_mapper_realdata does, once as detected and once with every marker's corners replaced by the
// chessboard's prediction, and prints the board's marker spacing / marker size of both maps (1.88562).
//   diag_charuco RIG_YAML [max frames per camera (all)] [camera]
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <map>

#include "mapper/mapper.h"
#include "tests/detector/chessboard_truth.h"

using namespace mcmt;
using testing::ChessboardMarker;

namespace {
void Print(const std::string& what, const std::vector<ChessboardMarker>& markers,
           const std::function<bool(const ChessboardMarker&)>& take) {
  double offset = 0, size = 0;
  int n = 0;
  for (const ChessboardMarker& m : markers)
    if (take(m)) offset += m.offset_px, size += m.size_rel, ++n;
  if (n)
    std::printf("%-14s %5d markers: offset %+.4f px  size %+.3f %%\n", what.c_str(), n, offset / n,
                100 * size / n);
}
}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: diag_charuco RIG_YAML [max frames per camera] [camera]\n");
    return 2;
  }
  const RigConfig rig = LoadRigConfig(argv[1]);
  const testing::ChessboardComparison c =
      testing::CompareWithChessboard(rig, argc > 2 ? std::atoi(argv[2]) : -1, argc > 3 ? argv[3] : "");
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
