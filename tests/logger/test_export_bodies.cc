// mcmt-export on maps, logs and mapper folders with several rigid bodies (issue 16): one PLY / OBJ per
// body, every body in the ROS and OpenCV exports, one TUM / poses file per moving body; a single-object map
// keeps today's names. The files written are read back and compared numerically.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <map>
#include <opencv2/core.hpp>
#include <random>
#include <sstream>

#include "core/files.h"
#include "core/lcm_util.h"
#include "core/log_writer.h"
#include "core/map_export.h"
#include "core/marker.h"
#include "core/se3.h"
#include "logger/export.h"
#include "test_util.h"

using namespace mcmt;
using namespace mcmt_test;

namespace {

Rigid3 SomeRigid(std::mt19937_64& rng, double scale) {
  std::uniform_real_distribution<double> u(-1, 1);
  Rigid3 t = Rigid3::Identity();
  t.linear() =
      Eigen::AngleAxisd(u(rng) * 3, Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized()).toRotationMatrix();
  t.translation() = scale * Eigen::Vector3d(u(rng), u(rng), u(rng));
  return t;
}

// tool (ids 0-3, moving), patient (10-15, moving), floor (20-27, static, 8 cm).
RigMap BodiesMap() {
  std::mt19937_64 rng(16);
  RigMap map;
  map.dictionary = "DICT_6X6_250";
  map.reference_camera = "cam0";
  for (int i = 0; i < 2; ++i) {
    MapCamera c;
    c.name = "cam" + std::to_string(i);
    c.model = CameraModel::Pinhole(640, 480, 500, 320, 240);
    c.rig_from_cam = i == 0 ? Rigid3::Identity() : SomeRigid(rng, 1.0);
    map.cameras.push_back(c);
  }
  auto body = [&](const std::string& name, int first, int count, double size, bool is_static) {
    MapObject o;
    o.name = name;
    o.is_static = is_static;
    o.reference_marker = first;
    for (int k = 0; k < count; ++k) {
      MapMarker m;
      m.id = first + k;
      m.size = size;
      m.object_from_marker = k == 0 ? Rigid3::Identity() : SomeRigid(rng, 0.1);
      o.markers.push_back(m);
    }
    if (is_static) o.rig_from_object = SomeRigid(rng, 0.5);
    map.objects.push_back(o);
  };
  body("tool", 0, 4, 0.04, false);
  body("patient", 10, 6, 0.05, false);
  body("floor", 20, 8, 0.08, true);
  map.rig_frame = "floor";
  map.markers = map.objects[0].markers;
  map.reference_marker = 0;
  return map;
}

// PLY vertices and faces (with marker ids).
struct Ply {
  std::string comment;
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<int, 5>> faces;  // 4 indices + id
};
Ply ReadPly(const std::string& path) {
  std::istringstream in(ReadText(path));
  Ply ply;
  std::string line;
  int vertices = 0, faces = 0;
  while (std::getline(in, line) && line != "end_header") {
    if (line.rfind("element vertex", 0) == 0) vertices = std::stoi(line.substr(15));
    if (line.rfind("element face", 0) == 0) faces = std::stoi(line.substr(13));
    if (line.rfind("comment", 0) == 0) ply.comment = line;
  }
  ply.vertices.resize(vertices);
  for (auto& p : ply.vertices) in >> p.x() >> p.y() >> p.z();
  for (int f = 0; f < faces; ++f) {
    int n;
    std::array<int, 5> face;
    in >> n >> face[0] >> face[1] >> face[2] >> face[3] >> face[4];
    EXPECT_EQ(n, 4);
    ply.faces.push_back(face);
  }
  return ply;
}

// Every marker of `markers` is a face of the PLY whose 4 vertices are its corners in the body's frame,
// wound so that the normal is the marker's +z.
void ExpectLayout(const Ply& ply, const std::vector<MapMarker>& markers, const std::string& what) {
  ASSERT_EQ(ply.faces.size(), markers.size()) << what;
  for (size_t i = 0; i < markers.size(); ++i) {
    const MapMarker& m = markers[i];
    const auto& f = ply.faces[i];
    EXPECT_EQ(f[4], m.id) << what;
    const MarkerCorners3d c = MarkerCornersInMarker(m.size);
    // Face order BL, BR, TR, TL = corners 3, 2, 1, 0.
    for (int k = 0; k < 4; ++k)
      EXPECT_LT((ply.vertices.at(f[k]) - m.object_from_marker * c[3 - k]).norm(), 1e-15)
          << what << " " << m.id;
    const Eigen::Vector3d normal =
        (ply.vertices[f[1]] - ply.vertices[f[0]]).cross(ply.vertices[f[2]] - ply.vertices[f[0]]).normalized();
    EXPECT_GT(normal.dot(m.object_from_marker.linear().col(2)), 0.999999) << what;
  }
}

// OBJ vertices.
std::vector<Eigen::Vector3d> ObjVertices(const std::string& path, int* faces) {
  std::istringstream in(ReadText(path));
  std::vector<Eigen::Vector3d> out;
  std::string line;
  *faces = 0;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    std::string tag;
    s >> tag;
    if (tag == "v") {
      Eigen::Vector3d p;
      s >> p.x() >> p.y() >> p.z();
      out.push_back(p);
    }
    if (tag == "f") ++*faces;
  }
  return out;
}

struct TumRow {
  double t;
  Eigen::Vector3d p;
  Eigen::Vector4d q_xyzw;
};
std::vector<TumRow> ReadTum(const std::string& path) {
  std::istringstream in(ReadText(path));
  std::vector<TumRow> rows;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream s(line);
    TumRow r;
    s >> r.t >> r.p.x() >> r.p.y() >> r.p.z() >> r.q_xyzw[0] >> r.q_xyzw[1] >> r.q_xyzw[2] >> r.q_xyzw[3];
    EXPECT_TRUE(static_cast<bool>(s)) << path << ": " << line;
    rows.push_back(r);
  }
  return rows;
}

// The pose of body b at frame seq (distinct per body).
Rigid3 BodyPose(int b, int64_t seq) {
  Rigid3 t = Rigid3::Identity();
  t.linear() = Eigen::AngleAxisd(0.02 * seq + b, Eigen::Vector3d(b, 1, 0.5).normalized()).toRotationMatrix();
  t.translation() = Eigen::Vector3d(0.1 * b + 0.01 * seq, -0.3 * b, 1.0 + 0.001 * seq);
  return t;
}

class ExportBodies : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = MakeTempDir("bodies"); }
  void TearDown() override { RemoveTree(dir_); }
  std::string dir_;
};

}  // namespace

TEST(ExportBodiesNames, BodyPathPutsTheBodyBeforeTheExtension) {
  EXPECT_EQ(BodyPath("out/layout.ply", "tool"), "out/layout_tool.ply");
  EXPECT_EQ(BodyPath("poses.tum", "patient"), "poses_patient.tum");
  EXPECT_EQ(BodyPath("out.d/layout", "tool"), "out.d/layout_tool");
  EXPECT_EQ(BodyPath("/tmp/a.b/poses.csv", "x_1"), "/tmp/a.b/poses_x_1.csv");
}

TEST_F(ExportBodies, PlyAndObjOneFilePerBodyInItsOwnFrame) {
  const RigMap map = BodiesMap();
  const std::string map_yaml = dir_ + "/map.yaml";
  WriteMap(map_yaml, map);
  std::string out, err;
  ASSERT_EQ(RunProgram({Bin("mcmt-export"), "--map", map_yaml, "--ply", dir_ + "/layout.ply", "--obj",
                        dir_ + "/layout.obj"},
                       &out, &err),
            0)
      << err;
  EXPECT_FALSE(FileExists(dir_ + "/layout.ply"));  // no file for "the" object of a map with several
  for (const MapObject& o : map.objects) {
    const Ply ply = ReadPly(dir_ + "/layout_" + o.name + ".ply");
    EXPECT_NE(ply.comment.find(o.name), std::string::npos) << ply.comment;
    ASSERT_EQ(ply.vertices.size(), 4 * o.markers.size()) << o.name;
    ExpectLayout(ply, o.markers, o.name);
    // The OBJ holds the same vertices (same order), one face per marker.
    int faces = 0;
    const auto obj = ObjVertices(dir_ + "/layout_" + o.name + ".obj", &faces);
    EXPECT_EQ(faces, static_cast<int>(o.markers.size()));
    ASSERT_EQ(obj.size(), ply.vertices.size());
    for (size_t i = 0; i < obj.size(); ++i) EXPECT_EQ(obj[i], ply.vertices[i]) << o.name;
  }
  // The floor's 8 cm markers: side lengths of its faces.
  const Ply floor = ReadPly(dir_ + "/layout_floor.ply");
  for (const auto& f : floor.faces)
    EXPECT_NEAR((floor.vertices[f[1]] - floor.vertices[f[0]]).norm(), 0.08, 1e-12);
}

TEST_F(ExportBodies, ASingleObjectMapKeepsTheAskedName) {
  RigMap map = BodiesMap();
  map.objects.resize(1);  // version 2 with one body
  map.rig_frame.clear();
  const std::string v2 = dir_ + "/one.yaml";
  WriteMap(v2, map);
  RigMap v1 = map;
  v1.objects.clear();
  v1.rig_frame.clear();
  const std::string v1_path = dir_ + "/v1.yaml";
  WriteMap(v1_path, v1);
  for (const std::string& path : {v2, v1_path}) {
    std::string out, err;
    ASSERT_EQ(RunProgram({Bin("mcmt-export"), "--map", path, "--ply", dir_ + "/object.ply"}, &out, &err), 0)
        << err;
    ExpectLayout(ReadPly(dir_ + "/object.ply"), map.objects[0].markers, path);
    EXPECT_FALSE(FileExists(dir_ + "/object_tool.ply"));
  }
}

TEST_F(ExportBodies, ABodyWithoutMarkersIsRefusedAndNoLayoutWritten) {
  RigMap map = BodiesMap();
  map.objects[1].markers.clear();
  const std::string map_yaml = dir_ + "/map.yaml";
  WriteMap(map_yaml, map);
  std::string out, err;
  EXPECT_EQ(RunProgram({Bin("mcmt-export"), "--map", map_yaml, "--ply", dir_ + "/layout.ply", "--opencv",
                        dir_ + "/map.yml"},
                       &out, &err),
            1);
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  EXPECT_NE(err.find("--ply " + dir_ + "/layout.ply: not written: PLY: body 'patient' has no marker"),
            std::string::npos)
      << err;
  EXPECT_FALSE(FileExists(dir_ + "/layout_tool.ply"));  // refused before the first file
  EXPECT_TRUE(FileExists(dir_ + "/map.yml"));           // the other output still written
}

TEST_F(ExportBodies, RosAndOpenCvHoldEveryBody) {
  const RigMap map = BodiesMap();
  WriteRosDir(map, dir_ + "/ros");
  const YAML::Node st = YAML::LoadFile(dir_ + "/ros/static_transforms.yaml");
  std::map<std::string, std::pair<std::string, Rigid3>> got;  // child -> parent, pose
  for (const YAML::Node& t : st["transforms"]) {
    const Eigen::Vector3d p(t["translation"][0].as<double>(), t["translation"][1].as<double>(),
                            t["translation"][2].as<double>());
    const std::array<double, 4> wxyz = {
        t["rotation_xyzw"][3].as<double>(), t["rotation_xyzw"][0].as<double>(),
        t["rotation_xyzw"][1].as<double>(), t["rotation_xyzw"][2].as<double>()};
    got[t["child_frame_id"].as<std::string>()] = {t["frame_id"].as<std::string>(),
                                                  RigidFromQuaternion(wxyz, p)};
  }
  EXPECT_EQ(got.size(), 2u + 4u + 6u + 8u + 1u);  // cameras, markers of the 3 bodies, rig -> floor
  auto expect = [&](const std::string& child, const std::string& parent, const Rigid3& pose) {
    ASSERT_TRUE(got.count(child)) << child;
    EXPECT_EQ(got[child].first, parent) << child;
    EXPECT_LT(TranslationDistance(got[child].second, pose), 1e-12) << child;
    EXPECT_LT(RotationAngle(got[child].second, pose), 1e-9) << child;
  };
  expect("floor", "mcmt_rig", map.objects[2].rig_from_object);
  EXPECT_FALSE(got.count("tool"));  // moving: dynamic, not a static transform
  for (const MapObject& o : map.objects)
    for (const MapMarker& m : o.markers)
      expect(o.name + "_marker_" + std::to_string(m.id), o.name, m.object_from_marker);
  ASSERT_EQ(st["objects"].size(), 3u);
  EXPECT_EQ(st["objects"][2]["frame"].as<std::string>(), "floor");
  EXPECT_TRUE(st["objects"][2]["static"].as<bool>());

  WriteFileAtomic(dir_ + "/map.yml", OpenCvMapYaml(map));
  cv::FileStorage fs(dir_ + "/map.yml", cv::FileStorage::READ);
  cv::FileNode objects = fs["objects"];
  ASSERT_EQ(objects.size(), 3u);
  for (int k = 0; k < 3; ++k) {
    const MapObject& o = map.objects[k];
    EXPECT_EQ(static_cast<std::string>(objects[k]["name"]), o.name);
    EXPECT_EQ(static_cast<int>(objects[k]["static"]), o.is_static ? 1 : 0);
    cv::FileNode markers = objects[k]["markers"];
    ASSERT_EQ(markers.size(), o.markers.size());
    for (size_t i = 0; i < o.markers.size(); ++i) {
      cv::Mat t;
      markers[static_cast<int>(i)]["object_from_marker"] >> t;
      for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c)
          EXPECT_EQ(t.at<double>(r, c), o.markers[i].object_from_marker.matrix()(r, c));
    }
    if (o.is_static) {
      cv::Mat t;
      objects[k]["rig_from_object"] >> t;
      EXPECT_EQ(t.at<double>(2, 3), o.rig_from_object.translation().z());
    }
  }
}

// A log of the tracker with per-body channels (MCMT_POSE_TOOL, MCMT_POSE_PATIENT and the relative
// MCMT_POSE_TOOL_IN_PATIENT): one TUM and one poses CSV per channel, the numbers of the messages.
TEST_F(ExportBodies, TumPerBodyChannelFromALog) {
  const std::string log = dir_ + "/bodies.lcmlog";
  const std::vector<std::pair<std::string, std::string>> channels = {
      {"MCMT_POSE_TOOL", "tool"}, {"MCMT_POSE_PATIENT", "patient"}, {"MCMT_POSE_TOOL_IN_PATIENT", "tool"}};
  {
    EventLogWriter w(log);
    for (int64_t seq = 0; seq < 10; ++seq)
      for (size_t b = 0; b < channels.size(); ++b) {
        object_pose_t p =
            MakePose(seq, seq == 7 && b == 1 ? object_pose_t::STATUS_LOST : object_pose_t::STATUS_TRACKING);
        p.object = channels[b].second;
        const Rigid3 pose = BodyPose(static_cast<int>(b), seq);
        p.rig_from_object = ToPose3d(pose);
        const std::vector<uint8_t> data = Encode(p);
        w.Write(p.utime + 100, channels[b].first, data.data(), data.size());
      }
    w.Close();
  }
  std::string out, err;
  ASSERT_EQ(RunProgram({Bin("mcmt-export"), "--log", log, "--tum", dir_ + "/poses.tum", "--poses",
                        dir_ + "/poses.csv"},
                       &out, &err),
            0)
      << err;
  EXPECT_FALSE(FileExists(dir_ + "/poses.tum"));
  EXPECT_NE(err.find("body patient (MCMT_POSE_PATIENT): 9 poses (1 lost skipped)"), std::string::npos) << err;
  const std::vector<std::string> names = {"tool", "patient", "tool_in_patient"};
  for (size_t b = 0; b < names.size(); ++b) {
    const auto tum = ReadTum(dir_ + "/poses_" + names[b] + ".tum");
    const auto csv = ReadTrajectory(dir_ + "/poses_" + names[b] + ".csv");
    ASSERT_EQ(tum.size(), b == 1 ? 9u : 10u) << names[b];
    ASSERT_EQ(csv.size(), tum.size());
    for (size_t i = 0; i < tum.size(); ++i) {
      const Rigid3 truth = BodyPose(static_cast<int>(b), csv[i].seq);
      EXPECT_NEAR(tum[i].t, 1e-6 * static_cast<double>(csv[i].utime), 1e-6);
      EXPECT_LT((tum[i].p - truth.translation()).norm(), 1e-15) << names[b];
      const std::array<double, 4> q = {tum[i].q_xyzw[3], tum[i].q_xyzw[0], tum[i].q_xyzw[1],
                                       tum[i].q_xyzw[2]};
      EXPECT_LT(RotationAngle(RigidFromQuaternion(q, tum[i].p), truth), 1e-9) << names[b];
      EXPECT_LT(TranslationDistance(csv[i].rig_from_object, truth), 1e-15);
    }
  }
}

// A stream renamed by tracker.channels ({tool: NAV}): found by its type, the file named by the message's
// object field (poses_tool.csv), the numbers of the messages.
TEST_F(ExportBodies, RenamedPoseChannelIsExportedUnderItsBody) {
  const std::string log = dir_ + "/renamed.lcmlog";
  {
    EventLogWriter w(log);
    for (int64_t seq = 0; seq < 5; ++seq)
      for (int b = 0; b < 2; ++b) {
        object_pose_t p = MakePose(seq, object_pose_t::STATUS_TRACKING);
        p.object = b == 0 ? "tool" : "patient";
        p.rig_from_object = ToPose3d(BodyPose(b, seq));
        const std::vector<uint8_t> data = Encode(p);
        w.Write(p.utime + 100, b == 0 ? "NAV" : "MCMT_POSE_PATIENT", data.data(), data.size());
      }
    w.Close();
  }
  std::string out, err;
  ASSERT_EQ(RunProgram({Bin("mcmt-export"), "--log", log, "--poses", dir_ + "/poses.csv"}, &out, &err), 0)
      << err;
  for (int b = 0; b < 2; ++b) {
    const auto csv = ReadTrajectory(dir_ + (b == 0 ? "/poses_tool.csv" : "/poses_patient.csv"));
    ASSERT_EQ(csv.size(), 5u) << b;
    for (const TrajectoryRow& row : csv)
      EXPECT_LT(TranslationDistance(row.rig_from_object, BodyPose(b, row.seq)), 1e-15);
  }
  EXPECT_FALSE(FileExists(dir_ + "/poses_nav.csv"));
}

// The mapper's OUTDIR of a map with several bodies: --trajectory OUTDIR writes one TUM per moving body
// (the static floor has none); a single-object OUTDIR keeps trajectory.csv -> the asked name.
TEST_F(ExportBodies, TumPerMovingBodyFromAMapperFolder) {
  const RigMap map = BodiesMap();
  const std::string outdir = dir_ + "/out";
  ASSERT_EQ(std::system(("mkdir -p " + outdir).c_str()), 0);
  WriteMap(outdir + "/map.yaml", map);
  for (int b = 0; b < 2; ++b) {
    std::vector<TrajectoryRow> rows;
    for (int64_t seq = 0; seq < 5 + b; ++seq) {
      TrajectoryRow r;
      r.seq = seq;
      r.utime = 1700000000000000 + seq * 33333;
      r.rig_from_object = BodyPose(b, seq);
      rows.push_back(r);
    }
    WriteTrajectory(outdir + "/trajectory_" + map.objects[b].name + ".csv", rows);
  }
  std::string out, err;
  ASSERT_EQ(RunProgram({Bin("mcmt-export"), "--trajectory", outdir, "--tum", dir_ + "/t.tum"}, &out, &err), 0)
      << err;
  for (int b = 0; b < 2; ++b) {
    const auto tum = ReadTum(dir_ + "/t_" + map.objects[b].name + ".tum");
    ASSERT_EQ(tum.size(), 5u + b);
    for (size_t i = 0; i < tum.size(); ++i)
      EXPECT_LT((tum[i].p - BodyPose(b, static_cast<int64_t>(i)).translation()).norm(), 1e-15);
  }
  EXPECT_FALSE(FileExists(dir_ + "/t_floor.tum"));
  EXPECT_FALSE(FileExists(dir_ + "/t.tum"));
  // A missing body trajectory is named.
  std::remove((outdir + "/trajectory_patient.csv").c_str());
  EXPECT_EQ(RunProgram({Bin("mcmt-export"), "--trajectory", outdir, "--tum", dir_ + "/u.tum"}, &out, &err),
            1);
  EXPECT_NE(err.find(outdir + "/trajectory_patient.csv: no such trajectory"), std::string::npos) << err;
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
}

// mcmt-mapper publishes rig_map2_t on MCMT_MAP: a log of it exports every body, and --summary names the
// type and counts the map (an older log's rig_map_t still reads: test_logger_unit).
TEST_F(ExportBodies, TheMapOfALogWithRigMap2HasEveryBody) {
  const RigMap map = BodiesMap();
  const std::string log = dir_ + "/map.lcmlog";
  {
    EventLogWriter w(log);
    const std::vector<uint8_t> data = Encode(ToRigMap2Msg(map, 5));
    w.Write(5, kMapChannel, data.data(), data.size());
    w.Close();
  }
  std::string out, err;
  ASSERT_EQ(RunProgram({Bin("mcmt-export"), "--map", log, "--ply", dir_ + "/layout.ply"}, &out, &err), 0)
      << err;
  for (const MapObject& o : map.objects)
    ExpectLayout(ReadPly(dir_ + "/layout_" + o.name + ".ply"), o.markers, o.name);
  ASSERT_EQ(RunProgram({Bin("mcmt-export"), "--summary", log}, &out, &err), 0) << err;
  EXPECT_NE(out.find("mcmt.rig_map2_t"), std::string::npos) << out;
  EXPECT_NE(out.find("maps: 1"), std::string::npos) << out;
  EXPECT_EQ(out.find("do not decode"), std::string::npos) << out;
}
