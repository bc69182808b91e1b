#include <gtest/gtest.h>

#include <random>

#include "core/files.h"
#include "core/map_covariance.h"
#include "test_util.h"

namespace mcmt {
namespace {

using testing_util::Replace;
using testing_util::TempDir;

bool SameRigid(const Rigid3& a, const Rigid3& b) { return a.matrix() == b.matrix(); }

void ExpectSameMap(const RigMap& a, const RigMap& b) {
  EXPECT_EQ(a.version, b.version);
  EXPECT_EQ(a.dictionary, b.dictionary);
  EXPECT_EQ(a.reference_camera, b.reference_camera);
  EXPECT_EQ(a.reference_marker, b.reference_marker);
  EXPECT_EQ(a.rms_px, b.rms_px);
  EXPECT_EQ(a.num_frames, b.num_frames);
  EXPECT_EQ(a.num_observations, b.num_observations);
  EXPECT_EQ(a.time_reference_utime, b.time_reference_utime);
  ASSERT_EQ(a.cameras.size(), b.cameras.size());
  for (size_t i = 0; i < a.cameras.size(); ++i) {
    EXPECT_EQ(a.cameras[i].name, b.cameras[i].name);
    EXPECT_TRUE(a.cameras[i].model == b.cameras[i].model) << i;
    EXPECT_TRUE(SameRigid(a.cameras[i].rig_from_cam, b.cameras[i].rig_from_cam))
        << a.cameras[i].rig_from_cam.matrix() << "\n"
        << b.cameras[i].rig_from_cam.matrix();
    EXPECT_EQ(a.cameras[i].observations, b.cameras[i].observations);
    EXPECT_EQ(a.cameras[i].rms_px, b.cameras[i].rms_px);
    EXPECT_EQ(a.cameras[i].max_px, b.cameras[i].max_px);
    EXPECT_EQ(a.cameras[i].time_offset_us, b.cameras[i].time_offset_us);
    EXPECT_EQ(a.cameras[i].time_drift_ppm, b.cameras[i].time_drift_ppm);
  }
  ASSERT_EQ(a.markers.size(), b.markers.size());
  for (size_t i = 0; i < a.markers.size(); ++i) {
    EXPECT_EQ(a.markers[i].id, b.markers[i].id);
    EXPECT_EQ(a.markers[i].size, b.markers[i].size);
    EXPECT_TRUE(SameRigid(a.markers[i].object_from_marker, b.markers[i].object_from_marker));
    EXPECT_EQ(a.markers[i].observations, b.markers[i].observations);
    EXPECT_EQ(a.markers[i].rms_px, b.markers[i].rms_px);
    EXPECT_EQ(a.markers[i].max_px, b.markers[i].max_px);
  }
}

RigMap RandomMap(uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  RigMap map;
  map.dictionary = "DICT_6X6_250";
  map.reference_camera = "cam 1 \"front\"";
  map.reference_marker = 3;
  map.rms_px = u(rng);
  map.num_frames = 1234;
  map.num_observations = 98765;
  for (int i = 0; i < 5; ++i) {
    MapCamera c;
    c.name = i == 1 ? map.reference_camera : "cam" + std::to_string(i);
    c.model.width = 640 + i;
    c.model.height = 480;
    c.model.fx = 500 + u(rng);
    c.model.fy = 500 + u(rng);
    c.model.cx = 320 + u(rng);
    c.model.cy = 240 + u(rng);
    if (i % 3 == 0) {
      c.model.model = DistortionModel::kRadTan;
      c.model.distortion = {u(rng) - 0.5, u(rng) * 1e-3, -u(rng) * 1e-5, 1e-300, u(rng)};
    } else if (i % 3 == 1) {
      c.model.model = DistortionModel::kFisheye;
      c.model.distortion = {u(rng), u(rng), u(rng), u(rng)};
    }
    c.rig_from_cam = i == 1 ? Rigid3::Identity() : RandomRigid(rng, 3.0);
    c.observations = 100 * i;
    c.rms_px = u(rng);
    c.max_px = 10 * u(rng);
    if (i == 2) {  // a clock that is off and drifts (issue 18)
      c.time_offset_us = -20000 * u(rng);
      c.time_drift_ppm = 300 * u(rng);
      map.time_reference_utime = 1000000005000000LL + static_cast<int64_t>(seed);
    }
    map.cameras.push_back(c);
  }
  for (int id : {3, 0, 17, 249}) {
    MapMarker m;
    m.id = id;
    m.size = 0.04 + 0.001 * u(rng);
    m.object_from_marker = id == 3 ? Rigid3::Identity() : RandomRigid(rng, 0.2);
    m.observations = id * 7;
    m.rms_px = u(rng);
    m.max_px = u(rng) * 3;
    map.markers.push_back(m);
  }
  return map;
}

TEST(Files, MapRoundTripsExactly) {
  TempDir dir;
  for (uint64_t seed : {1, 2, 3}) {
    const RigMap map = RandomMap(seed);
    const std::string path = dir.File("map.yaml");
    WriteMap(path, map);
    const RigMap back = ReadMap(path);
    ExpectSameMap(map, back);
    // Writing what was read gives the same bytes.
    const std::string first = ReadFile(path);
    WriteMap(dir.File("map2.yaml"), back);
    EXPECT_EQ(first, ReadFile(dir.File("map2.yaml")));
    EXPECT_EQ(back.FindCamera("cam2"), &back.cameras[2]);
    EXPECT_EQ(back.FindMarker(17), &back.markers[2]);
    EXPECT_EQ(back.FindMarker(18), nullptr);
  }
  // An empty map.
  RigMap empty;
  WriteMap(dir.File("empty.yaml"), empty);
  ExpectSameMap(empty, ReadMap(dir.File("empty.yaml")));
}

// map.yaml's optional covariance (core/map_covariance.h): written after the map, read back to 9 significant
// digits; the map itself reads as without it; a map without the key has none; a malformed one is refused
// naming the key.
TEST(Files, MapCovarianceRoundTripsAndIsOptional) {
  TempDir dir;
  const RigMap map = RandomMap(4);
  MapCovariance c;
  c.cameras = {"cam1", "cam \"2\""};
  c.markers = {17};
  std::mt19937_64 rng(3);
  std::normal_distribution<double> normal(0.0, 1e-4);
  Eigen::MatrixXd l(18, 18);
  for (int r = 0; r < 18; ++r)
    for (int k = 0; k < 18; ++k) l(r, k) = normal(rng);
  c.matrix = l * l.transpose();
  const std::string path = dir.File("map.yaml");
  WriteMapWithCovariance(path, map, &c);
  ExpectSameMap(map, ReadMap(path));
  const std::optional<MapCovariance> back = ReadMapCovariance(path);
  ASSERT_TRUE(back);
  EXPECT_EQ(back->cameras, c.cameras);
  EXPECT_EQ(back->markers, c.markers);
  EXPECT_TRUE(back->matrix.isApprox(c.matrix, 1e-8));
  EXPECT_EQ(back->CameraEntry("cam \"2\""), 1);
  EXPECT_EQ(back->MarkerEntry(17), 2);
  EXPECT_EQ(back->MarkerEntry(18), -1);
  EXPECT_EQ(back->CameraEntry("cam0"), -1);
  WriteMap(dir.File("plain.yaml"), map);
  EXPECT_FALSE(ReadMapCovariance(dir.File("plain.yaml")));
  WriteMapWithCovariance(dir.File("none.yaml"), map, nullptr);
  EXPECT_EQ(ReadFile(dir.File("none.yaml")), ReadFile(dir.File("plain.yaml")));
  const std::string text = ReadFile(path);
  auto error = [&](const std::string& edited) {
    try {
      ReadMapCovariance(dir.Write("bad.yaml", edited));
    } catch (const FileFormatError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error(Replace(text, "  markers: [17]", "  markers: [17, 18]"))
                .find("covariance.matrix: expected 24 rows"),
            std::string::npos);
  EXPECT_NE(error(Replace(text, "  markers: [17]", "  markers: [17, 17]"))
                .find("covariance.markers: a marker is listed twice"),
            std::string::npos);
  Eigen::MatrixXd asymmetric = c.matrix;
  asymmetric(0, 1) *= 2.0;
  MapCovariance bad = c;
  bad.matrix = asymmetric;
  WriteMapWithCovariance(dir.File("asym.yaml"), map, &bad);
  EXPECT_THROW(ReadMapCovariance(dir.File("asym.yaml")), FileFormatError);
}

TEST(Files, MapWithoutRotationMatrixUsesQuaternion) {
  TempDir dir;
  const RigMap map = RandomMap(4);
  WriteMap(dir.File("map.yaml"), map);
  // Drop every rotation_matrix line (a hand-written map): poses come from the quaternions.
  std::string text = ReadFile(dir.File("map.yaml")), out;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line))
    if (line.find("rotation_matrix") == std::string::npos) out += line + "\n";
  const RigMap back = ReadMap(dir.Write("hand.yaml", out));
  for (size_t i = 0; i < map.cameras.size(); ++i) {
    EXPECT_LT(RotationAngle(map.cameras[i].rig_from_cam, back.cameras[i].rig_from_cam), 1e-15);
    EXPECT_EQ(map.cameras[i].rig_from_cam.translation(), back.cameras[i].rig_from_cam.translation());
  }
}

std::string MapError(const std::string& text) {
  TempDir dir;
  const std::string path = dir.Write("map.yaml", text);
  try {
    ReadMap(path);
  } catch (const FileFormatError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(path, 0), 0u) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    return what;
  }
  ADD_FAILURE() << "no error";
  return "";
}

TEST(Files, MapErrorsNameTheKey) {
  TempDir dir;
  WriteMap(dir.File("m.yaml"), RandomMap(5));
  const std::string good = ReadFile(dir.File("m.yaml"));
  EXPECT_CONTAINS(MapError(Replace(good, "version: 1", "version: 3")), "version: unsupported map version 3");
  EXPECT_CONTAINS(MapError(Replace(good, "version: 1\n", "")), "version: missing");
  EXPECT_CONTAINS(MapError(Replace(good, "      fx: ", "      fxx: ")), "cameras[0].intrinsics.fx: missing");
  EXPECT_CONTAINS(MapError(Replace(good, "distortion_model: fisheye", "distortion_model: fish")),
                  "cameras[1].intrinsics.distortion_model: unknown distortion model");
  EXPECT_CONTAINS(MapError(Replace(good, "  - id: 17", "  - id: x17")), "markers[2].id: expected an integer");
  EXPECT_CONTAINS(MapError(Replace(good, "  - id: 17", "  - id: 0")),
                  "markers[2].id: duplicated marker id 0");
  EXPECT_CONTAINS(MapError(Replace(good, "rotation_wxyz: [", "rotation_wxyz: [0.5, ")),
                  "cameras[0].rig_from_cam.rotation_wxyz: expected 4 numbers, got 5");
  // Editing only the quaternion is caught.
  {
    std::string edited = good;
    const size_t at = edited.find("rotation_wxyz: [", edited.find("- name: \"cam2\""));
    const size_t end = edited.find('\n', at);
    edited.replace(at, end - at, "rotation_wxyz: [0, 1, 0, 0]");
    EXPECT_CONTAINS(MapError(edited),
                    "cameras[2].rig_from_cam.rotation_matrix: disagrees with rotation_wxyz");
  }
  // Issue 14: a NaN translation was accepted (and exported as .Nan); a duplicated key too.
  {
    std::string edited = good;
    const size_t first = edited.find("translation: [") + std::string("translation: [").size();
    edited.replace(first, edited.find(',', first) - first, ".nan");
    EXPECT_CONTAINS(MapError(edited),
                    "rig_from_cam.translation: item 0: expected a finite number, got '.nan'");
  }
  EXPECT_CONTAINS(MapError(Replace(good, "version: 1\n", "version: 1\nversion: 1\n")),
                  ": duplicated key 'version' (first at line ");
  EXPECT_CONTAINS(MapError("version: [1\n"), "YAML syntax error");
  EXPECT_CONTAINS(MapError("- 1\n- 2\n"), "not a map file");
  EXPECT_THROW(ReadMap(dir.File("absent.yaml")), FileFormatError);
}

TEST(Files, TrajectoryRoundTrips) {
  TempDir dir;
  std::mt19937_64 rng(8);
  std::vector<TrajectoryRow> rows;
  for (int i = 0; i < 200; ++i) {
    TrajectoryRow r;
    r.utime = 1700000000000000LL + 33333LL * i;
    r.seq = i;
    r.rig_from_object = RandomRigid(rng, 2.0);
    r.rms_px = 0.1 * i + 1.0 / 3.0;
    r.cameras = i % 5;
    r.markers = i % 11;
    rows.push_back(r);
  }
  const std::string path = dir.File("trajectory.csv");
  WriteTrajectory(path, rows);
  const std::string text = ReadFile(path);
  EXPECT_EQ(text.rfind(std::string(kTrajectoryHeader) + "\n", 0), 0u);
  const auto back = ReadTrajectory(path);
  ASSERT_EQ(back.size(), rows.size());
  for (size_t i = 0; i < rows.size(); ++i) {
    EXPECT_EQ(back[i].utime, rows[i].utime);
    EXPECT_EQ(back[i].seq, rows[i].seq);
    EXPECT_EQ(back[i].rig_from_object.translation(), rows[i].rig_from_object.translation());
    // The quaternion is written exactly; matrix -> quaternion -> matrix is exact to rounding.
    EXPECT_LT(RotationAngle(back[i].rig_from_object, rows[i].rig_from_object), 1e-15);
    EXPECT_EQ(back[i].rms_px, rows[i].rms_px);
    EXPECT_EQ(back[i].cameras, rows[i].cameras);
    EXPECT_EQ(back[i].markers, rows[i].markers);
  }
  // Everything but the rotation is bit-exact; the rotation goes through a quaternion (the file's
  // format) and is exact to rounding (checked above, < 1e-15 rad).
  // An empty trajectory is the header alone.
  WriteTrajectory(dir.File("empty.csv"), {});
  EXPECT_EQ(ReadFile(dir.File("empty.csv")), std::string(kTrajectoryHeader) + "\n");
  EXPECT_TRUE(ReadTrajectory(dir.File("empty.csv")).empty());
}

// n rows at utime 1000 + i, seq i, identity poses (the trajectory format tests' rows).
std::vector<TrajectoryRow> NumberedRows(int n) {
  std::vector<TrajectoryRow> rows(n);
  for (int i = 0; i < n; ++i) {
    rows[i].utime = 1000 + i;
    rows[i].seq = i;
  }
  return rows;
}

// The mapper's trajectory with time offsets keeps each row's velocity (kTrajectoryVelocityHeader):
// bit-exact; a file without the columns (every earlier one) reads as rows without velocity; rows
// without one are written with the six columns empty beside rows with one.
TEST(Files, TrajectoryVelocitiesRoundTrip) {
  TempDir dir;
  std::vector<TrajectoryRow> rows = NumberedRows(3);
  for (int i = 0; i < 3; ++i)
    if (i != 1)
      rows[i].velocity = std::array<double, 6>{0.1 * i, -1.0 / 3.0, 2e-7, 0.5, -0.25 * i, 1.0 / 7.0};
  const std::string path = dir.File("trajectory.csv");
  WriteTrajectory(path, rows);
  const std::string text = ReadFile(path);
  EXPECT_EQ(text.rfind(std::string(kTrajectoryVelocityHeader) + "\n", 0), 0u);
  EXPECT_NE(text.find("\n1001,1,0,0,0,1,0,0,0,0,0,0,,,,,,\n"), std::string::npos) << text;
  const std::vector<TrajectoryRow> back = ReadTrajectory(path);
  ASSERT_EQ(back.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    ASSERT_EQ(back[i].velocity.has_value(), rows[i].velocity.has_value()) << i;
    if (rows[i].velocity) {
      EXPECT_EQ(*back[i].velocity, *rows[i].velocity) << i;
    }
  }
  EXPECT_TRUE(IsTrajectoryHeader(kTrajectoryHeader));
  EXPECT_TRUE(IsTrajectoryHeader(std::string(kTrajectoryVelocityHeader) + "\r"));
  EXPECT_FALSE(IsTrajectoryHeader("utime,seq"));
  // Without velocities: the 12 columns alone, as before.
  for (TrajectoryRow& r : rows) r.velocity.reset();
  WriteTrajectory(path, rows);
  EXPECT_EQ(ReadFile(path).rfind(std::string(kTrajectoryHeader) + "\n", 0), 0u);
  for (const TrajectoryRow& r : ReadTrajectory(path)) EXPECT_FALSE(r.velocity.has_value());
  // A new rig frame rotates the velocity with the pose: the moved pose at dt is the pose at dt moved.
  TrajectoryRow row;
  row.rig_from_object =
      Rigid3(Eigen::Translation3d(0.1, 0.2, 1.0) * Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()));
  row.velocity = std::array<double, 6>{0.2, -0.1, 0.4, 0.3, 0.0, -0.2};
  const Rigid3 new_from_rig(Eigen::Translation3d(-0.5, 0.0, 0.2) *
                            Eigen::AngleAxisd(1.1, Eigen::Vector3d(1, 2, 3).normalized()));
  auto at = [](const TrajectoryRow& r, double dt) { return MovedAlong(r.rig_from_object, *r.velocity, dt); };
  TrajectoryRow moved = row;
  MoveToRig(new_from_rig, &moved);
  const Rigid3 want = new_from_rig * at(row, 0.05), got = at(moved, 0.05);
  EXPECT_LT((want.translation() - got.translation()).norm(), 1e-12);
  EXPECT_LT(RotationAngle(want, got), 1e-12);
}

// A tracker's poses carry their status and worst-direction sigmas (PoseQuality): bit-exact through the
// file, with or without the velocity columns; a row without one has the three columns empty; the
// tracker's header has them even with no row.
TEST(Files, TrajectoryQualityRoundTrip) {
  TempDir dir;
  std::vector<TrajectoryRow> rows = NumberedRows(3);
  rows[0].quality = PoseQuality{false, 1.0 / 3.0 * 1e-3, 2e-4};
  rows[2].quality = PoseQuality{true, 0.0078125, 0.25};
  const std::string path = dir.File("poses.csv");
  WriteTrajectory(path, rows);
  std::string text = ReadFile(path);
  EXPECT_EQ(text.rfind(std::string(kTrajectoryHeader) + ",status,sigma_position_m,sigma_rotation_rad\n", 0),
            0u)
      << text;
  EXPECT_NE(text.find("\n1001,1,0,0,0,1,0,0,0,0,0,0,,,\n"), std::string::npos) << text;
  EXPECT_NE(text.find("\n1002,2,0,0,0,1,0,0,0,0,0,0,ambiguous,0.0078125,0.25\n"), std::string::npos) << text;
  auto same = [&](const std::vector<TrajectoryRow>& back) {
    ASSERT_EQ(back.size(), 3u);
    for (int i = 0; i < 3; ++i) {
      ASSERT_EQ(back[i].quality.has_value(), rows[i].quality.has_value()) << i;
      if (!rows[i].quality) continue;
      EXPECT_EQ(back[i].quality->ambiguous, rows[i].quality->ambiguous) << i;
      EXPECT_EQ(back[i].quality->sigma_position_m, rows[i].quality->sigma_position_m) << i;
      EXPECT_EQ(back[i].quality->sigma_rotation_rad, rows[i].quality->sigma_rotation_rad) << i;
    }
  };
  same(ReadTrajectory(path));
  // After the velocity's columns (21 in all).
  rows[1].velocity = std::array<double, 6>{0.1, 0.2, 0.3, 0.4, 0.5, 0.6};
  WriteTrajectory(path, rows);
  text = ReadFile(path);
  EXPECT_EQ(text.rfind(TrajectoryHeader(true, true) + "\n", 0), 0u) << text;
  EXPECT_NE(text.find("\n1000,0,0,0,0,1,0,0,0,0,0,0,,,,,,,tracking,"), std::string::npos) << text;
  same(ReadTrajectory(path));
  EXPECT_TRUE(ReadTrajectory(path)[1].velocity.has_value());
  EXPECT_TRUE(IsTrajectoryHeader(TrajectoryHeader(false, true) + "\r"));
  EXPECT_TRUE(IsTrajectoryHeader(TrajectoryHeader(true, true)));
  EXPECT_FALSE(IsTrajectoryHeader(std::string(kTrajectoryHeader) + ",status"));
  // No quality: the columns are left out; asked for: the header has them with no row.
  WriteTrajectory(path, {}, true);
  EXPECT_EQ(ReadFile(path), TrajectoryHeader(false, true) + "\n");
  for (TrajectoryRow& r : rows) r.quality.reset(), r.velocity.reset();
  WriteTrajectory(path, rows);
  EXPECT_EQ(ReadFile(path).rfind(std::string(kTrajectoryHeader) + "\n", 0), 0u);
}

// The worst-direction sigmas of a pose covariance in object_pose_t's order. The rotation turns about the
// rig origin, so the origin's position moves by -[t]x w: an object at t = (0, 0, 1) m with rotation
// variances (a, b, c) about x, y, z and no translation variance has position variances (b, a, 0).
TEST(Files, QualityOfPoseIsTheWorstSigma) {
  const Rigid3 pose(Eigen::Translation3d(0, 0, 1));
  Matrix6d c = Matrix6d::Zero();
  c.diagonal() << 0, 0, 0, 1e-6, 4e-6, 9e-6;
  PoseQuality q = QualityOfPose(pose, c, false);
  EXPECT_NEAR(q.sigma_position_m, 2e-3, 1e-12);
  EXPECT_NEAR(q.sigma_rotation_rad, 3e-3, 1e-12);
  EXPECT_FALSE(q.ambiguous);
  // Translation alone: its own worst axis.
  c.diagonal() << 1e-6, 2.5e-5, 4e-6, 0, 0, 0;
  q = QualityOfPose(pose, c, true);
  EXPECT_NEAR(q.sigma_position_m, 5e-3, 1e-12);
  EXPECT_EQ(q.sigma_rotation_rad, 0.0);
  EXPECT_TRUE(q.ambiguous);
  // Not positive semi-definite (a degenerate solve): no finite sigma.
  c(0, 0) = -1e-3;
  EXPECT_TRUE(std::isnan(QualityOfPose(pose, c, false).sigma_position_m));
}

TEST(Files, TrajectoryErrorsNameTheLine) {
  TempDir dir;
  auto error = [&](const std::string& text) -> std::string {
    const std::string path = dir.Write("t.csv", text);
    try {
      ReadTrajectory(path);
    } catch (const FileFormatError& e) {
      EXPECT_EQ(std::string(e.what()).rfind(path, 0), 0u);
      return e.what();
    }
    return "";
  };
  const std::string h = std::string(kTrajectoryHeader) + "\n";
  EXPECT_CONTAINS(error("utime,seq\n1,2\n"), "t.csv:1: expected the header");
  EXPECT_CONTAINS(error(h + "1,2,0,0,0,1,0,0,0,0.5,1,1\n1,2,0,0,0,1,0,0\n"),
                  "t.csv:3: expected 12 fields, got 8");
  EXPECT_CONTAINS(error(h + "1,2,0,0,zero,1,0,0,0,0.5,1,1\n"), "t.csv:2: tz: not a number: 'zero'");
  EXPECT_CONTAINS(error(h + "1.5,2,0,0,0,1,0,0,0,0.5,1,1\n"), "t.csv:2: utime: not an integer");
  EXPECT_CONTAINS(error(h + "1,2,0,0,0,0,0,0,0,0.5,1,1\n"), "t.csv:2: qw..qz");
  EXPECT_CONTAINS(error(""), "empty file");
  // The velocity columns: all six numbers or all empty, each named.
  const std::string hv = std::string(kTrajectoryVelocityHeader) + "\n";
  EXPECT_CONTAINS(error(hv + "1,2,0,0,0,1,0,0,0,0.5,1,1\n"), "t.csv:2: expected 18 fields, got 12");
  EXPECT_CONTAINS(error(hv + "1,2,0,0,0,1,0,0,0,0.5,1,1,0,0,,0,0,0\n"),
                  "t.csv:2: wz: not a finite number: ''");
  EXPECT_CONTAINS(error(hv + "1,2,0,0,0,1,0,0,0,0.5,1,1,0,0,0,0,fast,0\n"),
                  "t.csv:2: vy: not a finite number: 'fast'");
  EXPECT_CONTAINS(error(hv + "1,2,0,0,0,1,0,0,0,0.5,1,1,0,0,0,nan,0,0\n"),
                  "t.csv:2: vx: not a finite number");
  EXPECT_CONTAINS(error(h + "1,2,0,0,0,1,0,0,0,0.5,1,1,0,0,0,0,0,0\n"),
                  "t.csv:2: expected 12 fields, got 18");
  // The quality columns: a status word and two sigmas >= 0 (nan: no finite sigma), or all empty.
  const std::string hq = TrajectoryHeader(false, true) + "\n";
  EXPECT_CONTAINS(error(hq + "1,2,0,0,0,1,0,0,0,0.5,1,1,lost,0.001,0.01\n"),
                  "t.csv:2: status: expected 'tracking' or 'ambiguous', got 'lost'");
  EXPECT_CONTAINS(error(hq + "1,2,0,0,0,1,0,0,0,0.5,1,1,tracking,-0.001,0.01\n"),
                  "t.csv:2: sigma_position_m: not a number >= 0: '-0.001'");
  EXPECT_CONTAINS(error(hq + "1,2,0,0,0,1,0,0,0,0.5,1,1,ambiguous,0.001,\n"),
                  "t.csv:2: sigma_rotation_rad: not a number >= 0: ''");
  EXPECT_CONTAINS(error(hq + "1,2,0,0,0,1,0,0,0,0.5,1,1\n"), "t.csv:2: expected 15 fields, got 12");
  EXPECT_TRUE(
      std::isnan(ReadTrajectory(dir.Write("nan.csv", hq + "1,2,0,0,0,1,0,0,0,0.5,1,1,tracking,nan,0.01\n"))[0]
                     .quality->sigma_position_m));
  // CRLF line ends are accepted.
  const std::string crlf = std::string(kTrajectoryHeader) + "\r\n1,2,0,0,0,1,0,0,0,0.5,1,1\r\n";
  EXPECT_EQ(ReadTrajectory(dir.Write("crlf.csv", crlf)).size(), 1u);
}

TEST(Files, AtomicWriteLeavesNoPartialFile) {
  TempDir dir;
  const std::string path = dir.File("out.txt");
  WriteFileAtomic(path, "first");
  EXPECT_EQ(ReadFile(path), "first");
  WriteFileAtomic(path, std::string(1 << 20, 'x'));
  EXPECT_EQ(ReadFile(path).size(), 1u << 20);
  for (const auto& entry : std::filesystem::directory_iterator(dir.path()))
    EXPECT_EQ(entry.path().filename().string(), "out.txt");
  // A folder that does not exist: error naming the file, nothing written.
  try {
    WriteFileAtomic(dir.File("no/such/dir/f.txt"), "x");
    FAIL();
  } catch (const FileFormatError& e) {
    EXPECT_CONTAINS(e.what(), "no/such/dir/f.txt");
  }
  // The target is a folder: rename fails, the temporary file is removed.
  std::filesystem::create_directories(dir.File("adir/sub"));
  EXPECT_THROW(WriteFileAtomic(dir.File("adir"), "x"), FileFormatError);
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
    (void)entry;
    ++count;
  }
  EXPECT_EQ(count, 2);  // out.txt and adir
  EXPECT_THROW(ReadFile(dir.File("absent")), FileFormatError);
}

}  // namespace
}  // namespace mcmt

namespace mcmt {
namespace {

// A map written by hand: statistics and rotation matrices may be left out.
TEST(Files, MinimalHandWrittenMap) {
  testing_util::TempDir dir;
  const std::string path = dir.Write("map.yaml", R"(version: 1
dictionary: DICT_6X6_250
reference_camera: left
reference_marker: 0
cameras:
  - name: left
    intrinsics: {width: 640, height: 480, fx: 500, fy: 500, cx: 319.5, cy: 239.5, distortion_model: none,
                 distortion: []}
    rig_from_cam: {translation: [0, 0, 0], rotation_wxyz: [1, 0, 0, 0]}
  - name: right
    intrinsics: {width: 640, height: 480, fx: 500, fy: 500, cx: 319.5, cy: 239.5, distortion_model: radtan,
                 distortion: [0.1, 0, 0, 0]}
    rig_from_cam: {translation: [0.2, 0, 0], rotation_wxyz: [0.7071067811865476, 0, 0.7071067811865476, 0]}
markers:
  - {id: 0, size: 0.05, object_from_marker: {translation: [0, 0, 0], rotation_wxyz: [1, 0, 0, 0]}}
)");
  const RigMap map = ReadMap(path);
  ASSERT_EQ(map.cameras.size(), 2u);
  EXPECT_EQ(map.cameras[1].model.model, DistortionModel::kRadTan);
  EXPECT_NEAR((map.cameras[1].rig_from_cam * Eigen::Vector3d(0, 0, 1) - Eigen::Vector3d(1.2, 0, 0)).norm(), 0,
              1e-15);
  EXPECT_EQ(map.cameras[1].observations, 0);
  EXPECT_EQ(map.num_frames, 0);
  ASSERT_EQ(map.markers.size(), 1u);
  EXPECT_EQ(map.markers[0].size, 0.05);
}

// A camera's clock (offset and drift against the reference camera's) applied to its messages, and two
// clocks measured one on top of the other made one (the maintenance, the time-offset passes).
TEST(Files, MapClocksCorrectMessagesAndCompose) {
  constexpr int64_t kRef = 1000000000000LL;
  RigMap applied;
  applied.time_reference_utime = kRef;
  applied.cameras.resize(2);
  applied.cameras[0].name = "cam0";
  applied.cameras[1].name = "cam1";
  applied.cameras[1].time_offset_us = 12000.0;
  applied.cameras[1].time_drift_ppm = 300.0;
  // 10 s after the reference cam1 reads 12 ms + 3 ms ahead.
  EXPECT_EQ(applied.ReferenceUtime("cam1", kRef + 10000000), kRef + 10000000 - 15000);
  EXPECT_EQ(applied.ReferenceUtime("cam0", kRef + 5), kRef + 5);
  EXPECT_EQ(applied.ReferenceUtime("cam9", kRef + 5), kRef + 5);  // not in the map: as stamped

  RigMap found = applied;  // what a solve on the corrected messages found: 0.5 ms more for cam1, no drift
  found.time_reference_utime = 0;
  for (MapCamera& c : found.cameras) c.time_offset_us = c.time_drift_ppm = 0.0;
  found.cameras[1].time_offset_us = 500.0;
  ComposeClocks(applied, &found);
  EXPECT_EQ(found.time_reference_utime, kRef);
  for (int64_t utime : {kRef - 20000000, kRef, kRef + 30000000}) {
    EXPECT_NEAR(found.cameras[1].ClockUs(utime, found.time_reference_utime),
                500.0 + applied.cameras[1].ClockUs(utime, kRef), 1e-6);
    EXPECT_NEAR(found.cameras[0].ClockUs(utime, found.time_reference_utime), 0.0, 1e-9);
  }
}

}  // namespace
}  // namespace mcmt
