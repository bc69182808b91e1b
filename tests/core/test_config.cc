#include <gtest/gtest.h>

#include <opencv2/core/persistence.hpp>

#include "core/config.h"
#include "core/dictionary.h"
#include "test_util.h"

namespace mcmt {
namespace {

using testing_util::Replace;
using testing_util::TempDir;

// As OpenCV's calibration sample (and cv::FileStorage) writes it.
const char kOpenCvIntrinsics[] = R"(%YAML:1.0
---
calibration_time: "Sat 21 Nov 2026 10:00:00 UTC"
nframes: 25
image_width: 1280
image_height: 720
board_width: 9
board_height: 6
square_size: 2.5000000000000000e-02
flags: 0
camera_matrix: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [ 9.1234500000000000e+02, 0., 6.4010000000000002e+02, 0.,
       9.1011000000000001e+02, 3.5920000000000005e+02, 0., 0., 1. ]
distortion_coefficients: !!opencv-matrix
   rows: 1
   cols: 5
   dt: d
   data: [ -2.1000000000000001e-01, 8.0000000000000002e-02,
       1.1999999999999999e-03, -8.0000000000000004e-04,
       -1.2e-02 ]
avg_reprojection_error: 2.1e-01
)";

// As ROS camera_calibration writes it.
const char kRosIntrinsics[] = R"(image_width: 640
image_height: 480
camera_name: narrow_stereo
camera_matrix:
  rows: 3
  cols: 3
  data: [500.5, 0, 320.25, 0, 501.75, 240.5, 0, 0, 1]
distortion_model: plumb_bob
distortion_coefficients:
  rows: 1
  cols: 5
  data: [0.1, -0.2, 0.001, 0.002, 0.05]
rectification_matrix:
  rows: 3
  cols: 3
  data: [1, 0, 0, 0, 1, 0, 0, 0, 1]
projection_matrix:
  rows: 3
  cols: 4
  data: [500.5, 0, 320.25, 0, 0, 501.75, 240.5, 0, 0, 0, 1, 0]
)";

const char kRosFisheye[] = R"(image_width: 640
image_height: 480
camera_matrix: {rows: 3, cols: 3, data: [300, 0, 320, 0, 301, 240, 0, 0, 1]}
distortion_model: equidistant
distortion_coefficients: {rows: 1, cols: 4, data: [0.01, -0.002, 0.0003, -0.00004]}
)";

std::string GoodRig() {
  return R"(markers:
  dictionary: DICT_4X4_50
  size: 0.04
  sizes: {7: 0.03, 9: 0.05}
  ids: [1, 2, 7, 9]
  inverted: true
cameras:
  - name: cam0
    intrinsics: cam0.yml
    source: cam0/
  - name: cam1
    intrinsics: intrinsics/cam1_ros.yaml
    source: "0"
    timestamps: ts.txt
  - name: cam2
    intrinsics: cam0.yml
    source: "v4l2src device=/dev/video2 ! videoconvert ! appsink"
mapper:
  reference_camera: cam1
  huber_px: 2.0
lcm:
  url: "udpm://239.255.76.67:7601?ttl=0"
tracker:
  max_rms_px: 3
)";
}

void WriteRigFiles(const TempDir& dir) {
  dir.Write("cam0.yml", kOpenCvIntrinsics);
  dir.Write("intrinsics/cam1_ros.yaml", kRosIntrinsics);
  dir.Write("ts.txt", "0\n33333\n");
  std::filesystem::create_directories(dir.File("cam0"));
}

// Loads a rig whose text is `rig` (with the good intrinsics beside it) and returns the error message.
std::string LoadError(const std::string& rig) {
  TempDir dir;
  WriteRigFiles(dir);
  const std::string path = dir.Write("rig.yaml", rig);
  try {
    LoadRigConfig(path);
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.find('\n'), std::string::npos) << "error is not one line: " << what;
    EXPECT_EQ(what.rfind(path, 0), 0u) << "error does not start with the file: " << what;
    return what;
  }
  ADD_FAILURE() << "no error for:\n" << rig;
  return "";
}

std::string LoadError2(const std::string& path) {
  try {
    LoadRigConfig(path);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(Config, LoadsGoodRig) {
  TempDir dir;
  WriteRigFiles(dir);
  const RigConfig rig = LoadRigConfig(dir.Write("rig.yaml", GoodRig()));
  EXPECT_EQ(rig.dir, dir.path());
  EXPECT_EQ(rig.markers.dictionary, "DICT_4X4_50");
  EXPECT_EQ(rig.markers.size, 0.04);
  EXPECT_EQ(rig.markers.sizes.size(), 2u);
  EXPECT_EQ(rig.markers.Sizes().Get(7), 0.03);
  EXPECT_EQ(rig.markers.Sizes().Get(1), 0.04);
  EXPECT_EQ(rig.markers.ids, (std::vector<int>{1, 2, 7, 9}));
  EXPECT_TRUE(rig.markers.Accepts(7));
  EXPECT_FALSE(rig.markers.Accepts(3));
  EXPECT_TRUE(rig.markers.inverted);
  ASSERT_EQ(rig.cameras.size(), 3u);
  EXPECT_EQ(rig.cameras[0].name, "cam0");
  EXPECT_EQ(rig.cameras[0].intrinsics_path, dir.File("cam0.yml"));
  EXPECT_EQ(rig.cameras[0].source, dir.File("cam0/"));
  EXPECT_EQ(rig.cameras[1].source, "0");
  EXPECT_EQ(rig.cameras[1].timestamps_path, dir.File("ts.txt"));
  EXPECT_EQ(rig.cameras[2].source, "v4l2src device=/dev/video2 ! videoconvert ! appsink");
  // OpenCV intrinsics.
  const CameraModel& k0 = rig.cameras[0].model;
  EXPECT_EQ(k0.width, 1280);
  EXPECT_EQ(k0.height, 720);
  EXPECT_EQ(k0.fx, 912.345);
  EXPECT_EQ(k0.fy, 910.11);
  EXPECT_EQ(k0.cx, 640.1);
  EXPECT_EQ(k0.model, DistortionModel::kRadTan);
  EXPECT_EQ(k0.distortion, (std::vector<double>{-2.1000000000000001e-01, 8.0000000000000002e-02,
                                                1.1999999999999999e-03, -8.0000000000000004e-04, -1.2e-02}));
  // ROS intrinsics.
  const CameraModel& k1 = rig.cameras[1].model;
  EXPECT_EQ(k1.width, 640);
  EXPECT_EQ(k1.fx, 500.5);
  EXPECT_EQ(k1.fy, 501.75);
  EXPECT_EQ(k1.cx, 320.25);
  EXPECT_EQ(k1.cy, 240.5);
  EXPECT_EQ(k1.distortion, (std::vector<double>{0.1, -0.2, 0.001, 0.002, 0.05}));
  EXPECT_EQ(rig.lcm_url, "udpm://239.255.76.67:7601?ttl=0");
  EXPECT_EQ(rig.mapper.GetString("reference_camera", ""), "cam1");
  EXPECT_EQ(rig.mapper.GetDouble("huber_px", 1.0), 2.0);
  EXPECT_EQ(rig.mapper.GetDouble("absent", 1.5), 1.5);
  EXPECT_EQ(rig.tracker.GetDouble("max_rms_px", 1.0), 3.0);
  EXPECT_FALSE(rig.detector.Has("anything"));
  EXPECT_EQ(rig.FindCamera("cam2"), &rig.cameras[2]);
  EXPECT_EQ(rig.FindCamera("nope"), nullptr);
  try {
    rig.GetCamera("nope");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_CONTAINS(e.what(), "nope");
    EXPECT_CONTAINS(e.what(), "cam0, cam1, cam2");
  }
}

TEST(Config, ErrorsNameFileAndKey) {
  const std::string good = GoodRig();
  EXPECT_CONTAINS(LoadError(Replace(good, "  size: 0.04\n", "")), "rig.yaml: markers.size: missing");
  EXPECT_CONTAINS(LoadError(Replace(good, "size: 0.04", "size: abc")),
                  "markers.size: expected a positive number, got 'abc'");
  EXPECT_CONTAINS(LoadError(Replace(good, "size: 0.04", "size: -1")),
                  "markers.size: expected a positive number");
  EXPECT_CONTAINS(LoadError(Replace(good, "- name: cam2", "- name: cam0")),
                  "cameras[2].name: duplicated camera name 'cam0'");
  {
    const std::string e = LoadError(Replace(good, "DICT_4X4_50", "DICT_4X4_51"));
    EXPECT_CONTAINS(e, "markers.dictionary: unknown dictionary 'DICT_4X4_51'");
    EXPECT_CONTAINS(e, "DICT_4X4_50");
    EXPECT_CONTAINS(e, "DICT_APRILTAG_36h11");
  }
  EXPECT_CONTAINS(LoadError(Replace(good, "intrinsics: cam0.yml", "intrinsics: missing.yml")),
                  "cameras[0].intrinsics: file not found");
  EXPECT_CONTAINS(LoadError(Replace(good, "  - name: cam1\n", "  - nam: cam1\n")),
                  "cameras[1].nam: unknown key");
  EXPECT_CONTAINS(LoadError(Replace(good, "    intrinsics: intrinsics/cam1_ros.yaml\n", "")),
                  "cameras[1].intrinsics: missing");
  EXPECT_CONTAINS(LoadError(Replace(good, "  inverted: true", "  inverted: maybe")),
                  "markers.inverted: expected true or false, got 'maybe'");
  EXPECT_CONTAINS(LoadError(Replace(good, "  inverted: true", "  invertd: true")),
                  "markers.invertd: unknown key");
  EXPECT_CONTAINS(LoadError(Replace(good, "ids: [1, 2, 7, 9]", "ids: [1, x]")), "markers.ids: item 1");
  EXPECT_CONTAINS(LoadError(Replace(good, "{7: 0.03, 9: 0.05}", "{7: 0.03, 9: big}")),
                  "markers.sizes.9: expected a positive number, got 'big'");
  EXPECT_CONTAINS(LoadError(Replace(good, "timestamps: ts.txt", "timestamps: none.txt")),
                  "cameras[1].timestamps: file not found");
  EXPECT_CONTAINS(LoadError("markers: {size: 0.04}\ncameras: []\n"), "rig.yaml: cameras: empty camera list");
  EXPECT_CONTAINS(LoadError("markers: {size: 0.04}\n"), "rig.yaml: cameras: missing");
  EXPECT_CONTAINS(LoadError("cameras: []\n"), "rig.yaml: markers: missing");
  EXPECT_CONTAINS(LoadError("markers: {size: 0.04}\ncameras: cam0\n"), "cameras: expected a list");
  EXPECT_CONTAINS(LoadError(Replace(good, "lcm:", "lcmm:")), "lcmm: unknown key");
  EXPECT_CONTAINS(LoadError(Replace(good, "tracker:\n  max_rms_px: 3", "tracker: 3")),
                  "tracker: expected a mapping");
  EXPECT_CONTAINS(LoadError("markers: {size: 0.04\ncameras: []\n"), "YAML syntax error");
}

// Issue 14: accepted silently before.
TEST(Config, IdsOutsideTheDictionaryRepeatedIdsDuplicatedKeysAndAbsurdSizesAreRefused) {
  const std::string good = GoodRig();
  EXPECT_CONTAINS(LoadError(Replace(good, "ids: [1, 2, 7, 9]", "ids: [1, 2, 7, 50]")),
                  "markers.ids: marker id 50 is not in DICT_4X4_50 (ids 0-49)");
  EXPECT_CONTAINS(LoadError(Replace(good, "ids: [1, 2, 7, 9]", "ids: [1, 2, 7, 2]")),
                  "markers.ids: marker id 2 is listed twice");
  EXPECT_CONTAINS(LoadError(Replace(good, "{7: 0.03, 9: 0.05}", "{7: 0.03, 77: 0.05}")),
                  "markers.sizes.77: marker id 77 is not in DICT_4X4_50");
  EXPECT_CONTAINS(LoadError(Replace(good, "size: 0.04", "size: 1e300")),
                  "markers.size: absurd marker side length 1e300 m (at most 10 m)");
  EXPECT_CONTAINS(LoadError(Replace(good, "{7: 0.03, 9: 0.05}", "{7: 0.03, 9: 1e300}")),
                  "markers.sizes.9: absurd marker side length");
  EXPECT_CONTAINS(LoadError(good + "lcm:\n  url: udpm://239.255.76.67:7667\n"),
                  "duplicated key 'lcm' (first at line");
  EXPECT_CONTAINS(LoadError(Replace(good, "  size: 0.04\n", "  size: 0.04\n  size: 0.05\n")),
                  "duplicated key 'size'");
}

TEST(Config, MalformedIntrinsicsNameTheFileAndKey) {
  struct Case {
    std::string content, expected;
  };
  const std::vector<Case> cases = {
      {Replace(kRosIntrinsics, "camera_matrix:", "camera_matrx:"), "camera_matrix: missing"},
      {Replace(kRosIntrinsics, "image_width: 640\n", ""), "image_width: missing"},
      {Replace(kRosIntrinsics, "data: [500.5, 0, 320.25, 0, 501.75, 240.5, 0, 0, 1]",
               "data: [500.5, 0, 320.25]"),
       "camera_matrix.data: has 3 values, expected rows*cols = 3*3"},
      {Replace(kRosIntrinsics, "data: [500.5, 0, 320.25, 0, 501.75, 240.5, 0, 0, 1]",
               "data: [500.5, 0, 320.25, 0, oops, 240.5, 0, 0, 1]"),
       "camera_matrix.data: item 4: expected a number, got 'oops'"},
      {Replace(kRosIntrinsics, "plumb_bob", "brown_conrady"), "distortion_model: unknown distortion model"},
      {Replace(kRosFisheye, "data: [0.01, -0.002, 0.0003, -0.00004]", "data: [0.01, -0.002, 0.0003]"),
       "distortion_coefficients.data: has 3 values"},
      {Replace(kRosFisheye, "cols: 4, data: [0.01, -0.002, 0.0003, -0.00004]",
               "cols: 3, data: [0.01, -0.002, 0.0003]"),
       "distortion_coefficients: fisheye needs 4 values, got 3"},
      {Replace(kRosIntrinsics, "data: [500.5, 0, 320.25, 0, 501.75", "data: [-500.5, 0, 320.25, 0, 501.75"),
       "camera_matrix: focal lengths must be positive"},
      {"just text", "not an intrinsics file"},
  };
  for (const auto& c : cases) {
    TempDir dir;
    const std::string path = dir.Write("bad_intrinsics.yaml", c.content);
    try {
      LoadIntrinsics(path);
      ADD_FAILURE() << "no error, expected " << c.expected;
    } catch (const ConfigError& e) {
      EXPECT_CONTAINS(e.what(), path + ": ");
      EXPECT_CONTAINS(e.what(), c.expected);
    }
    // Through a rig: the rig file, the camera's key and the intrinsics file all appear.
    dir.Write("rig.yaml",
              "markers: {size: 0.04}\ncameras:\n  - {name: a, intrinsics: bad_intrinsics.yaml}\n");
    try {
      LoadRigConfig(dir.File("rig.yaml"));
      ADD_FAILURE() << "rig loaded with bad intrinsics";
    } catch (const ConfigError& e) {
      EXPECT_CONTAINS(e.what(), "rig.yaml: cameras[0].intrinsics: " + path);
      EXPECT_CONTAINS(e.what(), c.expected);
    }
  }
  EXPECT_THROW(LoadIntrinsics("/nonexistent/file.yaml"), ConfigError);
}

TEST(Config, IntrinsicsFormats) {
  TempDir dir;
  const CameraModel ros_fisheye = LoadIntrinsics(dir.Write("f.yaml", kRosFisheye));
  EXPECT_EQ(ros_fisheye.model, DistortionModel::kFisheye);
  EXPECT_EQ(ros_fisheye.distortion, (std::vector<double>{0.01, -0.002, 0.0003, -0.00004}));
  EXPECT_EQ(ros_fisheye.fy, 301);
  // rational_polynomial: 8 coefficients.
  const CameraModel rational = LoadIntrinsics(
      dir.Write("r.yaml", Replace(Replace(kRosIntrinsics, "plumb_bob", "rational_polynomial"),
                                  "cols: 5\n  data: [0.1, -0.2, 0.001, 0.002, 0.05]",
                                  "cols: 8\n  data: [0.1, -0.2, 0.001, 0.002, 0.05, 0.3, 0.01, 0.002]")));
  EXPECT_EQ(rational.model, DistortionModel::kRadTan);
  EXPECT_EQ(rational.distortion.size(), 8u);
  // OpenCV's 14-coefficient output with a zero tail is accepted as 8.
  cv::FileStorage fs(dir.File("cv14.yml"), cv::FileStorage::WRITE);
  fs << "image_width" << 800 << "image_height" << 600;
  fs << "camera_matrix" << (cv::Mat_<double>(3, 3) << 700, 0, 400, 0, 701, 300, 0, 0, 1);
  cv::Mat d = cv::Mat::zeros(14, 1, CV_64F);
  d.at<double>(0) = -0.1;
  d.at<double>(5) = 0.2;
  fs << "distortion_coefficients" << d;
  fs.release();
  const CameraModel cv14 = LoadIntrinsics(dir.File("cv14.yml"));
  // OpenCV's calibration sample marks a fisheye calibration with fisheye_model: 1.
  const CameraModel fisheye = LoadIntrinsics(dir.Write("cv_fisheye.yml", R"(%YAML:1.0
---
image_width: 1280
image_height: 720
fisheye_model: 1
camera_matrix: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [ 600., 0., 640., 0., 601., 360., 0., 0., 1. ]
distortion_coefficients: !!opencv-matrix
   rows: 4
   cols: 1
   dt: d
   data: [ 0.1, -0.01, 0.001, -0.0001 ]
)"));
  EXPECT_EQ(fisheye.model, DistortionModel::kFisheye);
  EXPECT_EQ(fisheye.distortion.size(), 4u);
  EXPECT_EQ(cv14.distortion.size(), 8u);
  EXPECT_EQ(cv14.distortion[5], 0.2);
  EXPECT_EQ(cv14.fy, 701);
}

TEST(Config, WriteIntrinsicsRoundTripsAndOpenCvReadsIt) {
  TempDir dir;
  std::vector<CameraModel> models(4);
  for (auto& m : models) {
    m.width = 1920;
    m.height = 1080;
    m.fx = 1234.5678901234567;
    m.fy = 1230.1;
    m.cx = 959.49999999999989;
    m.cy = 540.3;
  }
  models[1].model = DistortionModel::kRadTan;
  models[1].distortion = {-0.1, 0.02, 1e-4, -2e-4, 0.003};
  models[2].model = DistortionModel::kRadTan;
  models[2].distortion = {-0.1, 0.02, 1e-4, -2e-4, 0.003, 0.1 / 3, 0.2, 1e-17};
  models[3].model = DistortionModel::kFisheye;
  models[3].distortion = {0.1, -0.01, 0.001, -1.0 / 3e4};
  for (size_t i = 0; i < models.size(); ++i) {
    const std::string path = dir.File("k" + std::to_string(i) + ".yml");
    WriteIntrinsicsOpenCv(path, models[i]);
    EXPECT_TRUE(LoadIntrinsics(path) == models[i]) << i;
    cv::FileStorage fs(path, cv::FileStorage::READ);
    ASSERT_TRUE(fs.isOpened());
    cv::Mat k, d;
    fs["camera_matrix"] >> k;
    fs["distortion_coefficients"] >> d;
    EXPECT_EQ(static_cast<int>(fs["image_width"]), 1920);
    EXPECT_EQ(static_cast<int>(fs["image_height"]), 1080);
    EXPECT_EQ(static_cast<std::string>(fs["distortion_model"]), DistortionModelName(models[i].model));
    EXPECT_EQ(cv::norm(k, models[i].CameraMatrix(), cv::NORM_INF), 0.0);
    if (!models[i].distortion.empty()) {
      EXPECT_EQ(cv::norm(d, models[i].DistortionCoeffs(), cv::NORM_INF), 0.0);
    }
    // No temporary file left behind.
    for (const auto& entry : std::filesystem::directory_iterator(dir.path()))
      EXPECT_EQ(entry.path().string().find(".tmp."), std::string::npos);
  }
}

TEST(Config, YamlSectionAccessors) {
  const YAML::Node node = YAML::Load("a: 1.5\nb: 3\nc: yes\nd: text\ne: [1, 2]\nf: {g: 2}\nh: zz\n");
  const YamlSection s(node, "x.yaml", "sec");
  EXPECT_TRUE(s.Has("a"));
  EXPECT_FALSE(s.Has("z"));
  EXPECT_EQ(s.GetDouble("a", 0), 1.5);
  EXPECT_EQ(s.GetInt("b", 0), 3);
  EXPECT_EQ(s.GetBool("c", false), true);
  EXPECT_EQ(s.GetString("d", ""), "text");
  EXPECT_EQ(s.GetIntList("e"), (std::vector<int>{1, 2}));
  EXPECT_EQ(s.Child("f").GetInt("g", 0), 2);
  EXPECT_EQ(s.Child("f").KeyName("g"), "sec.f.g");
  EXPECT_FALSE(s.Child("absent").Has("g"));
  EXPECT_EQ(s.RequireDouble("a"), 1.5);
  auto message = [](const std::function<void()>& f) -> std::string {
    try {
      f();
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(message([&] { s.GetDouble("h", 0); }), "x.yaml: sec.h: expected a number, got 'zz'");
  EXPECT_EQ(message([&] { s.GetInt("a", 0); }), "x.yaml: sec.a: expected an integer, got '1.5'");
  EXPECT_EQ(message([&] { s.RequireString("zz"); }), "x.yaml: sec.zz: missing");
  EXPECT_EQ(message([&] { s.GetPositiveDouble("b", 1); }), "");
  EXPECT_EQ(message([&] { s.Child("a"); }), "x.yaml: sec.a: expected a mapping, got 1.5");
  EXPECT_CONTAINS(message([&] {
                    s.CheckKnownKeys({"a", "b", "c", "d", "e", "f"});
                  }),
                  "x.yaml: sec.h: unknown key");
  EXPECT_EQ(message([&] { s.CheckKnownKeys({"a", "b", "c", "d", "e", "f", "h"}); }), "");
  // An empty section answers defaults.
  const YamlSection empty;
  EXPECT_EQ(empty.GetDouble("a", 4.0), 4.0);
}

TEST(Config, ResolvePath) {
  EXPECT_EQ(ResolvePath("/a/b", "c.yml"), "/a/b/c.yml");
  EXPECT_EQ(ResolvePath("/a/b", "../c.yml"), "/a/c.yml");
  EXPECT_EQ(ResolvePath("/a/b", "/x/y.yml"), "/x/y.yml");
  EXPECT_EQ(ResolvePath("/a/b", ""), "");
}

TEST(Dictionary, PredefinedNames) {
  const auto& names = PredefinedDictionaryNames();
  EXPECT_EQ(names.size(), 21u);
  for (const auto& name : names) {
    const auto d = LoadDictionary(name);
    ASSERT_TRUE(d);
    EXPECT_GT(d->bytesList.rows, 0) << name;
  }
  EXPECT_EQ(LoadDictionary("DICT_6X6_250")->bytesList.rows, 250);
  EXPECT_EQ(LoadDictionary("DICT_APRILTAG_36h11")->markerSize, 6);
  try {
    LoadDictionary("DICT_6X6_251");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_CONTAINS(e.what(), "DICT_6X6_251");
    EXPECT_CONTAINS(e.what(), "DICT_6X6_250");
    EXPECT_CONTAINS(e.what(), "DICT_ARUCO_ORIGINAL");
  }
}

TEST(Dictionary, CustomFileAndMarkerImage) {
  TempDir dir;
  auto original = cv::aruco::getPredefinedDictionary(cv::aruco::DICT_5X5_50);
  {
    auto fs = cv::makePtr<cv::FileStorage>(dir.File("my_dict.yml"), cv::FileStorage::WRITE);
    original->writeDictionary(fs);
    fs->release();
  }
  const auto loaded = LoadDictionary(dir.File("my_dict.yml"));
  EXPECT_EQ(loaded->markerSize, 5);
  EXPECT_EQ(loaded->bytesList.rows, 50);
  EXPECT_EQ(cv::norm(loaded->bytesList, original->bytesList, cv::NORM_INF), 0.0);
  // The same image as OpenCV draws.
  cv::Mat expected;
  original->drawMarker(13, 140, expected, 1);
  const cv::Mat image = MarkerImage(*loaded, 13, 140);
  EXPECT_EQ(image.size(), cv::Size(140, 140));
  EXPECT_EQ(cv::norm(image, expected, cv::NORM_INF), 0.0);
  EXPECT_THROW(MarkerImage(*loaded, 50, 100), std::invalid_argument);
  // Errors name the file.
  const std::string bad = dir.Write("bad.yml", "%YAML:1.0\nnmarkers: 2\nmarkersize: 4\nmarker_0: \"0101\"\n");
  try {
    LoadDictionary(bad);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_CONTAINS(e.what(), bad);
  }
  EXPECT_THROW(LoadDictionary(dir.File("absent.yml")), std::invalid_argument);
  // A rig names it relative to the rig's folder.
  dir.Write("k.yml", kRosIntrinsics);
  dir.Write("rig.yaml",
            "markers: {size: 0.04, dictionary: my_dict.yml}\ncameras:\n  - {name: a, intrinsics: k.yml}\n");
  EXPECT_EQ(LoadRigConfig(dir.File("rig.yaml")).markers.dictionary, dir.File("my_dict.yml"));
  dir.Write("rig2.yaml",
            "markers: {size: 0.04, dictionary: bad.yml}\ncameras:\n  - {name: a, intrinsics: k.yml}\n");
  EXPECT_CONTAINS(LoadError2(dir.File("rig2.yaml")), "markers.dictionary");
}

}  // namespace
}  // namespace mcmt
