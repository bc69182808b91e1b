#include <gtest/gtest.h>

#include <lcm/lcm-cpp.hpp>
#include <random>

#include "core/lcm_util.h"
#include "mcmt/mapper_command_t.hpp"
#include "mcmt/mapper_status_t.hpp"
#include "test_util.h"

namespace mcmt {
namespace {

using testing_util::TempDir;

camera_model_t SampleCameraMsg() {
  CameraModel m;
  m.width = 1280;
  m.height = 720;
  m.fx = 900.5;
  m.fy = 901.25;
  m.cx = 640.125;
  m.cy = 360.0625;
  m.model = DistortionModel::kRadTan;
  m.distortion = {-0.2, 0.05, 0.001, -0.002, 0.01};
  return ToCameraModelMsg(m);
}

detections_t SampleDetections(int num_markers = 3, const std::string& camera = "cam0", int64_t utime = 1000) {
  detections_t d;
  d.utime = utime;
  d.seq = 42;
  d.camera = camera;
  d.dictionary = "DICT_6X6_250";
  d.camera_model = SampleCameraMsg();
  d.num_markers = num_markers;
  for (int i = 0; i < num_markers; ++i) {
    marker_t m;
    m.id = 10 + i;
    for (int c = 0; c < 4; ++c) {
      m.corners[c][0] = 100.25 * i + c;
      m.corners[c][1] = 50.5 * i - c;
    }
    d.markers.push_back(m);
  }
  d.detection_ms = 3.25;
  return d;
}

object_pose_t SamplePose() {
  object_pose_t p;
  p.utime = 123456789;
  p.seq = 7;
  p.object = "cube";
  std::mt19937_64 rng(1);
  p.rig_from_object = ToPose3d(RandomRigid(rng, 1.0));
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) p.covariance[i][j] = i == j ? 1e-6 * (i + 1) : 1e-9 * (i - j);
  p.rms_px = 0.4;
  p.num_cameras = 2;
  p.cameras = {"cam0", "cam1"};
  p.num_markers = 3;
  p.markers = {1, 5, 9};
  p.num_rejected = 1;
  p.status = object_pose_t::STATUS_TRACKING;
  p.latency_ms = 1.5;
  return p;
}

RigMap SampleMap() {
  std::mt19937_64 rng(2);
  RigMap map;
  map.dictionary = "DICT_4X4_50";
  map.reference_camera = "cam0";
  map.reference_marker = 1;
  for (int i = 0; i < 3; ++i) {
    MapCamera c;
    c.name = "cam" + std::to_string(i);
    c.model = FromCameraModelMsg(SampleCameraMsg());
    c.rig_from_cam = i == 0 ? Rigid3::Identity() : RandomRigid(rng, 2.0);
    map.cameras.push_back(c);
  }
  for (int id : {1, 4}) {
    MapMarker m;
    m.id = id;
    m.size = 0.05;
    m.object_from_marker = RandomRigid(rng, 0.1);
    map.markers.push_back(m);
  }
  map.rms_px = 0.3;
  map.num_frames = 100;
  map.num_observations = 800;
  return map;
}

rig_map_t SampleMapMsg() { return ToRigMapMsg(SampleMap(), 99); }

// A version 2 map: a static room (the rig frame), a tool and a patient; clocks that drift.
RigMap SampleBodiesMap() {
  std::mt19937_64 rng(4);
  RigMap map = SampleMap();
  map.version = kMapVersionBodies;
  map.rig_frame = "room";
  map.time_reference_utime = 5000000;
  map.cameras[1].time_offset_us = 250.5;
  map.cameras[2].time_drift_ppm = -31.25;
  int id = 0;
  for (const char* name : {"room", "tool", "patient"}) {
    MapObject o;
    o.name = name;
    o.is_static = o.name == "room";
    for (int k = 0; k < 3; ++k) {
      MapMarker m;
      m.id = id++;
      m.size = 0.04 + 0.01 * k;
      m.object_from_marker = k == 0 ? Rigid3::Identity() : RandomRigid(rng, 0.1);
      o.markers.push_back(m);
    }
    o.reference_marker = o.markers[0].id;
    if (o.is_static) o.rig_from_object = RandomRigid(rng, 1.0);
    o.rms_px = 0.1 * id;
    o.num_frames = o.is_static ? 0 : 100 + id;
    o.num_observations = 10 * id;
    map.objects.push_back(o);
  }
  map.markers = map.objects[1].markers;  // the first moving body's, as ReadMap
  map.reference_marker = map.objects[1].reference_marker;
  return map;
}

rig_map2_t SampleMap2Msg() { return ToRigMap2Msg(SampleBodiesMap(), 77); }
object_layout_t SampleLayoutMsg() { return SampleMap2Msg().objects[1]; }

mapper_status_t SampleStatus() {
  mapper_status_t s;
  s.utime = 5;
  s.state = mapper_status_t::STATE_REFINING;
  s.frames = 10;
  s.observations = 20;
  s.cameras_seen = 3;
  s.cameras_connected = 2;
  s.markers_seen = 6;
  s.iteration = 4;
  s.cost = 12.5;
  s.rms_px = 0.7;
  s.message = "refining";
  return s;
}

mapper_command_t SampleCommand() {
  mapper_command_t c;
  c.utime = 6;
  c.command = "solve";
  return c;
}

pose3d_t SamplePose3d() {
  std::mt19937_64 rng(3);
  return ToPose3d(RandomRigid(rng, 1.0));
}

marker_t SampleMarker() { return SampleDetections(1).markers[0]; }

// Round trip, every truncation, trailing bytes, garbage and a foreign type.
template <typename Msg, typename Foreign>
void CheckCodec(const Msg& msg, const Foreign& foreign) {
  SCOPED_TRACE(Msg::getTypeName());
  const std::vector<uint8_t> bytes = Encode(msg);
  ASSERT_GT(bytes.size(), 8u);
  Msg back;
  std::string error;
  ASSERT_TRUE(Decode(bytes.data(), bytes.size(), &back, &error)) << error;
  EXPECT_EQ(Encode(back), bytes);  // byte-equal re-encoding
  for (size_t n = 0; n < bytes.size(); ++n) {
    Msg m;
    EXPECT_FALSE(Decode(bytes.data(), n, &m, &error)) << "truncated to " << n;
    EXPECT_FALSE(error.empty());
  }
  std::vector<uint8_t> longer = bytes;
  longer.push_back(0);
  EXPECT_FALSE(Decode(longer.data(), longer.size(), &back, &error));
  EXPECT_NE(error.find("trailing"), std::string::npos);
  EXPECT_THROW(DecodeOrThrow<Msg>(longer.data(), longer.size()), LcmDecodeError);
  EXPECT_NO_THROW(DecodeOrThrow<Msg>(bytes.data(), bytes.size()));
  // Another type's bytes: the fingerprint differs.
  const std::vector<uint8_t> other = Encode(foreign);
  EXPECT_FALSE(Decode(other.data(), other.size(), &back, &error));
  // Random garbage, and garbage behind a valid fingerprint (array lengths may be absurd): no crash.
  std::mt19937_64 rng(77);
  for (int trial = 0; trial < 300; ++trial) {
    std::vector<uint8_t> junk(rng() % (2 * bytes.size() + 1));
    for (auto& b : junk) b = static_cast<uint8_t>(rng());
    Msg m;
    EXPECT_FALSE(Decode(junk.data(), junk.size(), &m, &error));
    if (junk.size() >= 8) {
      std::copy(bytes.begin(), bytes.begin() + 8, junk.begin());
      Decode(junk.data(), junk.size(), &m, &error);  // may or may not decode; must not crash
    }
    // Flip one byte of a valid message: must not crash either.
    std::vector<uint8_t> flipped = bytes;
    flipped[8 + rng() % (bytes.size() - 8)] ^= static_cast<uint8_t>(1 + rng() % 255);
    Decode(flipped.data(), flipped.size(), &m, &error);
  }
}

TEST(LcmUtil, EveryTypeEncodesDecodesAndRejectsBadBuffers) {
  CheckCodec(SampleDetections(), SamplePose());
  CheckCodec(SampleDetections(0), SamplePose());
  CheckCodec(SampleCameraMsg(), SampleMarker());
  CheckCodec(SampleMarker(), SamplePose3d());
  CheckCodec(SamplePose3d(), SampleMarker());
  CheckCodec(SampleMapMsg(), SampleDetections());
  CheckCodec(SamplePose(), SampleDetections());
  CheckCodec(SampleStatus(), SampleCommand());
  CheckCodec(SampleCommand(), SampleStatus());
  CheckCodec(SampleMap2Msg(), SampleMapMsg());
  CheckCodec(SampleLayoutMsg(), SampleMap2Msg());
  CheckCodec(ToRigMap2Msg(SampleMap(), 3), SampleMapMsg());
}

void ExpectSameMap(const RigMap& a, const RigMap& b) {
  EXPECT_EQ(a.version, b.version);
  EXPECT_EQ(a.dictionary, b.dictionary);
  EXPECT_EQ(a.reference_camera, b.reference_camera);
  EXPECT_EQ(a.reference_marker, b.reference_marker);
  EXPECT_EQ(a.rig_frame, b.rig_frame);
  EXPECT_EQ(a.time_reference_utime, b.time_reference_utime);
  ASSERT_EQ(a.cameras.size(), b.cameras.size());
  for (size_t i = 0; i < a.cameras.size(); ++i) {
    EXPECT_EQ(a.cameras[i].name, b.cameras[i].name);
    EXPECT_TRUE(a.cameras[i].model == b.cameras[i].model);
    EXPECT_LT(RotationAngle(a.cameras[i].rig_from_cam, b.cameras[i].rig_from_cam), 1e-15);
    EXPECT_LT(TranslationDistance(a.cameras[i].rig_from_cam, b.cameras[i].rig_from_cam), 1e-15);
    EXPECT_EQ(a.cameras[i].time_offset_us, b.cameras[i].time_offset_us);
    EXPECT_EQ(a.cameras[i].time_drift_ppm, b.cameras[i].time_drift_ppm);
  }
  auto same_markers = [](const std::vector<MapMarker>& x, const std::vector<MapMarker>& y) {
    ASSERT_EQ(x.size(), y.size());
    for (size_t i = 0; i < x.size(); ++i) {
      EXPECT_EQ(x[i].id, y[i].id);
      EXPECT_EQ(x[i].size, y[i].size);
      EXPECT_LT(RotationAngle(x[i].object_from_marker, y[i].object_from_marker), 1e-15);
      EXPECT_LT(TranslationDistance(x[i].object_from_marker, y[i].object_from_marker), 1e-15);
    }
  };
  same_markers(a.markers, b.markers);
  ASSERT_EQ(a.objects.size(), b.objects.size());
  for (size_t k = 0; k < a.objects.size(); ++k) {
    const MapObject &x = a.objects[k], &y = b.objects[k];
    EXPECT_EQ(x.name, y.name);
    EXPECT_EQ(x.is_static, y.is_static);
    EXPECT_EQ(x.reference_marker, y.reference_marker);
    EXPECT_LT(TranslationDistance(x.rig_from_object, y.rig_from_object), 1e-15);
    EXPECT_LT(RotationAngle(x.rig_from_object, y.rig_from_object), 1e-15);
    EXPECT_EQ(x.rms_px, y.rms_px);
    EXPECT_EQ(x.num_frames, y.num_frames);
    EXPECT_EQ(x.num_observations, y.num_observations);
    same_markers(x.markers, y.markers);
  }
  EXPECT_EQ(a.rms_px, b.rms_px);
  EXPECT_EQ(a.num_frames, b.num_frames);
  EXPECT_EQ(a.num_observations, b.num_observations);
}

// Both map types decode into the one in-memory map: rig_map2_t with its bodies and clocks, rig_map_t (old
// logs) as before.
TEST(LcmUtil, MapMessagesOfBothTypesDecodeIntoTheOneMap) {
  const RigMap bodies = SampleBodiesMap();
  const std::vector<uint8_t> v2 = Encode(ToRigMap2Msg(bodies, 77));
  MapMessage got;
  std::string error;
  ASSERT_TRUE(DecodeMapMessage(v2.data(), v2.size(), &got, &error)) << error;
  EXPECT_STREQ(got.type, "rig_map2_t");
  EXPECT_EQ(got.utime, 77);
  ExpectSameMap(got.map, bodies);
  EXPECT_EQ(got.map.markers[0].id, 3);  // the tool's: the first moving body

  // A one-object map through the new type: one nameless object, the same map back (no objects).
  RigMap single = SampleMap();
  single.cameras[2].time_offset_us = -120.0;
  const std::vector<uint8_t> v1_in_2 = Encode(ToRigMap2Msg(single, 8));
  ASSERT_TRUE(DecodeMapMessage(v1_in_2.data(), v1_in_2.size(), &got, &error)) << error;
  EXPECT_EQ(got.map.objects.size(), 0u);
  ExpectSameMap(got.map, single);

  // The old type: what FromRigMapMsg gives (no clocks on that wire).
  const std::vector<uint8_t> old = Encode(ToRigMapMsg(SampleMap(), 5));
  ASSERT_TRUE(DecodeMapMessage(old.data(), old.size(), &got, &error)) << error;
  EXPECT_STREQ(got.type, "rig_map_t");
  EXPECT_EQ(got.utime, 5);
  ExpectSameMap(got.map, SampleMap());

  // Another type, a truncated map, an invalid camera model, a v2 map without objects: false, one line.
  const std::vector<uint8_t> foreign = Encode(SampleDetections());
  EXPECT_FALSE(DecodeMapMessage(foreign.data(), foreign.size(), &got, &error));
  EXPECT_NE(error.find("neither a rig_map2_t nor a rig_map_t"), std::string::npos) << error;
  EXPECT_FALSE(DecodeMapMessage(v2.data(), v2.size() - 3, &got, &error));
  EXPECT_NE(error.find("not a valid rig_map2_t"), std::string::npos) << error;
  EXPECT_FALSE(DecodeMapMessage(v2.data(), 4, &got, &error));
  rig_map2_t bad = ToRigMap2Msg(bodies, 1);
  bad.camera_models[1].fx = -1;
  const std::vector<uint8_t> bad_bytes = Encode(bad);
  EXPECT_FALSE(DecodeMapMessage(bad_bytes.data(), bad_bytes.size(), &got, &error));
  EXPECT_NE(error.find("invalid map message"), std::string::npos) << error;
  bad = ToRigMap2Msg(bodies, 1);
  bad.objects.clear();
  bad.num_objects = 0;
  const std::vector<uint8_t> empty = Encode(bad);
  EXPECT_FALSE(DecodeMapMessage(empty.data(), empty.size(), &got, &error));
  EXPECT_NE(error.find("without any object"), std::string::npos) << error;
  EXPECT_EQ(error.find('\n'), std::string::npos);
}

// Fingerprints of the message types as recorded when they were defined. A failure here means a .lcm
// file changed: old logs would stop decoding. Changing a message needs a new type (e.g. detections2_t)
// or a deliberate update of this constant together with a note in the issue/changelog.
TEST(LcmUtil, FingerprintsArePinned) {
  // Recorded 2026-11-22 from lcmtypes/*.lcm at commit 4b6034e.
  EXPECT_EQ(camera_model_t::getHash(), static_cast<int64_t>(0x7d376e520d5ceb83ULL));
  EXPECT_EQ(marker_t::getHash(), static_cast<int64_t>(0xe04500ceb99b5f00ULL));
  EXPECT_EQ(detections_t::getHash(), static_cast<int64_t>(0xf952b90f66821fd6ULL));
  EXPECT_EQ(pose3d_t::getHash(), static_cast<int64_t>(0x993f6a8bc31b3367ULL));
  EXPECT_EQ(rig_map_t::getHash(), static_cast<int64_t>(0x82331d367b46048aULL));
  EXPECT_EQ(object_pose_t::getHash(), static_cast<int64_t>(0x739eea3f956a02fcULL));
  EXPECT_EQ(mapper_status_t::getHash(), static_cast<int64_t>(0x5310391edee41472ULL));
  EXPECT_EQ(mapper_command_t::getHash(), static_cast<int64_t>(0x623f9e6ee24a3d2dULL));
  // Recorded 2026-12-02 (issue 16: the map with its bodies).
  EXPECT_EQ(object_layout_t::getHash(), static_cast<int64_t>(0x6df3f52ec2c9793fULL));
  EXPECT_EQ(rig_map2_t::getHash(), static_cast<int64_t>(0xa8ef5bdffe808663ULL));
}

TEST(LcmUtil, ChannelNames) {
  EXPECT_EQ(DetectionsChannel("cam0"), "MCMT_DETECTIONS_CAM0");
  EXPECT_EQ(DetectionsChannel("left-cam.1"), "MCMT_DETECTIONS_LEFT_CAM_1");
  EXPECT_EQ(DetectionsChannel("Front_Right"), "MCMT_DETECTIONS_FRONT_RIGHT");
  EXPECT_EQ(ImageChannel("cam 2"), "MCMT_IMAGE_CAM_2");
  EXPECT_EQ(std::string(kPoseChannel), "MCMT_POSE");
  EXPECT_EQ(std::string(kMapChannel), "MCMT_MAP");
  EXPECT_EQ(LogReadUrl("/tmp/a.lcmlog"), "file:///tmp/a.lcmlog?speed=0");
  EXPECT_EQ(LogReadUrl("/tmp/x/../a.lcmlog"), "file:///tmp/a.lcmlog?speed=0");
}

TEST(LcmUtil, Conversions) {
  std::mt19937_64 rng(9);
  for (int i = 0; i < 20; ++i) {
    const Rigid3 t = RandomRigid(rng, 3.0);
    const pose3d_t p = ToPose3d(t);
    EXPECT_GE(p.orientation[0], 0.0);
    const Rigid3 back = FromPose3d(p);
    EXPECT_LT(RotationAngle(t, back), 1e-15);
    EXPECT_EQ(back.translation(), t.translation());
  }
  const camera_model_t cm = SampleCameraMsg();
  EXPECT_EQ(cm.distortion_model, "radtan");
  EXPECT_EQ(cm.num_distortion, 5);
  const CameraModel model = FromCameraModelMsg(cm);
  EXPECT_TRUE(ToCameraModelMsg(model).distortion == cm.distortion);
  EXPECT_EQ(model.fx, 900.5);
  camera_model_t bad = cm;
  bad.distortion_model = "wavy";
  EXPECT_THROW(FromCameraModelMsg(bad), std::invalid_argument);
  bad = cm;
  bad.fx = 0;
  EXPECT_THROW(FromCameraModelMsg(bad), std::invalid_argument);

  const RigMap map = SampleMap();
  const rig_map_t msg = ToRigMapMsg(map, 99);
  EXPECT_EQ(msg.utime, 99);
  EXPECT_EQ(msg.num_cameras, 3);
  EXPECT_EQ(msg.num_markers, 2);
  const RigMap back = FromRigMapMsg(msg);
  EXPECT_EQ(back.reference_camera, "cam0");
  EXPECT_EQ(back.reference_marker, 1);
  EXPECT_EQ(back.dictionary, "DICT_4X4_50");
  ASSERT_EQ(back.cameras.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(back.cameras[i].name, map.cameras[i].name);
    EXPECT_TRUE(back.cameras[i].model == map.cameras[i].model);
    EXPECT_LT(RotationAngle(back.cameras[i].rig_from_cam, map.cameras[i].rig_from_cam), 1e-15);
  }
  ASSERT_EQ(back.markers.size(), 2u);
  EXPECT_EQ(back.markers[1].id, 4);
  EXPECT_EQ(back.markers[1].size, 0.05);
  EXPECT_EQ(back.num_observations, 800);

  const marker_t m = SampleDetections(2).markers[1];
  const MarkerCorners2d c = CornersOf(m);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(c[i], Eigen::Vector2d(m.corners[i][0], m.corners[i][1]));
}

TEST(LcmUtil, ObjectPoseAsTrajectoryRow) {
  std::mt19937_64 rng(5);
  object_pose_t msg;
  msg.utime = 1234567;
  msg.seq = 42;
  const Rigid3 rig_from_object = RandomRigid(rng, 2.0);
  msg.rig_from_object = ToPose3d(rig_from_object);
  msg.rms_px = 0.25;
  msg.num_cameras = 3;
  msg.num_markers = 7;
  msg.status = object_pose_t::STATUS_AMBIGUOUS;
  Matrix6d covariance = Matrix6d::Zero();
  covariance.diagonal() << 4e-6, 1e-6, 9e-6, 1e-4, 4e-4, 2.5e-5;
  for (int a = 0; a < 6; ++a)
    for (int b = 0; b < 6; ++b) msg.covariance[a][b] = covariance(a, b);
  const TrajectoryRow row = FromObjectPoseMsg(msg);
  EXPECT_EQ(row.utime, 1234567);
  EXPECT_EQ(row.seq, 42);
  EXPECT_LT(RotationAngle(row.rig_from_object, rig_from_object), 1e-12);
  EXPECT_LT((row.rig_from_object.translation() - rig_from_object.translation()).norm(), 1e-12);
  EXPECT_EQ(row.rms_px, 0.25);
  EXPECT_EQ(row.cameras, 3);
  EXPECT_EQ(row.markers, 7);
  // The status and the covariance's worst sigmas: QualityOfPose of the message's pose.
  ASSERT_TRUE(row.quality.has_value());
  EXPECT_TRUE(row.quality->ambiguous);
  const PoseQuality want = QualityOfPose(row.rig_from_object, covariance, true);
  EXPECT_EQ(row.quality->sigma_position_m, want.sigma_position_m);
  EXPECT_NEAR(row.quality->sigma_rotation_rad, 0.02, 1e-15);
  msg.status = object_pose_t::STATUS_TRACKING;
  EXPECT_FALSE(FromObjectPoseMsg(msg).quality->ambiguous);
  msg.status = object_pose_t::STATUS_LOST;  // no pose, so no quality
  EXPECT_FALSE(FromObjectPoseMsg(msg).quality.has_value());
}

class Counter {
 public:
  void OnDetections(const lcm::ReceiveBuffer* rbuf, const std::string& channel, const detections_t* msg) {
    ++count;
    last_channel = channel;
    last = *msg;
    last_bytes.assign(static_cast<const uint8_t*>(rbuf->data),
                      static_cast<const uint8_t*>(rbuf->data) + rbuf->data_size);
  }
  int count = 0;
  std::string last_channel;
  detections_t last;
  std::vector<uint8_t> last_bytes;
};

TEST(LcmUtil, HandleUntilOverMemq) {
  auto lcm = OpenLcm("memq://");
  Counter counter;
  lcm->subscribe(kDetectionsChannelRegex, &Counter::OnDetections, &counter);
  for (int i = 0; i < 5; ++i) {
    const detections_t d = SampleDetections(i, "cam" + std::to_string(i), 1000 + i);
    lcm->publish(DetectionsChannel(d.camera), &d);
  }
  EXPECT_TRUE(HandleUntil(
      *lcm, [&] { return counter.count == 5; }, std::chrono::seconds(10)));
  EXPECT_EQ(counter.last_channel, "MCMT_DETECTIONS_CAM4");
  EXPECT_EQ(counter.last.utime, 1004);
  EXPECT_EQ(counter.last_bytes, Encode(SampleDetections(4, "cam4", 1004)));
  // Nothing more arrives: returns false at the timeout.
  EXPECT_FALSE(HandleUntil(
      *lcm, [&] { return counter.count == 6; }, std::chrono::milliseconds(100)));
  // Already done: returns at once without handling.
  EXPECT_TRUE(HandleUntil(
      *lcm, [] { return true; }, std::chrono::milliseconds(0)));
}

TEST(LcmUtil, HandleUntilEndsWithFileLog) {
  TempDir dir;
  const std::string path = dir.File("session.lcmlog");
  {
    lcm::LogFile log(path, "w");
    ASSERT_TRUE(log.good());
    for (int i = 0; i < 20; ++i) {
      const detections_t d = SampleDetections(i % 4, "cam" + std::to_string(i % 3), 1000 + i);
      const std::vector<uint8_t> bytes = Encode(d);
      lcm::LogEvent event;
      event.eventnum = i;
      event.timestamp = 1000 + i;
      event.channel = DetectionsChannel(d.camera);
      event.datalen = static_cast<int32_t>(bytes.size());
      event.data = const_cast<uint8_t*>(bytes.data());
      log.writeEvent(&event);
    }
  }
  auto lcm = OpenLcm(LogReadUrl(path));
  Counter counter;
  lcm->subscribe(kDetectionsChannelRegex, &Counter::OnDetections, &counter);
  // Never done: returns false when the log ends (the test's own timeout guards against a hang).
  EXPECT_FALSE(HandleUntil(
      *lcm, [] { return false; }, std::chrono::seconds(60)));
  EXPECT_EQ(counter.count, 20);
  EXPECT_EQ(counter.last.utime, 1019);
}

TEST(LcmUtil, OpenLcmNamesBadUrl) {
  try {
    OpenLcm("nonsense://nowhere");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("nonsense://nowhere"), std::string::npos) << e.what();
  }
  try {
    OpenLcm("file:///nonexistent/dir/x.lcmlog?speed=0");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/x.lcmlog"), std::string::npos) << e.what();
  }
  EXPECT_GT(NowUtime(), 1600000000000000LL);
}

}  // namespace
}  // namespace mcmt
