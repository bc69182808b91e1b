// Each stage of the mapper's pipeline (mapper/stages.h) alone, on hand-made inputs or on the simulator's
// sessions (tests/support/mapper_sim.h), against ground truth.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <random>
#include <utility>

#include "core/ippe.h"
#include "core/lcm_util.h"
#include "core/marker.h"
#include "core/se3.h"
#include "mapper/stages.h"
#include "sim/eval.h"
#include "tests/support/mapper_sim.h"

namespace mcmt {
namespace {

constexpr double kDeg = M_PI / 180.0;

StoredMessage Message(int64_t utime, int camera, std::vector<int> ids) {
  StoredMessage m;
  m.utime = utime;
  m.seq = utime / 1000;
  m.camera = camera;
  for (int id : ids) m.markers.push_back({id, MarkerCorners2d()});
  return m;
}

std::vector<StoredMessage> MessagesOf(const std::vector<detections_t>& messages,
                                      const std::vector<std::string>& names) {
  std::vector<StoredMessage> out;
  for (const detections_t& d : messages) {
    StoredMessage m;
    m.utime = d.utime;
    m.seq = d.seq;
    m.camera = static_cast<int>(std::find(names.begin(), names.end(), d.camera) - names.begin());
    for (const marker_t& mk : d.markers) m.markers.push_back({mk.id, CornersOf(mk)});
    out.push_back(m);
  }
  return out;
}

// The session carried through the stages up to the initial object poses.
struct Pipeline {
  sim::Session session;
  sim::GroundTruth truth;
  std::vector<std::string> names;
  std::vector<CameraModel> models;
  MapperOptions options;
  std::vector<StoredMessage> messages;
  std::vector<Frame> frames;
  Observations observations;
  MapReport report;
  MarkerLayout layout;
  std::vector<ViewPose> views;
  CameraPlacement cameras;
  ObjectPoses poses;

  explicit Pipeline(const sim::SessionOptions& o) : Pipeline(sim::SimulateSession(o)) {}
  explicit Pipeline(sim::Session s) : session(std::move(s)), truth(session.Truth()) {
    for (const sim::SimCamera& c : session.cameras) {
      names.push_back(c.name);
      models.push_back(c.model);
    }
    options = test::MapperOptionsFor(truth);
    messages = MessagesOf(session.Messages(), names);
    frames = AssembleFrames(messages, static_cast<int>(names.size()), options.sync_tolerance_us());
    observations = CollectObservations(messages, frames, names, options, &report);
    EstimateHypotheses(models, options.tau_e, 2, &observations);
    layout = BuildMarkerGraph(observations, options, 2, &report);
    views = FitViews(observations, layout, models, 2);
    cameras = BuildCameraGraph(views, observations, names, options, 2, &report);
    poses = InitialObjectPoses(observations, frames, layout, cameras, options, 2, &report);
  }
  ObservationNames Names() const { return {&frames, &names, &observations.marker_ids}; }
  int MarkerOf(int id) const { return observations.marker_index.at(id); }
  const Rigid3& ObjectFromMarker(int id) const { return truth.FindMarker(id)->object_from_marker; }
  const Rigid3& RigFromCam(int camera) const { return session.cameras[camera].rig_from_cam; }
};

sim::SessionOptions Scene(int frames = 80) { return test::MapperSession(frames, 1, 0.2); }

TEST(MapperStages, AssembleFramesJoinsWithinToleranceOneMessagePerCamera) {
  const std::vector<StoredMessage> messages = {Message(1000, 0, {1}), Message(1500, 1, {1}),
                                               Message(1800, 0, {2}),  // camera 0 again: a new frame
                                               Message(9000, 1, {1})};
  const std::vector<Frame> frames = AssembleFrames(messages, 2, 2000);
  ASSERT_EQ(frames.size(), 3u);
  EXPECT_EQ(frames[0].messages, (std::vector<int>{0, 1}));
  EXPECT_EQ(frames[1].messages, (std::vector<int>{2}));
  EXPECT_EQ(frames[2].messages, (std::vector<int>{3}));
  EXPECT_EQ(frames[2].utime, 9000);
}

TEST(MapperStages, CollectObservationsCountsIgnoredAndDuplicateIdsAndGroupsViews) {
  const std::vector<StoredMessage> messages = {Message(1000, 0, {1, 2, 2, 9}), Message(1000, 1, {1, 3})};
  const std::vector<Frame> frames = AssembleFrames(messages, 2, 2000);
  MapperOptions options;
  options.marker_ids = {1, 2, 3};
  options.sizes.default_size = 0.04;
  MapReport report;
  const Observations o = CollectObservations(messages, frames, {"a", "b"}, options, &report);
  EXPECT_EQ(report.ignored_ids, 1);  // 9
  EXPECT_EQ(report.duplicates, 2);   // both 2s
  ASSERT_EQ(o.obs.size(), 3u);       // 1 (a), 1 and 3 (b)
  EXPECT_EQ(o.marker_ids, (std::vector<int>{1, 3}));
  EXPECT_EQ(o.views, (std::vector<std::pair<int, int>>{{0, 1}, {1, 3}}));
  EXPECT_EQ(o.camera_messages, (std::vector<int>{1, 1}));
  options.marker_ids = {7};
  EXPECT_THROW(CollectObservations(messages, frames, {"a", "b"}, options, &report), MapperError);
}

TEST(MapperStages, OneEdgeBuilderForBothGraphsFindsTheRelativePose) {
  // Nodes 0 and 1 seen together in 40 events; node 0's items carry a wrong second hypothesis. With at most
  // 10 stored events the medoid is still the truth, and every event is counted.
  std::mt19937_64 rng(11);
  const Rigid3 zero_from_one = RandomRigid(rng, 0.2);
  const Rigid3 wrong = RandomRigid(rng, 0.2);
  std::vector<GraphItem> items;
  for (int e = 0; e < 40; ++e) {
    const Rigid3 zero_from_common = RandomRigid(rng, 1.0);
    const Rigid3 one_from_common = Inverse(zero_from_one) * zero_from_common;
    GraphItem a{e, 0, {zero_from_common, wrong}, {Inverse(zero_from_common), Inverse(wrong)}, {}};
    GraphItem b{e, 1, {one_from_common}, {Inverse(one_from_common)}, {}};
    if (e % 2) std::swap(a, b);  // order within a group does not matter
    items.push_back(a);
    items.push_back(b);
  }
  EdgeOptions options;
  options.max_events = 10;
  options.medoid.point_scale = 0.1;
  const std::vector<GraphEdge> edges = BuildGraphEdges(items, 2, options, 2);
  ASSERT_EQ(edges.size(), 1u);
  EXPECT_EQ(edges[0].a, 0);
  EXPECT_EQ(edges[0].b, 1);
  EXPECT_EQ(edges[0].events, 40);
  EXPECT_EQ(edges[0].candidates, 80);
  EXPECT_LE(edges[0].stored_events, 10);
  EXPECT_LT(RotationAngle(edges[0].a_from_b, zero_from_one), 1e-9);
  EXPECT_LT(TranslationDistance(edges[0].a_from_b, zero_from_one), 1e-9);
}

TEST(MapperStages, MarkerGraphRecoversTheLayoutAndRejectsAStaticMarker) {
  sim::SessionOptions o = Scene();
  o.extra_bodies = {test::RoomMarker(40, 0.04, sim::MakeTrajectory(o.trajectory))};
  const Pipeline p(o);
  const int ref = p.layout.reference;
  const Rigid3 truth_ref = p.ObjectFromMarker(p.observations.marker_ids[ref]);
  for (const sim::SimMarker& marker : p.truth.markers) {
    const int id = marker.id;
    const int m = p.MarkerOf(id);
    ASSERT_TRUE(p.layout.placed[m]) << id;
    const Rigid3 truth = Inverse(truth_ref) * marker.object_from_marker;
    // Medoids of single-square poses: millimetres and degrees (a wrong hypothesis is tens of degrees).
    // Worst marker over seeds 1-12 (with the room's marker): 1.0-6.7 deg, 2.9-17.3 mm.
    EXPECT_LT(TranslationDistance(p.layout.object_from_marker[m], truth), 0.025) << id;
    EXPECT_LT(RotationAngle(p.layout.object_from_marker[m], truth), 10 * kDeg) << id;
  }
  ASSERT_TRUE(p.observations.marker_index.count(40));
  EXPECT_FALSE(p.layout.placed[p.MarkerOf(40)]);
  bool rejected = false;
  for (const RejectedMarker& r : p.report.rejected_markers) rejected = rejected || r.id == 40;
  EXPECT_TRUE(rejected);
}

// Two 4 cm markers 5 cm apart seen by one camera (f 420 px) at 1.3 m: 11-13 px squares, every corner
// coordinate with 0.4 px of noise, the object turned at random within 60 deg of face-on. Their square poses
// are pinned only where the corners pin them (a face-on square's tilt, its depth), so their relative poses
// scatter far beyond 15 deg and 2 cm + 15 %; within the poses' noise they agree. A marker moved by 5-15 cm
// from frame to frame is still not attached. mcmt-sim's grained surface at 1.3 m (marker 2, 0.71 px mean
// corner error) lost its map over 1-3 of 26 frames of one pair (bench/results/2026-12-06-knife.md).
TEST(MapperStages, SmallSquaresAgreeWithinTheirPosesNoise) {
  CameraModel camera = CameraModel::Pinhole(640, 480, 420, 320, 240);
  const double side = 0.04;
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, 0.4);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  const Rigid3 a_from_b = RigidFromParams((Vector6d() << 0, 0.3, 0, 0.05, 0, 0).finished());
  for (const bool attached : {true, false}) {
    Observations observations;
    observations.marker_ids = {0, 1};
    observations.marker_index = {{0, 0}, {1, 1}};
    observations.camera_messages = {60};
    for (int f = 0; f < 60; ++f) {
      const Vector6d turn = (Vector6d() << 0.6 * uniform(rng), 0.6 * uniform(rng), M_PI * uniform(rng),
                             0.1 * uniform(rng), 0.1 * uniform(rng), 1.3)
                                .finished();
      const Rigid3 cam_from_a = RigidFromParams(turn);
      const Vector6d moved = (Vector6d() << 0, 0, 0, 0.1 * uniform(rng), 0.1 * uniform(rng), 0.05).finished();
      const Rigid3 b_pose = attached ? a_from_b : RigidFromParams(moved) * a_from_b;
      for (int m = 0; m < 2; ++m) {
        Observation ob;
        ob.frame = ob.view = f;
        ob.marker = m;
        ob.side = side;
        const Rigid3 cam_from_marker = m == 0 ? cam_from_a : cam_from_a * b_pose;
        const MarkerCorners3d corners = MarkerCornersInMarker(side);
        for (int k = 0; k < 4; ++k) {
          const Eigen::Vector3d p = cam_from_marker * corners[k];
          camera.Project(p.data(), ob.corners[k].data());
          ob.corners[k] += Eigen::Vector2d(noise(rng), noise(rng));
        }
        observations.poses.push_back(EstimateSquarePose(camera, ob.corners, side));
        ob.kept = NumKeptHypotheses(observations.poses.back(), MapperOptions().tau_e);
        observations.obs.push_back(ob);
      }
      observations.views.push_back({2 * f, 2 * f + 2});
    }
    MapperOptions options;
    options.marker_ids = {0, 1};
    options.sizes.default_size = side;
    options.allow_partial = true;
    MapReport report;
    const MarkerLayout layout = BuildMarkerGraph(observations, options, 2, &report);
    ASSERT_EQ(layout.edges.size(), 1u);
    const double fraction = layout.edges[0].SupportFraction();
    std::printf("%s: support %d of %d\n", attached ? "attached" : "moved", layout.edges[0].support,
                layout.edges[0].stored_events);
    if (attached) {
      EXPECT_GT(fraction, 0.6);
      EXPECT_TRUE(layout.placed[1]);
      EXPECT_LT(
          TranslationDistance(Inverse(layout.object_from_marker[0]) * layout.object_from_marker[1], a_from_b),
          0.02);
    } else {
      EXPECT_LT(fraction, 0.3);
      EXPECT_FALSE(layout.placed[0] && layout.placed[1]);
    }
  }
}

TEST(MapperStages, CameraGraphPlacesEveryCameraRelativeToTheReference) {
  const Pipeline p(Scene());
  const int ref = p.cameras.reference;
  EXPECT_GT(p.views.size(), 200u);
  for (size_t c = 0; c < p.names.size(); ++c) {
    ASSERT_TRUE(p.cameras.placed[c]) << c;
    EXPECT_GT(p.cameras.views[c], 0);
    const Rigid3 truth = Inverse(p.RigFromCam(ref)) * p.RigFromCam(c);
    EXPECT_LT(TranslationDistance(p.cameras.rig_from_cam[c], truth), 0.05) << c;
    EXPECT_LT(RotationAngle(p.cameras.rig_from_cam[c], truth), 3 * kDeg) << c;
  }
}

// The board session of `bench/run --only objects` (mcmt-sim --object board --seed 7, 300 frames) as its
// detections-only twin, with what the detector saw in the rendered session where it broke the map: cam2
// and cam4 see the board together in frame 250 only (the detector missed cam4's grazing markers in the
// other frames where both saw it), cam4 a lone marker 5 seen edge-on, its corners as mcmt-detector found
// them. Its IPPE ratio calls the wrong hypothesis sure: the pair's one candidate is 145 deg off.
sim::Session BoardWithOneGrazingCoObservation() {
  const sim::DatasetOptions d = sim::DetectionsOnlySession("", 300, 7);
  sim::SessionOptions o;
  o.rig = d.rig;
  o.object = d.object;
  o.object.kind = sim::ObjectKind::kBoard;
  o.trajectory = d.trajectory;
  o.detections = d.detections;
  sim::Session session = sim::SimulateSession(o);
  const double detected[4][2] = {{301.09360766877143, 206.39532652256673},
                                 {307.15720732943038, 213.81476474708987},
                                 {304.67724468793585, 233.59014539386507},
                                 {298.90391158237833, 226.80691772771002}};
  int together = 0;
  for (std::vector<detections_t>& frame : session.views) {
    detections_t* cam2 = nullptr;
    detections_t* cam4 = nullptr;
    for (detections_t& m : frame) {
      if (m.camera == "cam2") cam2 = &m;
      if (m.camera == "cam4") cam4 = &m;
    }
    if (!cam2 || !cam4 || cam2->markers.empty() || cam4->markers.empty()) continue;
    ++together;
    cam4->markers.clear();
    if (cam4->seq == 250) {
      marker_t grazing;
      grazing.id = 5;
      std::copy(&detected[0][0], &detected[0][0] + 8, &grazing.corners[0][0]);
      cam4->markers.push_back(grazing);
    }
    cam4->num_markers = static_cast<int32_t>(cam4->markers.size());
  }
  EXPECT_EQ(together, 8);  // frames where the simulated cam2 and cam4 both see the board
  return session;
}

TEST(MapperStages, BoardCamerasIgnoreALoneUnconfirmedCoObservation) {
  const Pipeline p(BoardWithOneGrazingCoObservation());
  const int cam2 = 2, cam4 = 4;
  const GraphEdge* lone = nullptr;
  for (const GraphEdge& e : p.cameras.edges)
    if (e.a == cam2 && e.b == cam4) lone = &e;
  ASSERT_NE(lone, nullptr);
  EXPECT_EQ(lone->candidates, 1);
  EXPECT_EQ(lone->support, 1);  // no second co-observation confirms it
  const Rigid3 truth_2_from_4 = Inverse(p.RigFromCam(cam2)) * p.RigFromCam(cam4);
  EXPECT_GT(RotationAngle(lone->a_from_b, truth_2_from_4), 90 * kDeg);  // the wrong candidate
  const int ref = p.cameras.reference;
  for (size_t c = 0; c < p.names.size(); ++c) {
    ASSERT_TRUE(p.cameras.placed[c]) << c;
    const Rigid3 truth = Inverse(p.RigFromCam(ref)) * p.RigFromCam(c);
    EXPECT_LT(TranslationDistance(p.cameras.rig_from_cam[c], truth), 0.05) << p.names[c];
    EXPECT_LT(RotationAngle(p.cameras.rig_from_cam[c], truth), 3 * kDeg) << p.names[c];
  }
  // The whole mapper on the same detections: camera positions against the truth (bench/run's 2026-11-22
  // board row: 3.70 mm; the rendered session mapped 1018 mm off through this edge).
  const MapResult result = test::MapMessages(p.session.Messages(), p.options);
  const sim::EvalResult e = sim::Evaluate(p.truth, &result.map, &result.trajectory);
  EXPECT_EQ(e.mapped_cameras, 5);
  EXPECT_EQ(e.mapped_markers, 9);
  EXPECT_LT(e.camera_position_mm.max, 1.0);
  EXPECT_LT(e.camera_rotation_deg.max, 0.05);
  ::testing::Test::RecordProperty("camera_position_mm_max", std::to_string(e.camera_position_mm.max));
}

TEST(MapperStages, ObjectPosesFollowTheTruthInTheReferenceFrames) {
  const Pipeline p(Scene());
  const Rigid3 ref_from_world = Inverse(p.RigFromCam(p.cameras.reference));
  const Rigid3& object_from_ref_marker = p.ObjectFromMarker(p.observations.marker_ids[p.layout.reference]);
  int compared = 0;
  double sum_deg = 0, sum_m = 0;
  for (size_t f = 0; f < p.frames.size(); ++f) {
    if (!p.poses.has_pose[f]) continue;
    const auto k = std::find_if(p.truth.frames.begin(), p.truth.frames.end(),
                                [&](const sim::SimFrame& t) { return t.utime == p.frames[f].utime; });
    if (k == p.truth.frames.end()) continue;
    const Rigid3 truth = ref_from_world * k->rig_from_object * object_from_ref_marker;
    sum_deg += RotationAngle(p.poses.rig_from_object[f], truth) / kDeg;
    sum_m += TranslationDistance(p.poses.rig_from_object[f], truth);
    ++compared;
  }
  ASSERT_GT(compared, 70);
  // Means over frames, seeds 1-12: 1.9-3.8 deg, 6.0-23.8 mm (initial poses from single squares).
  EXPECT_LT(sum_deg / compared, 5.0);
  EXPECT_LT(sum_m / compared, 0.03);
}

// The observations kept through the bundle adjustment (the mapper's peak memory) are allocated at their
// size: grown by doubling they took up to twice it (an 8-camera board session, 3000 frames: 58.7 instead
// of 41.6 MB of Observation, 14.7 instead of 10.4 of BundleObservation).
TEST(MapperStages, ObservationsAreAllocatedAtTheirSize) {
  // The square poses (320 bytes each) are a vector of their own, released before the bundle adjustment:
  // an observation kept through it is 128 bytes (448 with its poses as a member).
  EXPECT_LE(sizeof(Observation), 128u);
  Pipeline p(Scene(60));
  EXPECT_EQ(p.observations.poses.size(), p.observations.obs.size());
  EXPECT_EQ(p.observations.obs.capacity(), p.observations.obs.size());
  const MapperBundle bundle =
      MakeBundleProblem(p.observations, p.Names(), p.layout, p.cameras, p.poses, p.models, &p.report);
  ASSERT_GT(bundle.problem.observations.size(), 100u);
  EXPECT_EQ(bundle.problem.observations.capacity(), bundle.problem.observations.size());
  EXPECT_EQ(bundle.observation.capacity(), bundle.observation.size());
}

TEST(MapperStages, RefinementKeepsTheReferencesAndRejectsAGrossObservation) {
  Pipeline p(Scene(60));
  // One observation 20 px off.
  const size_t gross = p.observations.obs.size() / 2;
  for (auto& c : p.observations.obs[gross].corners) c += Eigen::Vector2d(20, -15);
  MapperBundle bundle =
      MakeBundleProblem(p.observations, p.Names(), p.layout, p.cameras, p.poses, p.models, &p.report);
  const PoseBlock ref_block = bundle.problem.cam_from_rig[p.cameras.reference];
  const BundleSettings settings = BundleSettingsFor(p.options, 2);
  RefineWithRejection(p.observations, p.Names(), p.layout, p.options, settings, &bundle, &p.report);
  EXPECT_EQ(bundle.problem.cam_from_rig[p.cameras.reference], ref_block);
  bool rejected = false;
  for (size_t k = 0; k < bundle.observation.size(); ++k)
    if (bundle.observation[k] == static_cast<int>(gross)) rejected = !bundle.problem.active[k];
  EXPECT_TRUE(rejected);
  RigMap map;
  std::vector<TrajectoryRow> trajectory;
  FillMap(bundle, p.observations, p.Names(), p.layout, p.cameras, p.options, &map, &trajectory);
  const sim::EvalResult e = sim::Evaluate(p.truth, &map, &trajectory);
  // The worst camera over seeds 1-12 (60 frames, 0.2 px): 0.9-2.6 mm; the worst marker 0.08-0.13 mm.
  EXPECT_LT(e.camera_position_mm.max, 3.5);
  EXPECT_LT(e.configuration_mm.max, 0.5);
  EXPECT_LT(map.rms_px, 0.4);
}

// --allow-partial with a reference that does not fit: the best-connected camera that fits becomes the
// reference, the map re-expressed in its frame; without it, the error says which camera is the reference.
TEST(MapperStages, UnreliableReferenceCameraIsReplacedOrNamed) {
  Pipeline p(Scene(60));
  MapperBundle bundle =
      MakeBundleProblem(p.observations, p.Names(), p.layout, p.cameras, p.poses, p.models, &p.report);
  const BundleSettings settings = BundleSettingsFor(p.options, 2);
  RefineWithRejection(p.observations, p.Names(), p.layout, p.options, settings, &bundle, &p.report);
  const int old_ref = p.cameras.reference;
  for (size_t k = 0; k < bundle.problem.observations.size(); ++k)
    if (bundle.problem.observations[k].camera == old_ref && k % 3) bundle.problem.active[k] = 0;
  {
    CameraPlacement cameras = p.cameras;
    MapperBundle copy = bundle;
    MapReport report;
    try {
      DropUnreliableCameras(p.observations, p.Names(), p.options, settings, &cameras, &copy, &report);
      ADD_FAILURE() << "no error";
    } catch (const MapperError& e) {
      EXPECT_NE(std::string(e.what()).find("'" + p.names[old_ref] + "' (the reference camera)"),
                std::string::npos)
          << e.what();
    }
  }
  MapperOptions partial = p.options;
  partial.allow_partial = true;
  CameraPlacement cameras = p.cameras;
  MapReport report;
  // Frame velocities (the bundle's with time offsets; not refined here) go into the new reference's frame
  // with the poses.
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> speed(-1.0, 1.0);
  bundle.problem.frame_velocity.resize(bundle.problem.rig_from_object.size());
  for (std::array<double, 6>& twist : bundle.problem.frame_velocity)
    for (double& x : twist) x = speed(rng);
  const std::vector<std::array<double, 6>> old_velocity = bundle.problem.frame_velocity;
  const std::vector<PoseBlock> old_cam_from_rig = bundle.problem.cam_from_rig;
  DropUnreliableCameras(p.observations, p.Names(), partial, settings, &cameras, &bundle, &report);
  const Rigid3 new_from_old = RigidFromBlock(old_cam_from_rig[cameras.reference].data());
  for (size_t f = 0; f < old_velocity.size(); ++f)
    for (int i = 0; i < 6; ++i)
      ASSERT_NEAR(bundle.problem.frame_velocity[f][i], TwistIn(new_from_old, old_velocity[f])[i], 1e-12) << f;
  EXPECT_NE(cameras.reference, old_ref);
  EXPECT_FALSE(cameras.placed[old_ref]);
  EXPECT_EQ(report.dropped_cameras, std::vector<std::string>{p.names[old_ref]});
  EXPECT_EQ(bundle.problem.camera_fixed[cameras.reference], 1);
  EXPECT_EQ(bundle.problem.camera_fixed[old_ref], 0);
  RigMap map;
  std::vector<TrajectoryRow> trajectory;
  FillMap(bundle, p.observations, p.Names(), p.layout, cameras, p.options, &map, &trajectory);
  EXPECT_EQ(map.reference_camera, p.names[cameras.reference]);
  EXPECT_EQ(map.cameras.size(), p.names.size() - 1);
  EXPECT_LT(map.FindCamera(map.reference_camera)->rig_from_cam.translation().norm(), 1e-12);
  const sim::EvalResult e = sim::Evaluate(p.truth, &map, &trajectory);
  EXPECT_LT(e.camera_position_mm.max, 3.0);
  EXPECT_LT(e.object_translation_aligned_mm.mean, 2.0);
}

}  // namespace
}  // namespace mcmt
