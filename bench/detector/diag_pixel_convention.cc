// The pixel convention of mcmt's marker corners and of OpenCV's ChArUco chessboard corners (the truth of
// tests/detector/chessboard_truth.h) on a camera of a caliscope recording: every third frame of the first
// 111 is also detected rotated by 180 deg (pixel (x, y) -> (w - 1 - x, h - 1 - y) with pixel centres at
// integer coordinates). A method reporting x + c gives corners whose rotated-back position minus the
// frame's own is -2c on average.
//   diag_pixel_convention RIG_YAML [CAMERA_INDEX (0)]
#include <cstdio>
#include <map>
#include <opencv2/imgproc.hpp>

#include "detector/detector.h"
#include "detector/source.h"
#include "tests/detector/chessboard_truth.h"

using namespace mcmt;

namespace {

// The chessboard corners of the caliscope board in `gray`, by id (no camera model: pixel positions only).
std::map<int, cv::Point2f> CharucoCorners(const cv::Mat& gray) {
  static const auto board = testing::CaliscopeCharucoBoard();
  const testing::CharucoDetection d = testing::DetectCharuco(gray, board, cv::Mat(), cv::Mat());
  std::map<int, cv::Point2f> out;
  for (size_t i = 0; i < d.corner_ids.size(); ++i) out[d.corner_ids[i]] = d.corners[i];
  return out;
}

struct Mean {
  double x = 0, y = 0;
  int n = 0;
  void Print(const std::string& what) const {
    std::printf("%s: rotated back minus own %+.3f %+.3f px (%d corners): c = %+.3f %+.3f px\n", what.c_str(),
                x / n, y / n, n, -0.5 * x / n, -0.5 * y / n);
  }
};

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: diag_pixel_convention RIG_YAML [CAMERA_INDEX]\n");
    return 2;
  }
  const RigConfig rig = LoadRigConfig(argv[1]);
  const CameraConfig& cam = rig.cameras.at(argc > 2 ? std::atoi(argv[2]) : 0);
  SourceOptions so;
  so.source = cam.source, so.camera = cam.name;
  auto source = FrameSource::Open(so);
  MarkerDetector detector(rig.markers, DetectorOptions::FromConfig(rig));
  Mean ours, charuco;
  Frame frame;
  for (int f = 0; f < 111 && source->Read(&frame); ++f) {
    if (f % 3) continue;
    cv::Mat gray, rotated;
    if (frame.image.channels() == 3)
      cv::cvtColor(frame.image, gray, cv::COLOR_BGR2GRAY);
    else
      gray = frame.image;
    cv::rotate(gray, rotated, cv::ROTATE_180);
    const double w = gray.cols - 1, h = gray.rows - 1;
    detector.Reset();
    const std::vector<marker_t> own = detector.Detect(gray);
    detector.Reset();
    const std::vector<marker_t> turned = detector.Detect(rotated);
    for (const marker_t& a : own)
      for (const marker_t& b : turned)
        if (a.id == b.id)
          for (int k = 0; k < 4; ++k)
            ours.x += w - b.corners[k][0] - a.corners[k][0], ours.y += h - b.corners[k][1] - a.corners[k][1],
                ++ours.n;
    const std::map<int, cv::Point2f> c0 = CharucoCorners(gray), c1 = CharucoCorners(rotated);
    for (const auto& [id, p] : c0)
      if (c1.count(id)) charuco.x += w - c1.at(id).x - p.x, charuco.y += h - c1.at(id).y - p.y, ++charuco.n;
  }
  ours.Print(cam.name + " mcmt's marker corners");
  charuco.Print(cam.name + " OpenCV's ChArUco corners");
  return 0;
}
