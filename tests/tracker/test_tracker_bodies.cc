// Several bodies in the tracker (issue 16): every moving body of the simulator's bodies scene on its own
// channel, the relative pose patient_from_tool, bodies that cross, leave and re-enter, against each
// body's ground truth with mcmt-mapper's map; the relative covariance against Monte-Carlo; bad input.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <iostream>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "core/options.h"
#include "tests/tracker/bodies_session.h"
#include "tracker/relative.h"
#include "tracker/tracker.h"

namespace mcmt {
namespace {

using tracker_test::Bodies;
using tracker_test::BodiesSession;

const char kRelativeSection[] = "tracker:\n  relative:\n    - {of: tool, in: patient}\n";

// The left perturbation d (tx, ty, tz, rx, ry, rz) with estimate = Exp(d) * truth (core's PerturbLeft).
Vector6d LeftError(const Rigid3& estimate, const Rigid3& truth) {
  const Eigen::Matrix3d r = estimate.linear() * truth.linear().transpose();
  Vector6d d;
  d.head<3>() = estimate.translation() - r * truth.translation();
  d.tail<3>() = VectorFromRotation(r);
  return d;
}

Matrix6d RandomCovariance(std::mt19937_64& rng, double sigma_t, double sigma_r) {
  std::normal_distribution<double> n(0.0, 1.0);
  Matrix6d a;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) a(i, j) = n(rng) * (i < 3 ? sigma_t : sigma_r);
  return a * a.transpose() / 6.0;
}

Vector6d Sample(std::mt19937_64& rng, const Matrix6d& covariance) {
  std::normal_distribution<double> n(0.0, 1.0);
  Vector6d z;
  for (int i = 0; i < 6; ++i) z[i] = n(rng);
  return Eigen::LLT<Matrix6d>(covariance).matrixL() * z;
}

// Perturbs in object_pose_t's order (t, r): PerturbLeft takes (r, t).
Rigid3 Perturb(const Rigid3& pose, const Vector6d& d_tr) {
  Vector6d rt;
  rt << d_tr.tail<3>(), d_tr.head<3>();
  return PerturbLeft(pose, rt);
}

// Sigma_rel = Ad(B^-1)(Sigma_a + Sigma_b)Ad(B^-1)^T against the spread of in_from_of when both poses are
// drawn from their covariances (millimetre and milliradian noise, poses a metre apart).
TEST(TrackerRelative, CovarianceMatchesMonteCarlo) {
  std::mt19937_64 rng(16);
  for (int trial = 0; trial < 3; ++trial) {
    const Rigid3 a = RandomRigid(rng, 1.0), b = RandomRigid(rng, 1.0);
    const Matrix6d sa = RandomCovariance(rng, 1e-3, 2e-3), sb = RandomCovariance(rng, 2e-3, 1e-3);
    const RelativePose rel = ComposeRelative(a, sa, b, sb);
    EXPECT_LT(TranslationDistance(rel.in_from_of, Inverse(b) * a), 1e-12);
    const int n = 40000;
    Matrix6d spread = Matrix6d::Zero();
    for (int k = 0; k < n; ++k) {
      const Rigid3 a_k = Perturb(a, Sample(rng, sa)), b_k = Perturb(b, Sample(rng, sb));
      const Vector6d d = LeftError(Inverse(b_k) * a_k, rel.in_from_of);
      spread += d * d.transpose() / n;
    }
    // Entry by entry, relative to the diagonal's scale (a sample covariance of 40000 draws: ~1 %).
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j < 6; ++j) {
        const double scale = std::sqrt(rel.covariance(i, i) * rel.covariance(j, j));
        EXPECT_NEAR(spread(i, j), rel.covariance(i, j), 0.04 * scale) << trial << " " << i << "," << j;
      }
    // Against the wrong formula (the sum without the adjoint): the test can tell them apart.
    EXPECT_GT((spread - (sa + sb)).norm(), 0.2 * spread.norm());
  }
}

struct Published {
  std::map<std::string, std::vector<object_pose_t>> by_channel;
  void OnPose(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    object_pose_t msg;
    if (Decode(rbuf->data, rbuf->data_size, &msg)) by_channel[channel].push_back(msg);
  }
};

// Tracks `detections` (written as a log) with `rig`'s tracker options and the session's map; every
// object_pose_t published, by channel.
Published Track(const BodiesSession& s, const std::string& rig_path,
                const std::vector<detections_t>& detections) {
  const std::string log = s.dir->File("track_input.lcmlog");
  sim::WriteMessagesLog(log, detections);
  const RigConfig rig = LoadRigConfig(rig_path);
  TrackerNodeOptions options;
  options.tracker = TrackerOptions::FromConfig(rig);
  options.log_mode = true;
  options.quiet = true;
  lcm::LCM input("memq://"), output("memq://");
  Published got;
  output.subscribe("MCMT_POSE.*", &Published::OnPose, &got)->setQueueCapacity(1 << 20);
  TrackerNode node(input, rig, options, s.map, &output);
  node.RunLog(log, StopToken());
  while (output.handleTimeout(0) > 0) {
  }
  return got;
}

std::vector<TrajectoryRow> Poses(const std::vector<object_pose_t>& msgs) {
  std::vector<TrajectoryRow> rows;
  for (const object_pose_t& m : msgs)
    if (m.status != object_pose_t::STATUS_LOST) rows.push_back(FromObjectPoseMsg(m));
  return rows;
}

Matrix6d Covariance(const object_pose_t& m) {
  Matrix6d c;
  for (int a = 0; a < 6; ++a)
    for (int b = 0; b < 6; ++b) c(a, b) = m.covariance[a][b];
  return c;
}

// Normalised estimation error squared of a pose against the truth in the estimate's frames.
double Nees(const object_pose_t& m, const Rigid3& truth) {
  const Vector6d d = LeftError(FromPose3d(m.rig_from_object), truth);
  return d.dot(Covariance(m).ldlt().solve(d));
}

const sim::SimFrame* TruthAt(const sim::GroundTruth& truth, int64_t seq) {
  for (const sim::SimFrame& f : truth.frames)
    if (f.seq == seq) return &f;
  return nullptr;
}

struct BodyFigures {
  sim::EvalResult eval;
  double nees_mean = 0.0;
  int frames = 0;  // with a pose
};

BodyFigures BodyPoses(const BodiesSession& s, const std::string& body,
                      const std::vector<object_pose_t>& msgs) {
  BodyFigures f;
  f.eval = tracker_test::EvaluateBody(s, body, Poses(msgs));
  const Rigid3 a = f.eval.gt_rig_from_est_rig, b = f.eval.gt_object_from_est_object;
  for (const object_pose_t& m : msgs) {
    if (m.status == object_pose_t::STATUS_LOST) continue;
    const sim::SimFrame* t = TruthAt(s.truth.at(body), m.seq);
    if (!t) continue;
    f.nees_mean += Nees(m, Inverse(a) * t->rig_from_object * b);
    ++f.frames;
  }
  if (f.frames) f.nees_mean /= f.frames;
  return f;
}

struct RelativeFigures {
  sim::Stats translation_mm, rotation_deg;
  double nees_mean = 0.0;
  int frames = 0;
};

RelativeFigures RelativePoses(const BodiesSession& s, const std::vector<object_pose_t>& msgs,
                              const BodyFigures& tool, const BodyFigures& patient) {
  RelativeFigures f;
  std::vector<double> t_mm, r_deg;
  for (const object_pose_t& m : msgs) {
    if (m.status == object_pose_t::STATUS_LOST) continue;
    const Rigid3 truth =
        tracker_test::TrueRelative(s, "tool", "patient", m.seq, tool.eval.gt_object_from_est_object,
                                   patient.eval.gt_object_from_est_object);
    const Rigid3 est = FromPose3d(m.rig_from_object);
    // Position of the tool's true origin in the patient's true frame, as in Evaluate.
    const Rigid3 gt_p = patient.eval.gt_object_from_est_object, gt_t = tool.eval.gt_object_from_est_object;
    t_mm.push_back(1e3 * TranslationDistance(gt_p * est * Inverse(gt_t), gt_p * truth * Inverse(gt_t)));
    r_deg.push_back(RotationAngle(est, truth) * 180.0 / M_PI);
    f.nees_mean += Nees(m, truth);
    ++f.frames;
  }
  f.translation_mm = sim::ComputeStats(t_mm);
  f.rotation_deg = sim::ComputeStats(r_deg);
  if (f.frames) f.nees_mean /= f.frames;
  return f;
}

TEST(TrackerBodies, EveryMovingBodyOnItsChannelWithinTheTargets) {
  const BodiesSession& s = Bodies();
  ASSERT_EQ(s.map.objects.size(), 3u);
  const Published got = Track(s, s.Rig("rig_relative.yaml", kRelativeSection), s.detections);
  // The streams: the two moving bodies and the relative pose, one message per frame each; no MCMT_POSE,
  // nothing for the static floor.
  ASSERT_EQ(got.by_channel.size(), 3u);
  for (const char* channel : {"MCMT_POSE_TOOL", "MCMT_POSE_PATIENT", "MCMT_POSE_TOOL_IN_PATIENT"}) {
    ASSERT_TRUE(got.by_channel.count(channel)) << channel;
    EXPECT_EQ(got.by_channel.at(channel).size(), 300u) << channel;
  }
  EXPECT_EQ(got.by_channel.at("MCMT_POSE_TOOL")[0].object, "tool");
  EXPECT_EQ(got.by_channel.at("MCMT_POSE_TOOL_IN_PATIENT")[0].object, "tool_in_patient");

  const BodyFigures tool = BodyPoses(s, "tool", got.by_channel.at("MCMT_POSE_TOOL"));
  const BodyFigures patient = BodyPoses(s, "patient", got.by_channel.at("MCMT_POSE_PATIENT"));
  const RelativeFigures rel = RelativePoses(s, got.by_channel.at("MCMT_POSE_TOOL_IN_PATIENT"), tool, patient);
  for (const auto& [name, f] :
       {std::pair<const char*, const BodyFigures&>{"tool", tool}, {"patient", patient}})
    std::cout << name << ": " << f.frames << " frames, " << f.eval.object_translation_mm.mean << " mm mean / "
              << f.eval.object_translation_mm.max << " mm max, " << f.eval.object_rotation_deg.mean
              << " deg mean / " << f.eval.object_rotation_deg.max << " deg max, NEES " << f.nees_mean << "\n";
  std::cout << "tool_in_patient: " << rel.frames << " frames, " << rel.translation_mm.mean << " mm mean / "
            << rel.translation_mm.max << " mm max, " << rel.rotation_deg.mean << " deg mean / "
            << rel.rotation_deg.max << " deg max, NEES " << rel.nees_mean << "\n";
  // The targets for moving poses: 0.3 mm / 0.15 deg (here every frame, crossings included).
  for (const BodyFigures* f : {&tool, &patient}) {
    EXPECT_GE(f->frames, 285);  // the crossings hide a body from some cameras, not from all
    EXPECT_LT(f->eval.object_translation_mm.mean, 0.3);
    EXPECT_LT(f->eval.object_translation_mm.max, 1.0);
    EXPECT_LT(f->eval.object_rotation_deg.mean, 0.15);
    // The covariance is honest: NEES of a 6-dof pose averages 6 (map errors add a little).
    EXPECT_GT(f->nees_mean, 2.0);
    EXPECT_LT(f->nees_mean, 18.0);
  }
  // Where they cross and hide each other (s = 1/4 and 3/4 of the session): every frame posed, as accurately.
  for (const char* body : {"tool", "patient"}) {
    std::vector<TrajectoryRow> crossing;
    for (const TrajectoryRow& r :
         Poses(got.by_channel.at(std::string("MCMT_POSE_") + (body[0] == 't' ? "TOOL" : "PATIENT"))))
      if (std::abs(r.seq - 75) <= 10 || std::abs(r.seq - 224) <= 10) crossing.push_back(r);
    const sim::EvalResult e = tracker_test::EvaluateBody(s, body, crossing);
    std::cout << body << " while crossing: " << crossing.size() << " of 42 frames, "
              << e.object_translation_mm.max << " mm max\n";
    EXPECT_EQ(crossing.size(), 42u) << body;
    EXPECT_LT(e.object_translation_mm.max, 0.5) << body;
  }
  EXPECT_EQ(rel.frames, std::min(tool.frames, patient.frames));
  EXPECT_LT(rel.translation_mm.mean, 0.6);
  EXPECT_LT(rel.translation_mm.max, 2.0);
  EXPECT_LT(rel.rotation_deg.mean, 0.2);
  EXPECT_GT(rel.nees_mean, 2.0);
  EXPECT_LT(rel.nees_mean, 18.0);
}

// The tool leaves every camera's view for two seconds: LOST on its channel and on the relative one (the
// patient goes on), then tracked again from its first frame back, as accurately as before.
TEST(TrackerBodies, ABodyThatLeavesAndReEntersIsLostThenTrackedAgain) {
  const BodiesSession& s = Bodies();
  std::vector<detections_t> detections = s.detections;
  const int64_t first_gone = 100, last_gone = 159;
  for (detections_t& d : detections) {
    if (d.seq < first_gone || d.seq > last_gone) continue;
    std::vector<marker_t> kept;
    for (const marker_t& m : d.markers)
      if (!s.truth.at("tool").FindMarker(m.id)) kept.push_back(m);
    d.markers = kept;
    d.num_markers = static_cast<int32_t>(kept.size());
  }
  const Published got = Track(s, s.Rig("rig_leave.yaml", kRelativeSection), detections);
  const std::vector<object_pose_t>& tool = got.by_channel.at("MCMT_POSE_TOOL");
  const std::vector<object_pose_t>& rel = got.by_channel.at("MCMT_POSE_TOOL_IN_PATIENT");
  const std::vector<object_pose_t>& patient = got.by_channel.at("MCMT_POSE_PATIENT");
  ASSERT_EQ(tool.size(), 300u);
  int lost = 0, patient_tracked = 0;
  for (size_t k = 0; k < tool.size(); ++k) {
    const bool gone = tool[k].seq >= first_gone && tool[k].seq <= last_gone;
    if (gone) {
      lost += tool[k].status == object_pose_t::STATUS_LOST;
      EXPECT_EQ(rel[k].status, object_pose_t::STATUS_LOST) << tool[k].seq;
      patient_tracked += patient[k].status != object_pose_t::STATUS_LOST;
    }
  }
  EXPECT_EQ(lost, last_gone - first_gone + 1);
  EXPECT_GE(patient_tracked, 55);
  // Back: its first frames after the gap within the accuracy of the whole run.
  std::vector<object_pose_t> back;
  for (const object_pose_t& m : tool)
    if (m.seq > last_gone && m.seq <= last_gone + 10) back.push_back(m);
  ASSERT_EQ(back.size(), 10u);
  for (const object_pose_t& m : back) EXPECT_NE(m.status, object_pose_t::STATUS_LOST) << m.seq;
  const BodyFigures all = BodyPoses(s, "tool", tool);
  EXPECT_LT(all.eval.object_translation_mm.max, 1.0);
  const sim::EvalResult e = tracker_test::EvaluateBody(s, "tool", Poses(back));
  std::cout << "tool after re-entering: " << e.object_translation_mm.max << " mm max over 10 frames\n";
  EXPECT_LT(e.object_translation_mm.max, 0.5);
}

// A camera that moves (its corners 2.5 px off from frame 100 on: under outlier_px, so only the health leaves
// them out): judged on the first body (the tool), excluded, and then left out of every body's pose, the
// patient's too, which stays accurate.
TEST(TrackerBodies, AnExcludedCameraIsLeftOutOfEveryBody) {
  const BodiesSession& s = Bodies();
  std::vector<detections_t> detections = s.detections;
  for (detections_t& d : detections)
    if (d.camera == "cam2" && d.seq >= 100)
      for (marker_t& m : d.markers)
        for (auto& c : m.corners) c[0] += 2.5;
  const Published got = Track(s, s.Rig("rig_bumped.yaml", kRelativeSection), detections);
  int with_cam2_late = 0, late = 0;
  std::vector<object_pose_t> patient_late;
  for (const char* channel : {"MCMT_POSE_TOOL", "MCMT_POSE_PATIENT"})
    for (const object_pose_t& m : got.by_channel.at(channel)) {
      if (m.seq < 150 || m.status == object_pose_t::STATUS_LOST) continue;
      ++late;
      with_cam2_late += std::count(m.cameras.begin(), m.cameras.end(), "cam2") > 0;
      if (std::string(channel) == "MCMT_POSE_PATIENT") patient_late.push_back(m);
    }
  std::cout << "cam2 moved at frame 100: in " << with_cam2_late << " of " << late
            << " body poses from frame 150 on\n";
  EXPECT_GT(late, 250);
  EXPECT_EQ(with_cam2_late, 0);
  const sim::EvalResult e = tracker_test::EvaluateBody(s, "patient", Poses(patient_late));
  EXPECT_LT(e.object_translation_mm.max, 1.0);
}

std::string ConfigError(const std::string& rig_path) {
  try {
    TrackerOptions::FromConfig(LoadRigConfig(rig_path));
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(TrackerBodies, BadStreamsAreOneLineNamingTheKey) {
  const BodiesSession& s = Bodies();
  // A relative pose naming an unknown body: the rig's bodies are known at load.
  std::string e = ConfigError(s.Rig("rig_unknown.yaml", "tracker:\n  relative: [{of: tool, in: patinet}]\n"));
  EXPECT_NE(
      e.find("rig_unknown.yaml: tracker.relative[0].in: no body named 'patinet' (bodies: tool, patient, "
             "floor)"),
      std::string::npos)
      << e;
  EXPECT_EQ(e.find('\n'), std::string::npos);
  // Two streams on one channel.
  e = ConfigError(s.Rig("rig_collide.yaml", "tracker:\n  channels: {patient: MCMT_POSE_TOOL}\n"));
  EXPECT_NE(e.find("tracker.channels.patient: channel MCMT_POSE_TOOL of 'patient' is also 'tool''s"),
            std::string::npos)
      << e;
  // A channel of another mcmt type, a static body's channel, a body relative to itself, a bad list.
  e = ConfigError(s.Rig("rig_reserved.yaml", "tracker:\n  channels: {tool: MCMT_MAP}\n"));
  EXPECT_NE(e.find("tracker.channels.tool: channel MCMT_MAP of 'tool' is an mcmt channel"), std::string::npos)
      << e;
  e = ConfigError(s.Rig("rig_static.yaml", "tracker:\n  channels: {floor: FLOOR}\n"));
  EXPECT_NE(e.find("tracker.channels.floor: 'floor' is a static body (not tracked)"), std::string::npos) << e;
  e = ConfigError(s.Rig("rig_self.yaml", "tracker:\n  relative: [{of: tool, in: tool}]\n"));
  EXPECT_NE(e.find("tracker.relative[0]: 'tool' relative to itself"), std::string::npos) << e;
  e = ConfigError(s.Rig("rig_list.yaml", "tracker:\n  relative: {of: tool, in: patient}\n"));
  EXPECT_NE(e.find("tracker.relative: expected a list"), std::string::npos) << e;
  // Options built in code against the map: the node refuses them naming the key.
  TrackerNodeOptions options;
  options.tracker.relative = {{"tool", "nobody"}};
  options.log_mode = true;
  lcm::LCM lcm("memq://");
  const RigConfig rig = LoadRigConfig(s.dir->File("rig.yaml"));
  try {
    TrackerNode node(lcm, rig, options, s.map);
    ADD_FAILURE() << "no error";
  } catch (const OptionError& err) {
    EXPECT_NE(std::string(err.what()).find("tracker.relative[0].in: no body named 'nobody'"),
              std::string::npos)
        << err.what();
  }
}

// A tool relative to the static floor (its one pose from the map, no covariance of its own): the tool's
// pose in the floor's frame, which is the rig frame here, so the same pose as on MCMT_POSE_TOOL.
TEST(TrackerBodies, RelativeToAStaticBodyUsesItsMapPose) {
  const BodiesSession& s = Bodies();
  ASSERT_EQ(s.map.rig_frame, "floor");
  std::vector<detections_t> first(s.detections.begin(), s.detections.begin() + 5 * 60);
  const Published got =
      Track(s, s.Rig("rig_floor.yaml", "tracker:\n  relative: [{of: tool, in: floor}]\n"), first);
  const std::vector<object_pose_t>& tool = got.by_channel.at("MCMT_POSE_TOOL");
  const std::vector<object_pose_t>& rel = got.by_channel.at("MCMT_POSE_TOOL_IN_FLOOR");
  ASSERT_EQ(tool.size(), rel.size());
  const Rigid3 rig_from_floor = s.map.FindObject("floor")->rig_from_object;
  for (size_t k = 0; k < tool.size(); ++k) {
    if (tool[k].status == object_pose_t::STATUS_LOST) continue;
    const Rigid3 expected = Inverse(rig_from_floor) * FromPose3d(tool[k].rig_from_object);
    EXPECT_LT(TranslationDistance(FromPose3d(rel[k].rig_from_object), expected), 1e-9);
    const Matrix6d ad = AdjointTranslationFirst(Inverse(rig_from_floor));
    EXPECT_LT((Covariance(rel[k]) - ad * Covariance(tool[k]) * ad.transpose()).norm(),
              1e-9 * Covariance(tool[k]).norm());
  }
}

// Maps from MCMT_MAP of both types: rig_map2_t (what mcmt-mapper publishes) gives every body its stream;
// an old rig_map_t (one object: the first moving body's markers) the single stream on MCMT_POSE.
TEST(TrackerBodies, MapsOnMcmtMapOfEitherType) {
  const BodiesSession& s = Bodies();
  const RigConfig rig = LoadRigConfig(s.Rig("rig_maps.yaml", kRelativeSection));
  TrackerNodeOptions options;
  options.tracker = TrackerOptions::FromConfig(rig);
  options.quiet = true;
  lcm::LCM lcm("memq://");
  TrackerNode node(lcm, rig, options, std::nullopt);
  EXPECT_FALSE(node.has_map());
  const std::vector<uint8_t> v2 = Encode(ToRigMap2Msg(s.map, 10));
  node.OnMap(v2.data(), v2.size());
  ASSERT_TRUE(node.has_map());
  std::vector<std::string> channels;
  for (const PoseStream& st : node.streams()) channels.push_back(st.channel);
  EXPECT_EQ(channels,
            (std::vector<std::string>{"MCMT_POSE_TOOL", "MCMT_POSE_PATIENT", "MCMT_POSE_TOOL_IN_PATIENT"}));
  for (const detections_t& d : s.detections) {
    if (d.seq >= 20) break;
    const std::vector<uint8_t> bytes = Encode(d);
    node.OnDetections(DetectionsChannel(d.camera), bytes.data(), bytes.size());
  }
  node.Flush();
  for (const PoseStream& st : node.streams()) EXPECT_EQ(st.tracked, 20) << st.name;

  TrackerNodeOptions plain;  // a one-object map: no relative pose to give
  plain.quiet = true;
  TrackerNode old_node(lcm, rig, plain, std::nullopt);
  const std::vector<uint8_t> v1 = Encode(ToRigMapMsg(s.map, 11));
  old_node.OnMap(v1.data(), v1.size());
  ASSERT_TRUE(old_node.has_map());
  ASSERT_EQ(old_node.streams().size(), 1u);
  EXPECT_EQ(old_node.streams()[0].channel, "MCMT_POSE");
  EXPECT_EQ(old_node.streams()[0].name, "object");
}

}  // namespace
}  // namespace mcmt
