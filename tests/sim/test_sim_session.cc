// Detections-only sessions in memory (sim/session.cc): the same simulation as a generated dataset, a static
// body seen beside the object, the rig file and the log written from a session.
#include <gtest/gtest.h>

#include <set>

#include "core/config.h"
#include "core/files.h"
#include "core/lcm_util.h"
#include "core/log_reader.h"
#include "core/marker.h"
#include "sim/sim.h"
#include "tests/support/temp_dir.h"

namespace mcmt::sim {
namespace {

std::vector<detections_t> ReadMessages(const std::string& path, std::vector<int64_t>* timestamps = nullptr) {
  std::vector<detections_t> out;
  for (const LogEvent& e : ReadEventLog(path)) {
    detections_t d;
    EXPECT_GE(d.decode(e.data.data(), 0, static_cast<int>(e.data.size())), 0) << e.channel;
    EXPECT_EQ(e.channel, DetectionsChannel(d.camera));
    out.push_back(d);
    if (timestamps) timestamps->push_back(e.timestamp);
  }
  return out;
}

TEST(SimSession, HoldsTheMessagesAGeneratedDatasetLogs) {
  test::TempDir dir("sim_session");
  DatasetOptions o = DetectionsOnlySession(dir.path(), 40, 5);
  o.detections.corner_noise_px = 0.3;
  o.detections.false_rate = 0.2;
  o.detections.drop_rate = 0.1;
  GenerateDataset(o);
  SessionOptions so;
  so.rig = o.rig;
  so.object = o.object;
  so.trajectory = o.trajectory;
  so.detections = o.detections;
  const Session session = SimulateSession(so);
  const std::vector<detections_t> logged = ReadMessages(dir / "detections.lcmlog");
  const std::vector<detections_t> messages = session.Messages();
  ASSERT_EQ(messages.size(), logged.size());
  ASSERT_LT(messages.size(), 40u * 5u);  // some dropped
  for (size_t i = 0; i < messages.size(); ++i) EXPECT_EQ(Encode(messages[i]), Encode(logged[i])) << i;
  EXPECT_EQ(session.views.size(), 40u);
  EXPECT_EQ(session.Truth().markers.size(), session.object().markers.size());
  EXPECT_EQ(session.Truth().frames.size(), 40u);
}

TEST(SimSession, AStaticBodyIsSeenBesideTheObjectAndCamerasAreStaggered) {
  SessionOptions so;
  so.trajectory.frames = 30;
  Session base = SimulateSession(so);
  SceneBody fixed;
  fixed.name = "fixed";
  fixed.is_static = true;
  fixed.object.markers.push_back({77, 0.04, Rigid3::Identity()});
  fixed.object.radius = 0.03;
  fixed.frames = base.frames();
  for (SimFrame& f : fixed.frames) {  // on the floor below the object, facing up
    f.rig_from_object = Rigid3::Identity();
    f.rig_from_object.translation() = Eigen::Vector3d(0.2, -0.1, -0.15);
  }
  const Session s = SimulateSession(base.cameras, {base.bodies[0], fixed}, so.detections, 3, 500);
  int fixed_seen = 0;
  std::set<int> cameras_seeing_it;
  for (size_t f = 0; f < s.views.size(); ++f) {
    ASSERT_EQ(s.views[f].size(), s.cameras.size());
    for (size_t k = 0; k < s.views[f].size(); ++k) {
      const detections_t& d = s.views[f][k];
      EXPECT_EQ(d.utime, s.frames()[f].utime + static_cast<int64_t>(k) * 500);
      for (const marker_t& m : d.markers)
        if (m.id == 77) {
          ++fixed_seen;
          cameras_seeing_it.insert(static_cast<int>(k));
        }
    }
  }
  EXPECT_GT(fixed_seen, 30);
  EXPECT_GE(cameras_seeing_it.size(), 3u);
  EXPECT_THROW(SimulateSession(base.cameras, {}, so.detections, 3), std::invalid_argument);
  fixed.frames.pop_back();
  EXPECT_THROW(SimulateSession(base.cameras, {base.bodies[0], fixed}, so.detections, 3),
               std::invalid_argument);
}

TEST(SimSession, RigAndLogFilesReadBack) {
  test::TempDir dir("sim_session_files");
  SessionOptions so;
  so.object.kind = ObjectKind::kPentagon;
  so.object.marker_size = 0.025;
  so.trajectory.frames = 10;
  const Session s = SimulateSession(so);
  const RigConfig rig = LoadRigConfig(WriteSessionRig(dir.path(), s, "sync:\n  tolerance_ms: 4\n"));
  ASSERT_EQ(rig.cameras.size(), s.cameras.size());
  for (size_t k = 0; k < s.cameras.size(); ++k) {
    EXPECT_EQ(rig.cameras[k].name, s.cameras[k].name);
    EXPECT_NEAR(rig.cameras[k].model.fx, s.cameras[k].model.fx, 1e-9);
  }
  EXPECT_DOUBLE_EQ(rig.markers.Sizes().Get(s.object().markers[0].id), s.object().markers[0].size);
  EXPECT_EQ(rig.markers.dictionary, s.dictionary);
  const std::string log = dir / "d.lcmlog";
  const std::vector<detections_t> messages = s.Messages();
  EXPECT_EQ(
      WriteMessagesLog(log, messages, [](const detections_t& d) { return d.camera == "cam1" ? 70 : 0; }),
      static_cast<int64_t>(messages.size()));
  std::vector<int64_t> times;
  const std::vector<detections_t> back = ReadMessages(log, &times);
  ASSERT_EQ(back.size(), messages.size());
  for (size_t i = 0; i < back.size(); ++i) {
    EXPECT_EQ(Encode(back[i]), Encode(messages[i]));
    EXPECT_EQ(times[i], messages[i].utime + (messages[i].camera == "cam1" ? 70 : 0));
  }
}

// The cube with a grid of markers per face (the tracker's test rig): every marker flat on a face, inside it,
// the markers of one face a quarter side apart; ids in order; bad grid sizes named.
TEST(SimObject, CubeWithAGridOfMarkersPerFace) {
  sim::ObjectOptions o;
  o.kind = sim::ObjectKind::kCube;
  o.marker_size = 0.02;
  o.face_columns = 3;
  o.face_rows = 2;
  o.first_id = 5;
  const sim::SimObject cube = sim::MakeObject(o);
  ASSERT_EQ(cube.markers.size(), 36u);
  const double half = 0.5 * (3 * 0.025 - 0.005 + 0.02);
  for (size_t k = 0; k < cube.markers.size(); ++k) {
    const sim::SimMarker& m = cube.markers[k];
    EXPECT_EQ(m.id, 5 + static_cast<int>(k));
    const Eigen::Vector3d n = m.object_from_marker.linear().col(2);
    EXPECT_NEAR(n.cwiseAbs().maxCoeff(), 1.0, 1e-12) << "marker " << m.id << " not on a cube face";
    for (const auto& c : MarkerCornersInMarker(m.size)) {
      const Eigen::Vector3d p = m.object_from_marker * c;
      EXPECT_NEAR(p.dot(n), half, 1e-12) << "marker " << m.id << " off its face";
      EXPECT_LE(p.cwiseAbs().maxCoeff(), half + 1e-12) << "marker " << m.id << " over the face's edge";
    }
    for (size_t j = 0; j < k; ++j) {
      const sim::SimMarker& other = cube.markers[j];
      if (other.object_from_marker.linear().col(2).dot(n) < 0.5) continue;
      const double d = (other.object_from_marker.translation() - m.object_from_marker.translation()).norm();
      EXPECT_GE(d, 0.025 - 1e-12) << "markers " << other.id << " and " << m.id << " overlap";
    }
  }
  o.face_columns = 1, o.face_rows = 1;
  EXPECT_EQ(sim::MakeObject(o).markers.size(), 6u);
  o.face_rows = 0;
  try {
    sim::MakeObject(o);
    FAIL() << "no error for a 1 x 0 grid";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "cube: face_columns and face_rows must be >= 1 (got 1 x 0)");
  }
}

}  // namespace
}  // namespace mcmt::sim
