// mcmt-import's engine on small bags written here: chunk compressions, message decoding from the stored
// definition, corner order against geometry, frame grouping, errors that list what the bag holds.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/config.h"
#include "core/lcm_util.h"
#include "core/log_writer.h"
#include "core/marker.h"
#include "import/import.h"
#include "tests/import/bag_writer.h"
#include "tests/support/process.h"
#include "tests/support/temp_dir.h"

namespace mcmt {
namespace {

using import_test::AprilTagArray;
using import_test::AprilTagDefinition;
using import_test::TestConnection;
using import_test::TestMessage;
using import_test::TestTag;
using test::TempDir;

std::vector<detections_t> ReadSession(const std::string& log) {
  std::vector<detections_t> out;
  for (const LogEvent& e : ReadEventLog(log)) {
    detections_t d = DecodeOrThrow<detections_t>(e.data.data(), e.data.size());
    EXPECT_EQ(e.channel, DetectionsChannel(d.camera));
    EXPECT_EQ(e.timestamp, d.utime);
    out.push_back(d);
  }
  return out;
}

void WriteCameras(const std::string& path, const std::vector<std::string>& topics,
                  const std::string& distortion = "equidistant") {
  std::ofstream f(path);
  for (size_t i = 0; i < topics.size(); ++i)
    f << "cam" << i << ":\n  camera_model: pinhole\n  intrinsics: [470.3, 470.5, 639.7, 524.4]\n"
      << "  distortion_model: " << distortion << "\n  distortion_coeffs: [-0.013, -0.0099, 0.0121, -0.0045]\n"
      << "  resolution: [1280, 1024]\n  rostopic: /images\n  tagtopic: " << topics[i] << "\n";
}

TestTag Tag(int id, double x0) {
  TestTag t{id, {{x0, 100}, {x0 + 20, 100}, {x0 + 20, 80}, {x0, 80}}};
  return t;
}

// A marker 1 m in front of a pinhole camera, turned a little; corners projected in AprilTag's order
// (bottom-left, bottom-right, top-right, top-left of the printed tag: marker frame (-s/2,-s/2),
// (s/2,-s/2), (s/2,s/2), (-s/2,s/2)).
struct Scene {
  CameraModel camera;
  Rigid3 cam_from_marker;
  double side = 0.16;
  Scene() {
    camera = CameraModel::Pinhole(1280, 1024, 600, 640, 512);
    cam_from_marker =
        RigidFromRvecTvec(Eigen::Vector3d(M_PI + 0.2, 0.1, 0.3), Eigen::Vector3d(0.1, -0.05, 1.0));
  }
  Eigen::Vector2d Pixel(double mx, double my) const {
    return camera.Project(Eigen::Vector3d(cam_from_marker * Eigen::Vector3d(mx, my, 0)));
  }
  TestTag AprilTagOrder(int id) const {
    const double h = side / 2;
    const double m[4][2] = {{-h, -h}, {h, -h}, {h, h}, {-h, h}};
    TestTag t{id, {}};
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector2d p = Pixel(m[k][0], m[k][1]);
      t.corners[k][0] = p.x();
      t.corners[k][1] = p.y();
    }
    return t;
  }
};

TEST(ImportBag, DecodesTheSameMessagesFromEveryChunkCompressionAndAWholeFileBz2) {
  TempDir dir("import_bag");
  const std::vector<TestConnection> conns = {
      {"/cam0/tags", "apriltag_msgs/ApriltagArrayStamped", AprilTagDefinition()}};
  std::vector<TestMessage> msgs;
  for (uint32_t i = 0; i < 50; ++i)
    msgs.push_back({0, 100 + i, 5, AprilTagArray(i, 100 + i, 5000, {Tag(3, i), Tag(7, 2 * i)})});
  std::vector<std::string> dumps;
  for (const std::string c : {"none", "bz2", "lz4"}) {
    const std::string path = dir / (c + ".bag");
    import_test::WriteBag(path, conns, msgs, c);
    const RosBag bag = RosBag::Open(path);
    ASSERT_EQ(bag.messages().size(), 50u) << c;
    EXPECT_EQ(bag.chunk_compressions().at(c), 1);
    std::ostringstream dump;
    for (const BagMessage& m : bag.messages()) {
      const RosValue v = bag.Decode(m);
      dump << v.At("header.seq").AsInt() << ' ' << v.At("header.stamp.secs").AsInt() << ' '
           << v.At("header.stamp.nsecs").AsInt() << ' ' << v.At("header.frame_id").text;
      for (const RosValue& t : v.At("apriltags").items)
        dump << ' ' << t.At("id").AsInt() << ' ' << t.At("family").text << ' '
             << t.At("corners").items[2].At("x").AsDouble();
      dump << '\n';
    }
    dumps.push_back(dump.str());
  }
  EXPECT_EQ(dumps[0], dumps[1]);
  EXPECT_EQ(dumps[0], dumps[2]);
  EXPECT_NE(dumps[0].find("49 149 5000 cam 3 tf36h11 69"), std::string::npos) << dumps[0].substr(0, 200);
  // The whole file bzip2-compressed (tag_detections.bag.bz2) opens the same.
  std::ofstream(dir / "whole.bag.bz2", std::ios::binary) << Bz2Compress(test::ReadText(dir / "lz4.bag"));
  EXPECT_EQ(RosBag::Open(dir / "whole.bag.bz2").messages().size(), 50u);
}

TEST(ImportBag, DamageNamesTheFileAndByte) {
  TempDir dir("import_damage");
  const std::string path = dir / "cut.bag";
  import_test::WriteBag(path, {{"/t", "apriltag_msgs/ApriltagArrayStamped", AprilTagDefinition()}},
                        {{0, 1, 0, AprilTagArray(0, 1, 0, {Tag(1, 0)})}}, "none");
  const std::string bytes = test::ReadText(path);
  std::ofstream(path, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  try {
    RosBag::Open(path);
    FAIL() << "a cut bag opened";
  } catch (const BagError& e) {
    EXPECT_NE(std::string(e.what()).find(path + ": byte "), std::string::npos) << e.what();
  }
  std::ofstream(dir / "text.bag") << "hello";
  EXPECT_THROW(RosBag::Open(dir / "text.bag"), BagError);
}

TEST(ImportRosbag, CornersComeOutInArucoOrderAsTheGeometryDemands) {
  TempDir dir("import_corners");
  const Scene scene;
  import_test::WriteBag(dir / "tags.bag",
                        {{"/cam0/tags", "apriltag_msgs/ApriltagArrayStamped", AprilTagDefinition()}},
                        {{0, 10, 0, AprilTagArray(0, 10, 0, {scene.AprilTagOrder(5)})}}, "lz4");
  WriteCameras(dir / "cameras.yaml", {"/cam0/tags"}, "none");
  ImportRosbag({dir / "tags.bag", dir / "cameras.yaml", dir / "session", 0.16, "", ""});
  const std::vector<detections_t> d = ReadSession(dir / "session/session.lcmlog");
  ASSERT_EQ(d.size(), 1u);
  ASSERT_EQ(d[0].num_markers, 1);
  const MarkerCorners3d aruco = MarkerCornersInMarker(scene.side);
  double signed_area = 0;
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector2d expected = scene.Pixel(aruco[k].x(), aruco[k].y());
    EXPECT_NEAR(d[0].markers[0].corners[k][0], expected.x(), 1e-9) << "corner " << k;
    EXPECT_NEAR(d[0].markers[0].corners[k][1], expected.y(), 1e-9) << "corner " << k;
    const auto& a = d[0].markers[0].corners[k];
    const auto& b = d[0].markers[0].corners[(k + 1) % 4];
    signed_area += a[0] * b[1] - b[0] * a[1];
  }
  EXPECT_GT(signed_area, 0) << "ArUco order runs clockwise in the image (y down)";
}

TEST(ImportRosbag, FramesAreGroupedByHeaderStampAcrossCameras) {
  TempDir dir("import_frames");
  const std::string type = "apriltag_msgs/ApriltagArrayStamped";
  // cam1's messages are stored before cam0's and its record times differ: only header stamps count.
  std::vector<TestMessage> msgs = {{1, 50, 0, AprilTagArray(0, 20, 500000000, {Tag(1, 0)})},
                                   {1, 51, 0, AprilTagArray(1, 21, 0, {})},
                                   {0, 52, 0, AprilTagArray(0, 20, 500000000, {Tag(1, 5), Tag(2, 50)})},
                                   {0, 53, 0, AprilTagArray(1, 20, 750000000, {Tag(2, 7)})},
                                   {0, 54, 0, AprilTagArray(2, 21, 0, {Tag(1, 9)})},
                                   {0, 55, 0, AprilTagArray(3, 21, 0, {Tag(1, 9)})}};
  import_test::WriteBag(dir / "tags.bag",
                        {{"/a", type, AprilTagDefinition()}, {"/b", type, AprilTagDefinition()}}, msgs,
                        "bz2");
  WriteCameras(dir / "cameras.yaml", {"/a", "/b"});
  const ImportSummary s =
      ImportRosbag({dir / "tags.bag", dir / "cameras.yaml", dir / "session", 0.1, "", ""});
  EXPECT_EQ(s.frames, 3);
  EXPECT_EQ(s.duplicate_messages, 1);
  EXPECT_EQ(s.dictionary, "DICT_APRILTAG_36h11");
  const std::vector<detections_t> d = ReadSession(dir / "session/session.lcmlog");
  ASSERT_EQ(d.size(), 5u);
  const std::vector<std::tuple<std::string, int64_t, int64_t, int>> expected = {{"cam0", 20500000, 0, 2},
                                                                                {"cam1", 20500000, 0, 1},
                                                                                {"cam0", 20750000, 1, 1},
                                                                                {"cam0", 21000000, 2, 1},
                                                                                {"cam1", 21000000, 2, 0}};
  for (size_t i = 0; i < d.size(); ++i) {
    EXPECT_EQ(d[i].camera, std::get<0>(expected[i])) << i;
    EXPECT_EQ(d[i].utime, std::get<1>(expected[i])) << i;
    EXPECT_EQ(d[i].seq, std::get<2>(expected[i])) << i;
    EXPECT_EQ(d[i].num_markers, std::get<3>(expected[i])) << i;
  }
  EXPECT_EQ(d[0].camera_model.distortion_model, "fisheye");
  // The session's rig loads as mcmt reads rigs.
  const RigConfig rig = LoadRigConfig(dir / "session/rig.yaml");
  ASSERT_EQ(rig.cameras.size(), 2u);
  EXPECT_EQ(rig.cameras[1].model.model, DistortionModel::kFisheye);
  EXPECT_DOUBLE_EQ(rig.cameras[1].model.distortion[2], 0.0121);
  EXPECT_DOUBLE_EQ(rig.markers.size, 0.1);
  EXPECT_EQ(rig.markers.dictionary, "DICT_APRILTAG_36h11");
  EXPECT_EQ(rig.mapper.GetString("reference_camera", ""), "cam0");
  // Never overwritten.
  try {
    ImportRosbag({dir / "tags.bag", dir / "cameras.yaml", dir / "session", 0.1, "", ""});
    FAIL() << "overwrote a session";
  } catch (const ImportError& e) {
    EXPECT_NE(std::string(e.what()).find("session.lcmlog: exists"), std::string::npos) << e.what();
  }
}

TEST(ImportRosbag, UnknownTypesAndTopicsAreListedNotGuessed) {
  TempDir dir("import_unknown");
  import_test::WriteBag(dir / "tags.bag",
                        {{"/cam0/tags", "apriltag_ros/AprilTagDetectionArray",
                          "std_msgs/Header header\n"
                          "====\nMSG: std_msgs/Header\nuint32 seq\ntime stamp\nstring frame_id\n"},
                         {"/imu", "sensor_msgs/Imu", "float64 x\n"}},
                        {}, "none");
  WriteCameras(dir / "cameras.yaml", {"/cam0/tags"});
  auto error_of = [&](const std::string& cameras) {
    try {
      ImportRosbag({dir / "tags.bag", cameras, dir / "out", 0.1, "", ""});
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string wrong_type = error_of(dir / "cameras.yaml");
  EXPECT_NE(wrong_type.find("topic /cam0/tags (cam0) has type apriltag_ros/AprilTagDetectionArray"),
            std::string::npos)
      << wrong_type;
  EXPECT_NE(wrong_type.find(
                "topics found: /cam0/tags (apriltag_ros/AprilTagDetectionArray), /imu (sensor_msgs/Imu)"),
            std::string::npos)
      << wrong_type;
  WriteCameras(dir / "other.yaml", {"/left/tags"});
  const std::string missing = error_of(dir / "other.yaml");
  EXPECT_NE(missing.find("no topic /left/tags (" + dir / "other.yaml" +
                         ": cam0.tagtopic); topics found: /cam0/tags"),
            std::string::npos)
      << missing;
  EXPECT_FALSE(std::filesystem::exists(dir / "out")) << "nothing written on failure";
  // A definition whose fields are not where apriltag_msgs has them.
  import_test::WriteBag(
      dir / "odd.bag",
      {{"/cam0/tags", "apriltag_msgs/ApriltagArrayStamped",
        "std_msgs/Header header\nApriltag[] apriltags\n====\nMSG: std_msgs/Header\nuint32 seq\n"
        "time stamp\nstring frame_id\n====\nMSG: apriltag_msgs/Apriltag\nint32 id\n"
        "geometry_msgs/Point[] corners\n====\nMSG: geometry_msgs/Point\nfloat64 x\nfloat64 y\n"}},
      {}, "none");
  try {
    ImportRosbag({dir / "odd.bag", dir / "cameras.yaml", dir / "out2", 0.1, "", ""});
    FAIL();
  } catch (const ImportError& e) {
    EXPECT_NE(std::string(e.what()).find("apriltag_msgs/Apriltag.corners is not a [4] array"),
              std::string::npos)
        << e.what();
  }
}

TEST(ImportKalibr, ReadsRadtanAndEquidistantAndNamesBadKeys) {
  TempDir dir("import_kalibr");
  WriteCameras(dir / "equi.yaml", {"/a", "/b"});
  const std::vector<KalibrCamera> equi = LoadKalibrCameras(dir / "equi.yaml");
  ASSERT_EQ(equi.size(), 2u);
  EXPECT_EQ(equi[1].name, "cam1");
  EXPECT_EQ(equi[1].topic, "/b");
  EXPECT_EQ(equi[0].model.model, DistortionModel::kFisheye);
  EXPECT_DOUBLE_EQ(equi[0].model.fy, 470.5);
  EXPECT_EQ(equi[0].model.height, 1024);
  WriteCameras(dir / "radtan.yaml", {"/a"}, "radtan");
  EXPECT_EQ(LoadKalibrCameras(dir / "radtan.yaml")[0].model.model, DistortionModel::kRadTan);
  WriteCameras(dir / "fov.yaml", {"/a", "/b"}, "fov");
  try {
    LoadKalibrCameras(dir / "fov.yaml");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("fov.yaml: cam0.distortion_model: 'fov' is not supported"),
              std::string::npos)
        << e.what();
  }
  std::ofstream(dir / "short.yaml")
      << "cam0:\n  intrinsics: [1, 2, 3]\n  resolution: [10, 10]\n  tagtopic: /a\n";
  try {
    LoadKalibrCameras(dir / "short.yaml");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(
        std::string(e.what()).find("short.yaml: cam0.intrinsics: expected [fx, fy, cx, cy], got 3 values"),
        std::string::npos)
        << e.what();
  }
  std::ofstream(dir / "tagslam.yaml") << "default_body: perch\nbodies:\n - perch:\n     default_tag_size: "
                                         "0.125\n     tags:\n       - id: 10\n"
                                         "         size: 0.2\n - rig:\n     is_static: false\n";
  const TagSizes t = LoadTagslamSizes(dir / "tagslam.yaml");
  EXPECT_DOUBLE_EQ(t.default_size, 0.125);
  EXPECT_DOUBLE_EQ(t.sizes.at(10), 0.2);
  EXPECT_EQ(DictionaryForFamily("tf36h11"), "DICT_APRILTAG_36h11");
  EXPECT_EQ(DictionaryForFamily("tag16h5"), "DICT_APRILTAG_16h5");
  EXPECT_EQ(DictionaryForFamily("mit"), "DICT_APRILTAG_36h11");
  EXPECT_EQ(DictionaryForFamily("circle21h7"), "");
}

TEST(ImportCsv, MakesASessionTheRigReadsBack) {
  TempDir dir("import_csv");
  CameraModel m = CameraModel::Pinhole(640, 480, 500, 320, 240);
  std::filesystem::create_directories(dir / "calib");
  WriteIntrinsicsOpenCv(dir / "calib/c.yml", m);
  std::ofstream(dir / "rig.yaml") << "markers:\n  dictionary: DICT_4X4_50\n  size: 0.05\ncameras:\n"
                                     "  - name: left\n    intrinsics: calib/c.yml\n    source: left/\n"
                                     "mapper:\n  huber_px: 2.0\n";
  std::ofstream(dir / "det.csv") << "utime,seq,camera,id,x0,y0,x1,y1,x2,y2,x3,y3\n"
                                    "1000,0,left,3,10,10,20,10,20,20,10,20\n"
                                    "1000,0,left,4,30,10,40,10,40,20,30,20\n"
                                    "2000,1,left,3,11,10,21,10,21,20,11,20\n";
  const ImportSummary s = ImportCsv(dir / "det.csv", dir / "rig.yaml", dir / "session");
  const std::vector<detections_t> d = ReadSession(dir / "session/session.lcmlog");
  ASSERT_EQ(d.size(), 2u);
  EXPECT_EQ(d[0].num_markers, 2);
  EXPECT_EQ(d[1].markers[0].corners[1][0], 21);
  const RigConfig rig = LoadRigConfig(dir / "session/rig.yaml");
  EXPECT_EQ(rig.cameras[0].intrinsics_path, dir / "session/left.yml");
  EXPECT_TRUE(rig.cameras[0].model == m);
  EXPECT_EQ(rig.cameras[0].source, "");
  EXPECT_DOUBLE_EQ(YamlSection(rig.mapper).GetDouble("huber_px", 0), 2.0);
  std::ofstream(dir / "bad.csv")
      << "utime,seq,camera,id,x0,y0,x1,y1,x2,y2,x3,y3\n1000,0,left,x,1,2,3,4,5,6,7,8\n";
  try {
    ImportCsv(dir / "bad.csv", dir / "rig.yaml", dir / "bad");
    FAIL();
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("bad.csv:2: id: expected an integer, got 'x'"), std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "bad"));
}

TEST(ImportProcess, BadInputGivesOneLineAndANonZeroExit) {
  TempDir dir("import_cli");
  const std::string bin = MCMT_BIN_DIR "/mcmt-import";
  std::string out;
  EXPECT_EQ(test::RunProgram({bin, "--rosbag", dir / "x.bag", "--out", dir / "s"}, dir / "1.txt", &out), 2);
  EXPECT_EQ(out, "mcmt-import: error: --rosbag needs --cameras cameras.yaml\n");
  std::ofstream(dir / "x.bag") << "not a bag";
  WriteCameras(dir / "cameras.yaml", {"/a"});
  EXPECT_EQ(test::RunProgram({bin, "--rosbag", dir / "x.bag", "--cameras", dir / "cameras.yaml", "--tag-size",
                              "0.1", "--out", dir / "s"},
                             dir / "2.txt", &out),
            1);
  EXPECT_EQ(out, "mcmt-import: error: " + dir / "x.bag" + ": not a ROS bag (no '#ROSBAG V2.0' line)\n");
  EXPECT_FALSE(std::filesystem::exists(dir / "s"));
  import_test::WriteBag(dir / "ok.bag", {{"/a", "apriltag_msgs/ApriltagArrayStamped", AprilTagDefinition()}},
                        {{0, 1, 0, AprilTagArray(0, 1, 0, {Tag(4, 0)})}}, "bz2");
  EXPECT_EQ(test::RunProgram({bin, "--rosbag", dir / "ok.bag", "--cameras", dir / "cameras.yaml",
                              "--tag-size", "0.1", "--out", dir / "s"},
                             dir / "3.txt", &out),
            0)
      << out;
  EXPECT_NE(out.find("cam0: /a, 1 messages, 1 tags"), std::string::npos) << out;
  EXPECT_TRUE(std::filesystem::exists(dir / "s/session.lcmlog"));
  EXPECT_TRUE(std::filesystem::exists(dir / "s/cam0.yml"));
}

}  // namespace
}  // namespace mcmt
