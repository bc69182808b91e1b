// Unit tests of the logger library: the event log format (and LCM's own reader/writer agreeing with it),
// damage handling, exports from logs (CSV, TUM, summary), CSV -> log round trip, map exports.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <opencv2/core.hpp>
#include <random>
#include <set>
#include <sstream>

#include "core/config.h"
#include "core/files.h"
#include "core/lcm_util.h"
#include "core/log_writer.h"
#include "core/marker.h"
#include "core/se3.h"
#include "logger/export.h"
#include "logger/session_logger.h"
#include "test_util.h"

using namespace mcmt;
using namespace mcmt_test;

namespace {

struct Msg {
  std::string channel;
  std::vector<uint8_t> data;
  int64_t timestamp;
};

// A mixed stream: 3 cameras x 20 frames (some without markers), poses, a foreign message.
std::vector<Msg> MakeStream() {
  std::vector<Msg> out;
  for (int64_t seq = 0; seq < 20; ++seq) {
    for (int c = 0; c < 3; ++c) {
      const std::string cam = "cam" + std::to_string(c);
      detections_t d = MakeDetections(cam, seq, (seq + c) % 4);  // 0..3 markers
      out.push_back({DetectionsChannel(cam), Encode(d), d.utime + 100 + c});
    }
    object_pose_t p = MakePose(seq, seq % 5 == 4 ? object_pose_t::STATUS_LOST
                                                 : (seq % 5 == 3 ? object_pose_t::STATUS_AMBIGUOUS
                                                                 : object_pose_t::STATUS_TRACKING));
    out.push_back({kPoseChannel, Encode(p), p.utime + 500});
  }
  return out;
}

std::string WriteLog(const std::string& path, const std::vector<Msg>& msgs) {
  EventLogWriter w(path);
  for (const Msg& m : msgs) w.Write(m.timestamp, m.channel, m.data.data(), m.data.size());
  w.Close();
  return path;
}

class TmpDirTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = MakeTempDir("unit"); }
  void TearDown() override { RemoveTree(dir_); }
  std::string dir_;
};

using EventLogTest = TmpDirTest;
using ExportTest = TmpDirTest;

}  // namespace

TEST_F(EventLogTest, WriterOutputIsReadByLcmsOwnReaderAndViceVersa) {
  const auto msgs = MakeStream();
  const std::string ours = WriteLog(dir_ + "/ours.lcmlog", msgs);
  // LCM's reader on our file.
  {
    lcm::LogFile f(ours, "r");
    ASSERT_TRUE(f.good());
    size_t i = 0;
    while (const lcm::LogEvent* e = f.readNextEvent()) {
      ASSERT_LT(i, msgs.size());
      EXPECT_EQ(e->channel, msgs[i].channel);
      EXPECT_EQ(e->timestamp, msgs[i].timestamp);
      EXPECT_EQ(e->eventnum, static_cast<int64_t>(i));
      ASSERT_EQ(static_cast<size_t>(e->datalen), msgs[i].data.size());
      EXPECT_EQ(0, std::memcmp(e->data, msgs[i].data.data(), msgs[i].data.size()));
      ++i;
    }
    EXPECT_EQ(i, msgs.size());
  }
  // LCM's writer, our reader.
  const std::string theirs = dir_ + "/theirs.lcmlog";
  {
    lcm::LogFile f(theirs, "w");
    ASSERT_TRUE(f.good());
    for (const Msg& m : msgs) {
      lcm::LogEvent e;
      e.timestamp = m.timestamp;
      e.channel = m.channel;
      e.datalen = static_cast<int32_t>(m.data.size());
      e.data = const_cast<uint8_t*>(m.data.data());
      ASSERT_EQ(0, f.writeEvent(&e));
    }
  }
  const auto events = ReadEventLog(theirs);
  ASSERT_EQ(events.size(), msgs.size());
  for (size_t i = 0; i < msgs.size(); ++i) {
    EXPECT_EQ(events[i].channel, msgs[i].channel);
    EXPECT_EQ(events[i].timestamp, msgs[i].timestamp);
    EXPECT_EQ(events[i].data, msgs[i].data);
  }
  // Byte-identical files: same format, same event numbers.
  EXPECT_EQ(ReadText(ours), ReadText(theirs));
}

TEST_F(EventLogTest, WriterNeverOverwrites) {
  const std::string path = dir_ + "/x.lcmlog";
  WriteText(path, "precious");
  try {
    EventLogWriter w(path);
    FAIL() << "expected a refusal";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("exists"), std::string::npos) << e.what();
  }
  EXPECT_EQ(ReadText(path), "precious");
}

TEST_F(EventLogTest, GarbageIsReportedWithFileAndOffset) {
  // Not a log at all.
  const std::string text = dir_ + "/text.lcmlog";
  WriteText(text, "this is not an LCM log, just text\n");
  try {
    ReadEventLog(text);
    FAIL();
  } catch (const LogFormatError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(text), std::string::npos) << what;
    EXPECT_NE(what.find("byte 0"), std::string::npos) << what;
    EXPECT_NE(what.find("not an LCM event log"), std::string::npos) << what;
  }
  // Garbage between two valid events: strict throws at the right offset, resync skips exactly it.
  const auto msgs = MakeStream();
  std::string good, first;
  AppendEncodedEvent(0, msgs[0].timestamp, msgs[0].channel, msgs[0].data.data(), msgs[0].data.size(), &first);
  good = first;
  const std::string junk = "GARBAGE-GARBAGE-GARBAGE";
  good += junk;
  AppendEncodedEvent(1, msgs[1].timestamp, msgs[1].channel, msgs[1].data.data(), msgs[1].data.size(), &good);
  const std::string mixed = dir_ + "/mixed.lcmlog";
  WriteText(mixed, good);
  try {
    ReadEventLog(mixed);
    FAIL();
  } catch (const LogFormatError& e) {
    EXPECT_NE(std::string(e.what()).find("byte " + std::to_string(first.size())), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("event 1"), std::string::npos) << e.what();
  }
  EventLogReader r(mixed, /*resync=*/true);
  LogEvent e;
  std::vector<LogEvent> got;
  while (r.Next(&e)) got.push_back(e);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[1].data, msgs[1].data);
  EXPECT_EQ(r.skipped_bytes(), junk.size());
  // A summary of it reports the damage but lists both events.
  LogSummary s = SummarizeLog(mixed);
  EXPECT_EQ(s.events, 2);
  EXPECT_EQ(s.skipped_bytes, junk.size());
  ASSERT_EQ(s.damage.size(), 1u);
  EXPECT_NE(FormatSummary(s).find("garbage"), std::string::npos);
}

TEST_F(EventLogTest, TruncatedTailEndsTheLogWithoutError) {
  const auto msgs = MakeStream();
  const std::string path = WriteLog(dir_ + "/t.lcmlog", msgs);
  const std::string full = ReadText(path);
  for (size_t cut : {size_t(3), size_t(20), size_t(40), size_t(200)}) {
    const std::string cut_path = dir_ + "/cut" + std::to_string(cut) + ".lcmlog";
    WriteText(cut_path, full.substr(0, full.size() - cut));
    EventLogReader r(cut_path);
    LogEvent e;
    int64_t n = 0;
    while (r.Next(&e)) ++n;
    EXPECT_EQ(n, static_cast<int64_t>(msgs.size()) - 1) << "cut " << cut;
    EXPECT_GT(r.truncated_tail_bytes(), 0u);
  }
}

TEST_F(EventLogTest, PartsAndSidecarNames) {
  EXPECT_EQ(LogPartName("/a/session.lcmlog", 3), "/a/session.03.lcmlog");
  EXPECT_EQ(LogPartName("/a.b/session", 0), "/a.b/session.00");
  EXPECT_EQ(SidecarPath("/a/session.lcmlog"), "/a/session.yaml");
  EXPECT_EQ(SidecarPath("/a.b/session"), "/a.b/session.yaml");
  const auto msgs = MakeStream();
  WriteLog(dir_ + "/s.00.lcmlog", {msgs.begin(), msgs.begin() + 10});
  WriteLog(dir_ + "/s.01.lcmlog", {msgs.begin() + 10, msgs.end()});
  const auto parts = LogParts(dir_ + "/s.lcmlog");
  ASSERT_EQ(parts.size(), 2u);
  EXPECT_EQ(SummarizeLog(dir_ + "/s.lcmlog").events, static_cast<int64_t>(msgs.size()));
  EXPECT_THROW(LogParts(dir_ + "/none.lcmlog"), LogFormatError);
}

// ---- exports from a log ------------------------------------------------------------------------------

TEST_F(ExportTest, PosesCsvAndTumHoldTheTrackedPoses) {
  const auto msgs = MakeStream();
  const std::string log = WriteLog(dir_ + "/p.lcmlog", msgs);
  LogExportRequest req;
  req.poses_csv = dir_ + "/poses.csv";
  req.tum = dir_ + "/poses.tum";
  LogExportResult r = ExportFromLog(log, req);
  EXPECT_EQ(r.pose_rows, 16);  // 20 frames, every 5th LOST
  EXPECT_EQ(r.poses_skipped, 4);
  const auto rows = ReadTrajectory(req.poses_csv);  // core's reader accepts it
  ASSERT_EQ(rows.size(), 16u);
  // Exactly the message's numbers, in the format core writes.
  {
    std::ifstream csv(req.poses_csv);
    std::string header, first;
    std::getline(csv, header);
    std::getline(csv, first);
    EXPECT_EQ(header, TrajectoryHeader(false, true));  // with the status and sigma columns
    const object_pose_t p0 = MakePose(0, 0);
    char expected[512];
    std::snprintf(expected, sizeof(expected), "%lld,0,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,2,3",
                  static_cast<long long>(p0.utime), p0.rig_from_object.position[0],
                  p0.rig_from_object.position[1], p0.rig_from_object.position[2],
                  p0.rig_from_object.orientation[0], p0.rig_from_object.orientation[1],
                  p0.rig_from_object.orientation[2], p0.rig_from_object.orientation[3], p0.rms_px);
    EXPECT_EQ(first.substr(0, first.find(",tracking,")), expected);
  }
  // The status and worst-direction sigmas of each message's covariance (1e-6 on the diagonal): rotation
  // 1 mrad; the origin at t moves by the rotation's lever arm too, variance 1e-6 (1 + |t|^2) at most.
  EXPECT_FALSE(rows[0].quality->ambiguous);
  EXPECT_NEAR(rows[0].quality->sigma_rotation_rad, 1e-3, 1e-15);
  EXPECT_NEAR(rows[0].quality->sigma_position_m, 1e-3 * std::sqrt(1.0 + 0.04 + 2.25), 1e-15);
  std::ifstream tum(req.tum);
  std::string line;
  std::getline(tum, line);
  EXPECT_EQ(line[0], '#');
  size_t i = 0;
  for (int64_t seq = 0; seq < 20; ++seq) {
    if (seq % 5 == 4) continue;
    const object_pose_t p = MakePose(seq, 0);
    ASSERT_LT(i, rows.size());
    EXPECT_EQ(rows[i].utime, p.utime);
    EXPECT_EQ(rows[i].seq, seq);
    EXPECT_NEAR(rows[i].rig_from_object.translation().x(), p.rig_from_object.position[0], 1e-12);
    EXPECT_NEAR(rows[i].rig_from_object.translation().y(), p.rig_from_object.position[1], 1e-12);
    const Rigid3 expected = FromPose3d(p.rig_from_object);
    EXPECT_LT(RotationAngle(rows[i].rig_from_object, expected), 1e-12);
    EXPECT_NEAR(rows[i].rms_px, p.rms_px, 1e-12);
    EXPECT_EQ(rows[i].cameras, 2);
    EXPECT_EQ(rows[i].markers, 3);
    ASSERT_TRUE(std::getline(tum, line));
    std::istringstream s(line);
    double t, x, y, z, qx, qy, qz, qw;
    ASSERT_TRUE(static_cast<bool>(s >> t >> x >> y >> z >> qx >> qy >> qz >> qw)) << line;
    EXPECT_NEAR(t, p.utime * 1e-6, 1e-6);
    EXPECT_EQ(x, p.rig_from_object.position[0]);
    EXPECT_EQ(y, p.rig_from_object.position[1]);
    EXPECT_EQ(qw, p.rig_from_object.orientation[0]);
    EXPECT_EQ(qz, p.rig_from_object.orientation[3]);
    ++i;
  }
  EXPECT_FALSE(std::getline(tum, line));
}

TEST_F(ExportTest, ForeignTypeOnADetectionsChannelIsAClearError) {
  auto msgs = MakeStream();
  object_pose_t p = MakePose(1, 0);
  msgs.insert(msgs.begin() + 5, Msg{"MCMT_DETECTIONS_CAM9", Encode(p), 1});
  const std::string log = WriteLog(dir_ + "/f.lcmlog", msgs);
  LogExportRequest req;
  req.detections_csv = dir_ + "/det.csv";
  try {
    ExportFromLog(log, req);
    FAIL();
  } catch (const LogFormatError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("f.lcmlog: event 5"), std::string::npos) << what;
    EXPECT_NE(what.find("MCMT_DETECTIONS_CAM9"), std::string::npos) << what;
    EXPECT_NE(what.find("detections_t"), std::string::npos) << what;
    EXPECT_NE(what.find("object_pose_t"), std::string::npos) << what;  // says what it found
  }
  EXPECT_FALSE(FileExists(req.detections_csv));  // nothing half-written
  // The summary lists it instead.
  LogSummary s = SummarizeLog(log);
  EXPECT_EQ(s.channels["MCMT_DETECTIONS_CAM9"].undecodable, 1);
  EXPECT_EQ(s.channels["MCMT_DETECTIONS_CAM9"].type, "mcmt.object_pose_t");
}

TEST_F(ExportTest, SummaryCountsCamerasIdsAndGaps) {
  std::vector<Msg> msgs;
  std::set<int> ids;
  for (int64_t seq : {0, 1, 2, 5, 6, 9}) {  // missing 3-4 and 7-8
    detections_t d = MakeDetections("left", seq, 2);
    for (const auto& m : d.markers) ids.insert(m.id);
    msgs.push_back({DetectionsChannel("left"), Encode(d), d.utime});
  }
  std::vector<uint8_t> foreign = {1, 2, 3, 4, 5, 6, 7, 8, 9};
  msgs.push_back({"SOMEONE_ELSE", foreign, 1700000000200000LL});
  const std::string log = WriteLog(dir_ + "/g.lcmlog", msgs);
  LogSummary s = SummarizeLog(log);
  ASSERT_EQ(s.cameras.size(), 1u);
  const CameraSummary& c = s.cameras["left"];
  EXPECT_EQ(c.frames, 6);
  EXPECT_EQ(c.missing, 4);
  ASSERT_EQ(c.gaps.size(), 2u);
  EXPECT_EQ(c.gaps[0], (std::pair<int64_t, int64_t>(3, 4)));
  EXPECT_EQ(c.gaps[1], (std::pair<int64_t, int64_t>(7, 8)));
  EXPECT_EQ(s.marker_ids, ids);
  EXPECT_NE(s.channels["SOMEONE_ELSE"].type.find("unknown"), std::string::npos);
  const std::string text = FormatSummary(s);
  EXPECT_NE(text.find("3..4 7..8"), std::string::npos) << text;
  EXPECT_NE(text.find("MCMT_DETECTIONS_LEFT"), std::string::npos) << text;
}

// ---- detections CSV <-> log ---------------------------------------------------------------------------

namespace {
CameraModel TestModel(int i) {
  CameraModel m;
  m.width = 640;
  m.height = 480;
  m.fx = 500 + i;
  m.fy = 501 + i;
  m.cx = 319.5;
  m.cy = 239.5;
  m.model = DistortionModel::kRadTan;
  m.distortion = {0.01, -0.02, 0.001, 0.002, 0.003};
  return m;
}

std::string WriteRig(const std::string& dir, int cameras) {
  std::string yaml = "markers:\n  dictionary: DICT_6X6_250\n  size: 0.04\ncameras:\n";
  for (int i = 0; i < cameras; ++i) {
    WriteIntrinsicsOpenCv(dir + "/cam" + std::to_string(i) + ".yml", TestModel(i));
    yaml += "  - name: cam" + std::to_string(i) + "\n    intrinsics: cam" + std::to_string(i) + ".yml\n";
  }
  WriteText(dir + "/rig.yaml", yaml);
  return dir + "/rig.yaml";
}
}  // namespace

TEST_F(ExportTest, DetectionsCsvToLogToCsvIsIdentical) {
  const RigConfig rig = LoadRigConfig(WriteRig(dir_, 3));
  std::vector<Msg> msgs;
  for (int64_t seq = 0; seq < 15; ++seq)
    for (int c = 0; c < 3; ++c) {
      const std::string cam = "cam" + std::to_string(c);
      detections_t d = MakeDetections(cam, seq, (seq + c) % 4);
      d.camera_model = ToCameraModelMsg(rig.cameras[c].model);
      msgs.push_back({DetectionsChannel(cam), Encode(d), d.utime});
    }
  const std::string log = WriteLog(dir_ + "/a.lcmlog", msgs);
  LogExportRequest req;
  req.detections_csv = dir_ + "/a.csv";
  LogExportResult r1 = ExportFromLog(log, req);
  EXPECT_GT(r1.detection_rows, 40);

  CsvToLogResult back = DetectionsCsvToLog(req.detections_csv, rig, dir_ + "/b.lcmlog");
  EXPECT_EQ(back.rows, r1.detection_rows);
  req.detections_csv = dir_ + "/b.csv";
  ExportFromLog(dir_ + "/b.lcmlog", req);
  EXPECT_EQ(ReadText(dir_ + "/a.csv"), ReadText(dir_ + "/b.csv"));

  // The messages that come back are the originals with markers (detection_ms is not in the CSV).
  const auto events = ReadEventLog(dir_ + "/b.lcmlog");
  size_t j = 0;
  for (const Msg& m : msgs) {
    detections_t orig = DecodeOrThrow<detections_t>(m.data.data(), m.data.size());
    if (orig.num_markers == 0) continue;
    ASSERT_LT(j, events.size());
    EXPECT_EQ(events[j].channel, m.channel);
    detections_t got = DecodeOrThrow<detections_t>(events[j].data.data(), events[j].data.size());
    orig.detection_ms = 0;
    EXPECT_EQ(Encode(got), Encode(orig)) << "message " << j;
    ++j;
  }
  EXPECT_EQ(j, events.size());

  // Never overwrites its output.
  EXPECT_THROW(DetectionsCsvToLog(dir_ + "/a.csv", rig, dir_ + "/b.lcmlog"), std::runtime_error);
}

TEST_F(ExportTest, BadCsvNamesLineAndColumn) {
  const RigConfig rig = LoadRigConfig(WriteRig(dir_, 2));
  auto expect_error = [&](const std::string& body, const std::string& needle) {
    const std::string csv = dir_ + "/bad.csv";
    WriteText(csv, body);
    const std::string out = dir_ + "/bad.lcmlog";
    try {
      DetectionsCsvToLog(csv, rig, out);
      ADD_FAILURE() << "no error for: " << body;
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
    EXPECT_FALSE(FileExists(out));
  };
  const std::string h = std::string(kDetectionsCsvHeader) + "\n";
  expect_error("utime,seq\n", "bad.csv:1: expected the header");
  expect_error(h + "1,2,cam0,3,1,2,3,4,5,6,7,8\n1,2,cam0,4,1,2,3,4,5,6,7\n",
               "bad.csv:3: expected 12 columns");
  expect_error(h + "1,2,cam0,3,1,2,3,abc,5,6,7,8\n", "bad.csv:2: y1: expected a number, got 'abc'");
  expect_error(h + "1,2,camX,3,1,2,3,4,5,6,7,8\n", "bad.csv:2: camera 'camX' is not in");
  expect_error(h + "1.5,2,cam0,3,1,2,3,4,5,6,7,8\n", "bad.csv:2: utime: expected an integer");
}

// ---- map exports ----------------------------------------------------------------------------------------

namespace {
RigMap MakeMap() {
  std::mt19937_64 rng(7);
  RigMap map;
  map.dictionary = "DICT_6X6_250";
  map.reference_camera = "cam0";
  map.reference_marker = 3;
  for (int i = 0; i < 3; ++i) {
    MapCamera c;
    c.name = "cam" + std::to_string(i);
    c.model = TestModel(i);
    if (i == 1) {
      c.model.model = DistortionModel::kFisheye;
      c.model.distortion = {0.1, -0.01, 0.002, -0.0003};
    }
    if (i == 2) {
      c.model.model = DistortionModel::kNone;
      c.model.distortion.clear();
    }
    c.rig_from_cam = i == 0 ? Rigid3::Identity() : RandomRigid(rng, 2.0);
    map.cameras.push_back(c);
  }
  for (int id : {3, 5, 11, 12}) {
    MapMarker m;
    m.id = id;
    m.size = id == 11 ? 0.03 : 0.04;
    m.object_from_marker = id == 3 ? Rigid3::Identity() : RandomRigid(rng, 0.1);
    map.markers.push_back(m);
  }
  map.rms_px = 0.42;
  return map;
}

Eigen::Matrix4d MatrixFromRows(const YAML::Node& rows) {
  Eigen::Matrix4d m;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) m(r, c) = rows[r][c].as<double>();
  return m;
}
}  // namespace

TEST_F(ExportTest, KalibrCamchainParsesBackWithTheRightNumbers) {
  RigMap map = MakeMap();
  map.cameras[0].model.distortion[4] = 0.0;  // k3 = 0: representable in Kalibr's radtan
  YAML::Node y = YAML::Load(KalibrCamchain(map));
  ASSERT_EQ(y.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    const YAML::Node c = y["cam" + std::to_string(i)];
    ASSERT_TRUE(c) << i;
    const CameraModel& m = map.cameras[i].model;
    EXPECT_EQ(c["camera_model"].as<std::string>(), "pinhole");
    EXPECT_EQ(c["intrinsics"][0].as<double>(), m.fx);
    EXPECT_EQ(c["intrinsics"][1].as<double>(), m.fy);
    EXPECT_EQ(c["intrinsics"][2].as<double>(), m.cx);
    EXPECT_EQ(c["intrinsics"][3].as<double>(), m.cy);
    EXPECT_EQ(c["resolution"][0].as<int>(), m.width);
    EXPECT_EQ(c["rostopic"].as<std::string>(), "/cam" + std::to_string(i) + "/image_raw");
    if (i == 1) {
      EXPECT_EQ(c["distortion_model"].as<std::string>(), "equidistant");
      for (int k = 0; k < 4; ++k) EXPECT_EQ(c["distortion_coeffs"][k].as<double>(), m.distortion[k]);
    } else {
      EXPECT_EQ(c["distortion_model"].as<std::string>(), "radtan");
      for (int k = 0; k < 4; ++k)
        EXPECT_EQ(c["distortion_coeffs"][k].as<double>(), i == 0 ? m.distortion[k] : 0.0);
    }
    if (i > 0) {
      const Eigen::Matrix4d t = MatrixFromRows(c["T_cn_cnm1"]);
      const Eigen::Matrix4d expected =
          (Inverse(map.cameras[i].rig_from_cam) * map.cameras[i - 1].rig_from_cam).matrix();
      EXPECT_LT((t - expected).cwiseAbs().maxCoeff(), 1e-15);
    } else {
      EXPECT_FALSE(c["T_cn_cnm1"]);
    }
  }
  // The chain recovers camera 2 in the reference frame.
  const Eigen::Matrix4d c1_from_c0 = MatrixFromRows(y["cam1"]["T_cn_cnm1"]);
  const Eigen::Matrix4d c2_from_c1 = MatrixFromRows(y["cam2"]["T_cn_cnm1"]);
  const Eigen::Matrix4d rig_from_c2 = (c2_from_c1 * c1_from_c0).inverse();
  EXPECT_LT((rig_from_c2 - map.cameras[2].rig_from_cam.matrix()).cwiseAbs().maxCoeff(), 1e-12);
  // A radtan k3 Kalibr cannot hold is refused, not dropped.
  map.cameras[0].model.distortion[4] = 0.5;
  EXPECT_THROW(KalibrCamchain(map), std::runtime_error);
}

TEST_F(ExportTest, RosDirParsesBackWithTheRightNumbers) {
  const RigMap map = MakeMap();
  WriteRosDir(map, dir_ + "/ros");
  for (int i = 0; i < 3; ++i) {
    const MapCamera& c = map.cameras[i];
    const std::string path = dir_ + "/ros/" + c.name + ".yaml";
    YAML::Node y = YAML::LoadFile(path);
    EXPECT_EQ(y["camera_name"].as<std::string>(), c.name);
    EXPECT_EQ(y["image_width"].as<int>(), 640);
    EXPECT_EQ(y["camera_matrix"]["data"][0].as<double>(), c.model.fx);
    EXPECT_EQ(y["camera_matrix"]["data"][2].as<double>(), c.model.cx);
    EXPECT_EQ(y["camera_matrix"]["data"][4].as<double>(), c.model.fy);
    EXPECT_EQ(y["projection_matrix"]["data"].size(), 12u);
    EXPECT_EQ(y["distortion_model"].as<std::string>(), i == 1 ? "equidistant" : "plumb_bob");
    // core's ROS camera_info reader gets the same camera back (none -> plumb_bob zeros: same pixels).
    const CameraModel back = LoadIntrinsics(path);
    EXPECT_EQ(back.fx, c.model.fx);
    EXPECT_EQ(back.cy, c.model.cy);
    const Eigen::Vector3d p(0.3, -0.2, 1.0);
    EXPECT_LT((back.Project(p) - c.model.Project(p)).norm(), 1e-9) << c.name;
  }
  YAML::Node st = YAML::LoadFile(dir_ + "/ros/static_transforms.yaml");
  ASSERT_EQ(st["transforms"].size(), 7u);
  for (const YAML::Node& t : st["transforms"]) {
    const std::string child = t["child_frame_id"].as<std::string>();
    Rigid3 expected;
    if (child.rfind("marker_", 0) == 0) {
      EXPECT_EQ(t["frame_id"].as<std::string>(), "mcmt_object");
      expected = map.FindMarker(std::stoi(child.substr(7)))->object_from_marker;
    } else {
      EXPECT_EQ(t["frame_id"].as<std::string>(), "mcmt_rig");
      expected = map.FindCamera(child.substr(0, child.find("_optical_frame")))->rig_from_cam;
    }
    const Eigen::Vector3d p(t["translation"][0].as<double>(), t["translation"][1].as<double>(),
                            t["translation"][2].as<double>());
    const std::array<double, 4> wxyz = {
        t["rotation_xyzw"][3].as<double>(), t["rotation_xyzw"][0].as<double>(),
        t["rotation_xyzw"][1].as<double>(), t["rotation_xyzw"][2].as<double>()};
    const Rigid3 got = RigidFromQuaternion(wxyz, p);
    EXPECT_LT(TranslationDistance(got, expected), 1e-12) << child;
    EXPECT_LT(RotationAngle(got, expected), 1e-9) << child;
  }
  const std::string txt = ReadText(dir_ + "/ros/static_transforms.txt");
  EXPECT_NE(txt.find("--frame-id mcmt_rig --child-frame-id cam1_optical_frame"), std::string::npos);
}

TEST_F(ExportTest, OpenCvYamlParsesBackWithFileStorage) {
  const RigMap map = MakeMap();
  WriteFileAtomic(dir_ + "/map.yml", OpenCvMapYaml(map));
  cv::FileStorage fs(dir_ + "/map.yml", cv::FileStorage::READ);
  ASSERT_TRUE(fs.isOpened());
  EXPECT_EQ(static_cast<std::string>(fs["reference_camera"]), "cam0");
  EXPECT_EQ(static_cast<int>(fs["reference_marker"]), 3);
  cv::FileNode cams = fs["cameras"];
  ASSERT_EQ(cams.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    const MapCamera& c = map.cameras[i];
    cv::FileNode n = cams[i];
    EXPECT_EQ(static_cast<std::string>(n["name"]), c.name);
    cv::Mat k, d, t;
    n["camera_matrix"] >> k;
    n["distortion_coefficients"] >> d;
    n["rig_from_cam"] >> t;
    EXPECT_EQ(k.at<double>(0, 0), c.model.fx);
    EXPECT_EQ(k.at<double>(1, 2), c.model.cy);
    if (i == 1) {
      EXPECT_EQ(static_cast<std::string>(n["distortion_model"]), "fisheye");
      ASSERT_EQ(d.total(), 4u);
      EXPECT_EQ(d.at<double>(0, 3), c.model.distortion[3]);
    }
    for (int r = 0; r < 4; ++r)
      for (int col = 0; col < 4; ++col) EXPECT_EQ(t.at<double>(r, col), c.rig_from_cam.matrix()(r, col));
  }
  cv::FileNode markers = fs["markers"];
  ASSERT_EQ(markers.size(), 4u);
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(static_cast<int>(markers[i]["id"]), map.markers[i].id);
    EXPECT_EQ(static_cast<double>(markers[i]["size"]), map.markers[i].size);
    cv::Mat t;
    markers[i]["object_from_marker"] >> t;
    EXPECT_EQ(t.at<double>(0, 3), map.markers[i].object_from_marker.translation().x());
  }
}

TEST_F(ExportTest, PlyAndObjHoldTheMarkerSquaresFacingOut) {
  const RigMap map = MakeMap();
  // PLY
  std::istringstream ply(MarkersPly(map));
  std::string line;
  int vertices = 0, faces = 0;
  while (std::getline(ply, line) && line != "end_header") {
    if (line.rfind("element vertex", 0) == 0) vertices = std::stoi(line.substr(15));
    if (line.rfind("element face", 0) == 0) faces = std::stoi(line.substr(13));
  }
  ASSERT_EQ(vertices, 16);
  ASSERT_EQ(faces, 4);
  std::vector<Eigen::Vector3d> v(vertices);
  for (auto& p : v) ply >> p.x() >> p.y() >> p.z();
  for (int f = 0; f < faces; ++f) {
    int n, a, b, c, d, id;
    ply >> n >> a >> b >> c >> d >> id;
    ASSERT_EQ(n, 4);
    const MapMarker* m = map.FindMarker(id);
    ASSERT_NE(m, nullptr);
    // Every corner of the marker is a vertex of its face.
    const MarkerCorners3d corners = MarkerCornersInMarker(m->size);
    for (const auto& corner : corners) {
      const Eigen::Vector3d p = m->object_from_marker * corner;
      const double best =
          std::min({(v[a] - p).norm(), (v[b] - p).norm(), (v[c] - p).norm(), (v[d] - p).norm()});
      EXPECT_LT(best, 1e-15);
    }
    // Counter-clockwise seen from +z of the marker: normal along the marker's z axis.
    const Eigen::Vector3d normal = (v[b] - v[a]).cross(v[c] - v[a]).normalized();
    EXPECT_GT(normal.dot(m->object_from_marker.linear().col(2)), 0.999999);
    EXPECT_NEAR((v[b] - v[a]).norm(), m->size, 1e-12);
  }
  // OBJ: same vertices, 1-based faces.
  std::istringstream obj(MarkersObj(map));
  std::vector<Eigen::Vector3d> ov;
  int obj_faces = 0;
  while (std::getline(obj, line)) {
    std::istringstream s(line);
    std::string tag;
    s >> tag;
    if (tag == "v") {
      Eigen::Vector3d p;
      s >> p.x() >> p.y() >> p.z();
      ov.push_back(p);
    } else if (tag == "f") {
      int a, b, c;
      s >> a >> b >> c;
      const Eigen::Vector3d normal = (ov[b - 1] - ov[a - 1]).cross(ov[c - 1] - ov[a - 1]).normalized();
      EXPECT_GT(normal.dot(map.markers[obj_faces].object_from_marker.linear().col(2)), 0.999999);
      ++obj_faces;
    }
  }
  EXPECT_EQ(obj_faces, 4);
  ASSERT_EQ(ov.size(), v.size());
  for (size_t i = 0; i < v.size(); ++i) EXPECT_EQ(ov[i], v[i]);
}

TEST_F(ExportTest, MapFromALogIsTheLastRigMapOnMcmtMap) {
  RigMap first = MakeMap();
  RigMap second = MakeMap();
  second.reference_camera = "cam1";
  second.cameras[1].rig_from_cam = Rigid3::Identity();
  second.rms_px = 0.25;
  std::vector<Msg> msgs = MakeStream();
  msgs.push_back({kMapChannel, Encode(ToRigMapMsg(first, 1)), 1});
  msgs.push_back({kMapChannel, Encode(ToRigMapMsg(second, 2)), 2});
  const std::string log = WriteLog(dir_ + "/m.lcmlog", msgs);
  const RigMap got = ReadMapOrLog(log);
  EXPECT_EQ(got.reference_camera, "cam1");
  EXPECT_EQ(got.rms_px, 0.25);
  ASSERT_EQ(got.cameras.size(), 3u);
  EXPECT_LT(
      (got.cameras[2].rig_from_cam.matrix() - second.cameras[2].rig_from_cam.matrix()).cwiseAbs().maxCoeff(),
      1e-12);
  EXPECT_EQ(got.cameras[1].model.model, DistortionModel::kFisheye);
  ASSERT_EQ(got.markers.size(), 4u);
  EXPECT_EQ(got.markers[2].size, 0.03);
  // A log without a map says so.
  const std::string no_map = WriteLog(dir_ + "/n.lcmlog", MakeStream());
  try {
    ReadMapOrLog(no_map);
    FAIL();
  } catch (const LogFormatError& e) {
    EXPECT_NE(std::string(e.what()).find("n.lcmlog: no map (rig_map2_t or rig_map_t) on MCMT_MAP"),
              std::string::npos)
        << e.what();
  }
  // A map.yaml still reads as a map.
  WriteMap(dir_ + "/map.yaml", first);
  EXPECT_EQ(ReadMapOrLog(dir_ + "/map.yaml").reference_camera, "cam0");
}

// ---- every output that can be written is written -----------------------------------------------------

// The caliscope intrinsics have a non-zero k3: --kalibr aborted the whole command, so --opencv, --ply and
// --ros-dir asked together were not written either.
TEST_F(ExportTest, AnInexpressibleModelRefusesOnlyItsOutputAndTheOthersAreWritten) {
  const RigMap map = MakeMap();
  ASSERT_NE(map.cameras[0].model.distortion[4], 0.0);  // radtan k3
  const std::string map_yaml = dir_ + "/map.yaml";
  WriteMap(map_yaml, map);
  std::string out, err;
  const int code =
      RunProgram({Bin("mcmt-export"), "--map", map_yaml, "--kalibr", dir_ + "/camchain.yaml", "--opencv",
                  dir_ + "/map.yml", "--ply", dir_ + "/object.ply", "--ros-dir", dir_ + "/ros"},
                 &out, &err);
  EXPECT_EQ(code, 1) << err;
  EXPECT_FALSE(FileExists(dir_ + "/camchain.yaml"));
  EXPECT_TRUE(FileExists(dir_ + "/map.yml"));
  EXPECT_TRUE(FileExists(dir_ + "/object.ply"));
  EXPECT_TRUE(FileExists(dir_ + "/ros/cam0.yaml"));
  EXPECT_TRUE(FileExists(dir_ + "/ros/static_transforms.yaml"));
  // One line, naming the output, the camera, the coefficient and why.
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  EXPECT_NE(err.find("--kalibr " + dir_ +
                     "/camchain.yaml: not written: Kalibr camchain: camera cam0: radtan "
                     "coefficient k3 = "),
            std::string::npos)
      << err;
  EXPECT_NE(err.find("Kalibr's radtan has 4 coefficients"), std::string::npos) << err;
}

TEST_F(ExportTest, RosCameraInfoRefusesCoefficientsBeyondRationalPolynomialAndWritesNothing) {
  RigMap map = MakeMap();
  map.cameras[2].model.model = DistortionModel::kRadTan;
  map.cameras[2].model.distortion = {0.1, 0.01, 0, 0, 0.001, 0, 0, 0, 0.0005, 0, 0, 0};  // thin prism s1
  try {
    WriteRosDir(map, dir_ + "/ros");
    FAIL() << "expected a refusal";
  } catch (const MapExportRefused& e) {
    EXPECT_NE(std::string(e.what()).find("camera cam2: radtan coefficient s1 = 0.0005"), std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(FileExists(dir_ + "/ros"));  // refused before the first file
  // Every format of the table is reachable by its option name.
  std::set<std::string> options;
  for (const MapExportFormat& f : MapExportFormats()) options.insert(f.option);
  EXPECT_EQ(options, (std::set<std::string>{"kalibr", "ros-dir", "opencv", "ply", "obj"}));
}

// TUM and poses exports worked only on logs holding MCMT_POSE; the mapper's trajectory.csv was refused.
TEST_F(ExportTest, TumAndPosesFromATrajectoryCsv) {
  std::vector<TrajectoryRow> rows;
  for (int i = 0; i < 5; ++i) {
    TrajectoryRow r;
    r.utime = 1700000000000000 + i * 33333;
    r.seq = i;
    r.rig_from_object = FromPose3d(MakePose(i, 0).rig_from_object);
    r.rms_px = 0.1 * i;
    r.cameras = 2;
    r.markers = 4;
    rows.push_back(r);
  }
  const std::string traj = dir_ + "/trajectory.csv";
  WriteTrajectory(traj, rows);
  std::string out, err;
  // --log given the CSV is read as --trajectory.
  ASSERT_EQ(
      RunProgram({Bin("mcmt-export"), "--log", traj, "--tum", dir_ + "/t.tum", "--poses", dir_ + "/p.csv"},
                 &out, &err),
      0)
      << err;
  EXPECT_EQ(ReadText(dir_ + "/p.csv"), ReadText(traj));
  std::istringstream tum(ReadText(dir_ + "/t.tum"));
  std::string line;
  std::getline(tum, line);
  EXPECT_EQ(line[0], '#');
  for (const TrajectoryRow& r : rows) {
    ASSERT_TRUE(std::getline(tum, line));
    std::istringstream s(line);
    double t, x, y, z, qx, qy, qz, qw;
    ASSERT_TRUE(static_cast<bool>(s >> t >> x >> y >> z >> qx >> qy >> qz >> qw)) << line;
    EXPECT_NEAR(t, r.utime * 1e-6, 1e-6);
    EXPECT_EQ(x, r.rig_from_object.translation().x());
    const auto q = QuaternionWxyz(r.rig_from_object);
    EXPECT_EQ(qw, q[0]);
    EXPECT_EQ(qz, q[3]);
  }
  EXPECT_FALSE(std::getline(tum, line));
}

// A log without MCMT_POSE gave an empty TUM file and no word why.
TEST_F(ExportTest, AnEmptyPosesExportSaysWhyAndWhereThePosesAre) {
  std::vector<Msg> msgs;
  for (int64_t seq = 0; seq < 3; ++seq)
    msgs.push_back({DetectionsChannel("cam0"), Encode(MakeDetections("cam0", seq, 2)), 1000 + seq});
  const std::string log = WriteLog(dir_ + "/d.lcmlog", msgs);
  std::string out, err;
  ASSERT_EQ(RunProgram({Bin("mcmt-export"), "--log", log, "--tum", dir_ + "/t.tum"}, &out, &err), 0) << err;
  EXPECT_NE(err.find("t.tum is empty: no object_pose_t on MCMT_POSE in " + log), std::string::npos) << err;
  EXPECT_NE(err.find("--trajectory OUTDIR/trajectory.csv"), std::string::npos) << err;
}

// The caliscope recordings' own intrinsics (configs/caliscope, k3 = -0.0037): Kalibr refuses them
// naming k3; ROS (plumb_bob, 5 coefficients) and OpenCV hold them exactly.
TEST_F(ExportTest, CaliscopeIntrinsicsHaveNoKalibrCamchainButRosAndOpenCvHoldThem) {
  RigMap map = MakeMap();
  map.cameras.resize(1);
  map.cameras[0].model = LoadIntrinsics(std::string(MCMT_SOURCE_DIR) + "/configs/caliscope/4cam_cam0.yml");
  ASSERT_EQ(map.cameras[0].model.distortion.size(), 5u);
  try {
    KalibrCamchain(map);
    FAIL() << "expected a refusal";
  } catch (const MapExportRefused& e) {
    EXPECT_NE(std::string(e.what()).find("camera cam0: radtan coefficient k3 = -0.0037489346582201062"),
              std::string::npos)
        << e.what();
  }
  const YAML::Node ros = YAML::Load(RosCameraInfo(map.cameras[0]));
  EXPECT_EQ(ros["distortion_model"].as<std::string>(), "plumb_bob");
  for (int k = 0; k < 5; ++k)
    EXPECT_EQ(ros["distortion_coefficients"]["data"][k].as<double>(), map.cameras[0].model.distortion[k]);
  EXPECT_NO_THROW(OpenCvMapYaml(map));
}
