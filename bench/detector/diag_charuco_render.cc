// The caliscope board's small steep markers on renders (issue 15, bench/results/2026-12-05-cam1bias.md):
// each marker's size error (perimeter / true perimeter - 1), its mean outward offset (the sides' widths)
// and its skew error (how much farther from square its corner angles are than the true ones), per band
// of side and view angle. A size error with no offset is a skew error.
// Default: the board's neighbourhood. An inverted 4x4 marker (bright border, a dark one-cell margin, the
// bright neighbouring square beyond), drawn as the negative of a print with a one-cell margin on a
// black surface, through the camera, detected with the gamma given.
//   diag_charuco_render [images per band (20)] [blur sigma px (0.9)] [gamma (1.85)]
//                       [detector gamma (= gamma)] [defocus radius px (0)]
//                       [unsharp amount (0; sigma 1 px, on encoded values)] [JPEG quality (0)]
//                       [halo weight (0)] [halo sigma px (3)] [MPEG-4 qscale (0)]
//                       [denoise range (0; encoded levels)] [demosaic (0; 1 bilinear, 2 VNG, 3 EA)]
//                       [shoulder knee (0: none; encoded level)] [pedestal (0; encoded levels)]
//                       [encoded blur sigma px (0)]
// The halo: a part of the light spread by a second, wider Gaussian (a point-spread function that is not
// one Gaussian; a negative weight takes light away, as a sharpening of linear light does). The MPEG-4
// qscale: each image encoded as one frame by ffmpeg's mpeg4 encoder at that fixed quantiser (the
// caliscope recordings are MPEG-4 part 2 at qscale 3, 4:2:0) and decoded (its luma). The denoise: an
// edge-preserving smoothing of the encoded image (bilateral, 5 px, space sigma 1 px, range sigma as given),
// as webcams denoise: it flattens what differs less than the range from its neighbours. The demosaic:
// the (grey) image taken as a Bayer mosaic's samples and demosaiced by OpenCV, then made grey again: each
// pixel's value mixes its own sample with interpolated neighbours, differently on each of the 4 sites.
// The shoulder and the pedestal: a tone curve that is not the power law the detector is told. Above the
// knee K the encoded values roll off, y = x - (x - K)^2 / (2 (255 - K)) (slope 0 at 255); the pedestal
// P lifts the blacks, y = P + (255 - P) x / 255. The encoded blur: a Gaussian blur of the encoded image
// (after the gamma), as a webcam that scales or filters its YUV output blurs.
// Or condition N of the reference catalogue (ImagingCatalogue) as bench_imaging_maps renders it
// (DICT_6X6_250, not inverted, gamma fitted):
//   diag_charuco_render cN [images per band (20)]
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "tests/detector/accuracy.h"

using namespace mcmt;

namespace {

struct Band {
  double min_side_px, max_side_px, min_angle_deg, max_angle_deg;
};
constexpr Band kBands[] = {{15, 20, 0, 30},  {15, 20, 55, 70}, {20, 28, 0, 30},
                           {20, 28, 55, 70}, {30, 45, 0, 30},  {30, 45, 55, 70}};

// One detection against its truth: size error %, mean outward offset px, skew error deg.
struct MarkerError {
  double size_pct = 0, offset_px = 0, skew_deg = 0;
};

MarkerError ErrorOf(const marker_t& m, const testing::RenderedMarker& t) {
  std::array<cv::Point2d, 4> got;
  for (int k = 0; k < 4; ++k) got[k] = {m.corners[k][0], m.corners[k][1]};
  MarkerError e;
  for (int k = 0; k < 4; ++k) {
    const int next = (k + 1) % 4;
    // offset: the mean over the 4 sides of their ends' displacement along the true outward normal
    const cv::Point2d n = testing::OutwardNormal(t, k);
    e.offset_px += 0.125 * (n.dot(got[k] - t.corners[k]) + n.dot(got[next] - t.corners[next]));
  }
  e.size_pct = 100 * (testing::QuadPerimeter(got) / testing::QuadPerimeter(t.corners) - 1);
  e.skew_deg = testing::QuadSkewDeg(got) - testing::QuadSkewDeg(t.corners);
  return e;
}

// `image` through ffmpeg's MPEG-4 part 2 encoder at fixed quantiser `qscale` (4:2:0, one intra frame),
// decoded again; empty if ffmpeg failed.
cv::Mat ThroughMpeg4(const cv::Mat& image, int qscale) {
  const std::string stem = "/tmp/diag_charuco_render_" + std::to_string(getpid());
  cv::imwrite(stem + ".png", image);
  const std::string command = "ffmpeg -v error -y -i " + stem + ".png -c:v mpeg4 -q:v " +
                              std::to_string(qscale) + " -pix_fmt yuv420p " + stem + ".mp4";
  if (std::system(command.c_str()) != 0) return cv::Mat();
  cv::VideoCapture video(stem + ".mp4");
  cv::Mat frame, gray;
  if (!video.read(frame)) return cv::Mat();
  cv::cvtColor(frame, gray, cv::COLOR_BGR2GRAY);
  return gray;
}

// `images` renders per band of `im` (the negative of each render when `negative`), detected with the
// dictionary, polarity and gamma given; one line per band.
void Report(const testing::Imaging& im, const std::string& dictionary, bool inverted, bool negative,
            double gamma, int images, double halo_weight = 0, double halo_sigma_px = 3, int mpeg4_qscale = 0,
            double denoise_range = 0, int demosaic = 0, double shoulder_knee = 0, double pedestal = 0,
            double encoded_blur_px = 0) {
  auto dict = LoadDictionary(dictionary);
  MarkerConfig mc;
  mc.dictionary = dictionary, mc.inverted = inverted;
  DetectorOptions o;
  o.inverted = inverted, o.gamma = gamma;
  for (const Band& b : kBands) {
    MarkerDetector detector(mc, o);
    testing::ReferenceScene scene;
    scene.min_side_px = b.min_side_px, scene.max_side_px = b.max_side_px;
    scene.min_angle_deg = b.min_angle_deg, scene.max_angle_deg = b.max_angle_deg;
    scene.markers = 8;
    std::mt19937_64 rng(7 + static_cast<uint64_t>(b.min_side_px + b.min_angle_deg));
    MarkerError sum;
    double size_sq = 0;
    int n = 0, truths = 0;
    for (int i = 0; i < images; ++i) {
      std::vector<testing::RenderedMarker> truth;
      cv::Mat linear = testing::RenderReferenceLinear(*dict, scene, im, rng, &truth);
      if (negative) linear = im.exposure * (im.ink + im.paper) - linear;
      if (halo_weight != 0) {  // linear <- (1 - w) linear + w G(halo sigma) * linear
        cv::Mat wide;
        cv::GaussianBlur(linear, wide, cv::Size(0, 0), halo_sigma_px);
        linear = (1 - halo_weight) * linear + halo_weight * wide;
      }
      cv::Mat image = testing::reference::CameraPipeline(linear, im, rng);
      if (denoise_range > 0) {
        cv::Mat smooth;
        cv::bilateralFilter(image, smooth, 5, denoise_range, 1.0);
        image = smooth;
      }
      if (demosaic > 0) {
        const int code[] = {cv::COLOR_BayerBG2BGR, cv::COLOR_BayerBG2BGR_VNG, cv::COLOR_BayerBG2BGR_EA};
        cv::Mat bgr;
        cv::cvtColor(image, bgr, code[std::min(demosaic, 3) - 1]);
        cv::cvtColor(bgr, image, cv::COLOR_BGR2GRAY);
      }
      if (shoulder_knee > 0 || pedestal > 0)
        for (uint8_t& v : cv::Mat_<uint8_t>(image)) {
          double x = v;
          if (shoulder_knee > 0 && x > shoulder_knee)
            x -= (x - shoulder_knee) * (x - shoulder_knee) / (2 * (255 - shoulder_knee));
          v = cv::saturate_cast<uint8_t>(pedestal + (255 - pedestal) * x / 255);
        }
      if (encoded_blur_px > 0) {
        cv::Mat encoded;
        image.convertTo(encoded, CV_64F);
        cv::GaussianBlur(encoded, encoded, cv::Size(0, 0), encoded_blur_px);
        encoded.convertTo(image, CV_8U);
      }
      if (mpeg4_qscale > 0) image = ThroughMpeg4(image, mpeg4_qscale);
      truths += static_cast<int>(truth.size());
      for (const marker_t& m : detector.Detect(image))
        for (const testing::RenderedMarker& t : truth) {
          if (t.id != m.id) continue;
          const MarkerError e = ErrorOf(m, t);
          sum.size_pct += e.size_pct, sum.offset_px += e.offset_px, sum.skew_deg += e.skew_deg;
          size_sq += e.size_pct * e.size_pct, ++n;
        }
    }
    const int d = std::max(n, 1);
    const double mean = sum.size_pct / d, sd = std::sqrt(std::max(0.0, size_sq / d - mean * mean));
    std::printf(
        "sides %2.0f-%2.0f px, view %2.0f-%2.0f deg: %3d of %3d markers, size %+.3f %% (sd %.3f, se %.3f), "
        "offset %+.4f px, skew error %+.3f deg\n",
        b.min_side_px, b.max_side_px, b.min_angle_deg, b.max_angle_deg, n, truths, mean, sd,
        sd / std::sqrt(d), sum.offset_px / d, sum.skew_deg / d);
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc > 1 && argv[1][0] == 'c') {
    const testing::Imaging im = testing::ImagingCatalogue().at(std::atoi(argv[1] + 1));
    Report(im, "DICT_6X6_250", false, false, 0.0, argc > 2 ? std::atoi(argv[2]) : 20);
    return 0;
  }
  testing::Imaging im;
  im.margin_cells = 1.0, im.surface = im.ink;
  im.blur_sigma = argc > 2 ? std::atof(argv[2]) : 0.9;
  im.gamma = argc > 3 ? std::atof(argv[3]) : 1.85;
  im.defocus_radius = argc > 5 ? std::atof(argv[5]) : 0.0;
  im.sharpen = argc > 6 ? std::atof(argv[6]) : 0.0;
  im.jpeg_quality = argc > 7 ? std::atoi(argv[7]) : 0;
  Report(im, "DICT_4X4_1000", true, true, argc > 4 ? std::atof(argv[4]) : im.gamma,
         argc > 1 ? std::atoi(argv[1]) : 20, argc > 8 ? std::atof(argv[8]) : 0,
         argc > 9 ? std::atof(argv[9]) : 3, argc > 10 ? std::atoi(argv[10]) : 0,
         argc > 11 ? std::atof(argv[11]) : 0, argc > 12 ? std::atoi(argv[12]) : 0,
         argc > 13 ? std::atof(argv[13]) : 0, argc > 14 ? std::atof(argv[14]) : 0,
         argc > 15 ? std::atof(argv[15]) : 0);
  return 0;
}
