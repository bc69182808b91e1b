// Issue 14: every frame's size is checked against the calibration (frames of another size were published
// with the calibrated camera model), and frames of a video that do not decode are counted and reported.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "detector/source.h"
#include "tests/support/temp_dir.h"

namespace mcmt {
namespace {

namespace fs = std::filesystem;

fs::path TempFolder(const std::string& name) { return test::MakeTempDir("source_" + name); }

TEST(SourceChecks, FramesOfAnotherSizeAreRefusedPerFrame) {
  const fs::path dir = TempFolder("size");
  for (int i = 0; i < 6; ++i) {
    const cv::Size size = i == 3 ? cv::Size(32, 24) : cv::Size(64, 48);
    cv::imwrite((dir / (std::to_string(i) + ".png")).string(), cv::Mat(size, CV_8UC1, cv::Scalar(40 * i)));
  }
  SourceOptions o;
  o.source = dir.string();
  o.camera = "cam0";
  o.width = 64;
  o.height = 48;
  auto source = FrameSource::Open(o);
  testing::internal::CaptureStderr();
  std::vector<int64_t> read;
  Frame f;
  while (source->Read(&f)) {
    EXPECT_EQ(f.image.cols, 64);
    read.push_back(f.index);
  }
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(read, (std::vector<int64_t>{0, 1, 2, 4, 5}));
  EXPECT_EQ(source->skipped(), 1);
  EXPECT_NE(err.find("camera cam0: frame 3 of " + dir.string() + " is 32x24, the calibration is for 64x48"),
            std::string::npos)
      << err;
  fs::remove_all(dir);
}

TEST(SourceChecks, AVideoCutShortIsReported) {
  const fs::path dir = TempFolder("video");
  const std::string video = (dir / "v.avi").string();
  {
    cv::VideoWriter w(video, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 30, cv::Size(64, 48), false);
    if (!w.isOpened()) GTEST_SKIP() << "no MJPG writer";
    for (int i = 0; i < 40; ++i) w.write(cv::Mat(48, 64, CV_8UC1, cv::Scalar(5 * i)));
  }
  // Damage: the middle of the file overwritten with garbage.
  {
    std::fstream f(video, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(0, std::ios::end);
    const std::streamoff size = f.tellp();
    f.seekp(size / 3);
    for (std::streamoff i = size / 3; i < size / 2; ++i) f.put(static_cast<char>(0xA5));
  }
  SourceOptions o;
  o.source = video;
  o.camera = "cam1";
  o.width = 64;
  o.height = 48;
  testing::internal::CaptureStderr();
  int64_t frames = 0;
  int64_t skipped = 0;
  try {
    auto source = FrameSource::Open(o);
    Frame f;
    while (source->Read(&f)) ++frames;
    skipped = source->skipped();
  } catch (const std::exception& e) {
    testing::internal::GetCapturedStderr();
    GTEST_SKIP() << "the damaged video does not open: " << e.what();
  }
  const std::string err = testing::internal::GetCapturedStderr();
  std::cout << "[ source ] damaged video: " << frames << " frames read, " << skipped << " skipped"
            << std::endl;
  // Whatever the decoder makes of it, 40 frames are accounted for or the loss is said.
  if (frames + skipped < 40) {
    EXPECT_NE(err.find("camera cam1"), std::string::npos) << err;
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace mcmt
