// Unit tests of the mapper's building blocks: graph steps, the Ceres residual and manifold, and each
// initialisation step on synthetic data.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cstdio>
#include <random>

#include "core/ippe.h"
#include "mapper/bundle.h"
#include "mapper/graph.h"
#include "mapper/mapper.h"
#include "sim/eval.h"
#include "tests/support/mapper_sim.h"

namespace mcmt {
namespace {

constexpr double kDeg = M_PI / 180.0;

Rigid3 Pose(double rx, double ry, double rz, double tx, double ty, double tz) {
  Vector6d p;
  p << rx, ry, rz, tx, ty, tz;
  return RigidFromParams(p);
}

GraphEdge Edge(int a, int b, double cost, const Rigid3& a_from_b = Rigid3::Identity(),
               int64_t candidates = 10) {
  GraphEdge e;
  e.a = a;
  e.b = b;
  e.cost = cost;
  e.a_from_b = a_from_b;
  e.candidates = candidates;
  return e;
}

TEST(MapperGraph, MinimumSpanningTreeKeepsCheapestEdges) {
  // 0-1 (1), 1-2 (1), 0-2 (5), 2-3 (2), 1-3 (3): the tree is {0-1, 1-2, 2-3}.
  std::vector<GraphEdge> edges = {Edge(0, 1, 1), Edge(1, 2, 1), Edge(0, 2, 5), Edge(2, 3, 2), Edge(1, 3, 3)};
  const std::vector<GraphEdge> tree = MinimumSpanningTree(4, edges);
  ASSERT_EQ(tree.size(), 3u);
  std::set<std::pair<int, int>> got;
  for (const GraphEdge& e : tree) got.insert({e.a, e.b});
  EXPECT_EQ(got, (std::set<std::pair<int, int>>{{0, 1}, {1, 2}, {2, 3}}));
}

TEST(MapperGraph, UnconfirmedEdgesJoinTheTreeLast) {
  // 0-1 (1), 1-2 (2), 0-2 (0: one candidate, d = 0) and 2-3 (0, unconfirmed): 0-2 is the cheapest but no
  // second co-observation agrees with it, so 1-2 joins 2; 2-3 is the only way to 3 and is taken.
  std::vector<GraphEdge> edges = {Edge(0, 1, 1), Edge(1, 2, 2), Edge(0, 2, 0), Edge(2, 3, 0)};
  for (GraphEdge& e : edges) e.support = e.cost > 0 ? 5 : 1;
  const std::vector<GraphEdge> tree = MinimumSpanningTree(4, edges);
  std::set<std::pair<int, int>> got;
  for (const GraphEdge& e : tree) got.insert({e.a, e.b});
  EXPECT_EQ(got, (std::set<std::pair<int, int>>{{0, 1}, {1, 2}, {2, 3}}));
}

TEST(MapperGraph, PosesAlongTreePathsCompose) {
  std::mt19937_64 rng(3);
  std::vector<Rigid3> truth(5);  // root_from_node
  truth[0] = Rigid3::Identity();
  for (int i = 1; i < 5; ++i) truth[i] = RandomRigid(rng, 1.0);
  // Tree 0-1, 1-2, 0-3, 3-4 with edge transforms a_from_b = inv(root_from_a) * root_from_b; one edge
  // given reversed (a > b) to check the inverse direction.
  std::vector<GraphEdge> tree = {
      Edge(0, 1, 1, Inverse(truth[0]) * truth[1]), Edge(1, 2, 1, Inverse(truth[1]) * truth[2]),
      Edge(0, 3, 1, Inverse(truth[0]) * truth[3]), Edge(4, 3, 1, Inverse(truth[4]) * truth[3])};
  const TreePoses poses = PosesFromTree(5, 0, tree);
  for (int i = 0; i < 5; ++i) {
    ASSERT_TRUE(poses.placed[i]);
    EXPECT_LT(TranslationDistance(poses.root_from_node[i], truth[i]), 1e-12) << i;
    EXPECT_LT(RotationAngle(poses.root_from_node[i], truth[i]), 1e-12) << i;
  }
  EXPECT_EQ(poses.depth[4], 2);
  // A node outside the tree is not placed.
  const TreePoses partial = PosesFromTree(6, 0, tree);
  EXPECT_FALSE(partial.placed[5]);
}

TEST(MapperGraph, BestConnectedNodeAndComponents) {
  std::vector<GraphEdge> edges = {Edge(0, 1, 1, Rigid3::Identity(), 5), Edge(1, 2, 1, Rigid3::Identity(), 50),
                                  Edge(3, 4, 1, Rigid3::Identity(), 100)};
  EXPECT_EQ(BestConnectedNode(5, edges), 3);  // 100 (ties by index: 3 before 4)
  EXPECT_EQ(BestConnectedNode(5, edges, {true, true, true, false, false}), 1);  // 5 + 50
  const std::vector<bool> c = ComponentOf(5, 0, edges);
  EXPECT_EQ(c, (std::vector<bool>{true, true, true, false, false}));
}

TEST(MapperGraph, EdgeMedoidIsRobustToWrongHypotheses) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> n(0.0, 1.0);
  const Rigid3 truth = Pose(0.3, -0.2, 0.1, 0.1, 0.05, -0.02);
  PairCandidates pair;
  pair.a = 0;
  pair.b = 1;
  for (int e = 0; e < 60; ++e) {
    std::vector<Rigid3> cands;
    Vector6d d;
    for (int k = 0; k < 6; ++k) d[k] = n(rng) * (k < 3 ? 0.5 * kDeg : 0.0005);
    cands.push_back(PerturbLeft(truth, d));
    if (e % 2 == 0) cands.push_back(RandomRigid(rng, 0.2));  // a wrong (mirror) hypothesis
    pair.AddEvent(cands);
  }
  pair.total_events = pair.num_events;
  pair.total_candidates = static_cast<int64_t>(pair.a_from_b.size());
  MedoidOptions mo;
  mo.point_scale = 0.1;
  const GraphEdge edge = EvaluateEdge(pair, mo, 10.0, ConsistencyOptions());
  EXPECT_LT(TranslationDistance(edge.a_from_b, truth), 0.002);
  EXPECT_LT(RotationAngle(edge.a_from_b, truth), 2 * kDeg);
  EXPECT_EQ(edge.candidates, 90);
  EXPECT_GE(edge.support, 58);  // every event has its true candidate
  EXPECT_EQ(edge.stored_events, 60);
  // Few candidates make the edge dear (tau_n): same d/s, fewer candidates -> higher cost.
  PairCandidates few;
  few.a = 0;
  few.b = 1;
  for (int e = 0; e < 3; ++e) few.AddEvent({pair.a_from_b[e * 3]});
  few.total_events = 3;
  few.total_candidates = 3;
  const GraphEdge dear = EvaluateEdge(few, mo, 10.0, ConsistencyOptions());
  EXPECT_GT(dear.cost, 0.0);
  MedoidResult r;
  r.num_candidates = 3;
  r.summed_distance = 1.0;
  EXPECT_NEAR(MedoidEdgeCost(r, 10.0), (1.0 / 3) * (10.0 / 3), 1e-12);
}

TEST(MapperGraph, InconsistentPairHasLittleSupport) {
  std::mt19937_64 rng(7);
  PairCandidates pair;
  pair.a = 0;
  pair.b = 1;
  for (int e = 0; e < 50; ++e) pair.AddEvent({RandomRigid(rng, 0.5)});
  pair.total_events = 50;
  pair.total_candidates = 50;
  const GraphEdge edge = EvaluateEdge(pair, MedoidOptions(), 10.0, ConsistencyOptions());
  EXPECT_LT(edge.SupportFraction(), 0.2);
}

// SquarePoseCovariance against the spread of IPPE's poses from noisy corners: a 16 px square seen at 40
// deg, 0.5 px noise on every corner coordinate. Along each principal direction of the predicted covariance
// the measured variance is within 30 % of the prediction (measured: within 7 %; the tilt is the loosest,
// 3.7 deg).
TEST(MapperGraph, SquarePoseCovarianceMatchesTheSpreadOfNoisyPoses) {
  CameraModel camera = CameraModel::Pinhole(640, 480, 600, 320, 240);
  const double side = 0.025, sigma_px = 0.5;
  const Rigid3 cam_from_marker = Pose(0.7, 0.1, 0.3, 0.05, -0.03, 0.9);
  const MarkerCorners3d corners = MarkerCornersInMarker(side);
  MarkerCorners2d truth;
  for (int k = 0; k < 4; ++k) truth[k] = camera.Project(cam_from_marker * corners[k]);
  const Matrix6d predicted = SquarePoseCovariance(cam_from_marker, side, MeanSideLength(truth), sigma_px);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0.0, sigma_px);
  std::vector<Vector6d> deltas;
  for (int trial = 0; trial < 4000; ++trial) {
    MarkerCorners2d noisy = truth;
    for (Eigen::Vector2d& c : noisy) c += Eigen::Vector2d(noise(rng), noise(rng));
    const SquarePose pose = EstimateSquarePose(camera, noisy, side);
    ASSERT_TRUE(pose.ok);
    // The hypothesis on the true branch (the other one is the mirror the mapper's medoid sorts out).
    const PoseHypothesis* nearest = &pose.hypotheses[0];
    for (int h = 1; h < pose.num_hypotheses; ++h)
      if (RotationAngle(pose.hypotheses[h].cam_from_marker, cam_from_marker) <
          RotationAngle(nearest->cam_from_marker, cam_from_marker))
        nearest = &pose.hypotheses[h];
    const Rigid3 d = Inverse(cam_from_marker) * nearest->cam_from_marker;  // truth * Exp(delta)
    Vector6d delta;
    delta << VectorFromRotation(d.rotation()), d.translation();
    deltas.push_back(delta);
  }
  Matrix6d measured = Matrix6d::Zero();
  for (const Vector6d& d : deltas) measured += d * d.transpose() / deltas.size();
  const Eigen::SelfAdjointEigenSolver<Matrix6d> principal(predicted);
  for (int i = 0; i < 6; ++i) {
    const Vector6d u = principal.eigenvectors().col(i);
    const double ratio = u.dot(measured * u) / principal.eigenvalues()(i);
    std::printf("principal direction %d: predicted sd %.3g, measured / predicted variance %.3f\n", i,
                std::sqrt(principal.eigenvalues()(i)), ratio);
    EXPECT_GT(ratio, 0.7) << i;
    EXPECT_LT(ratio, 1.3) << i;
  }
}

// MahalanobisFactor's forward substitution gives the distance the full covariance's solve gives, also at the
// spread of conditions of a square pose's covariance (variances 1e-10 .. 1: sub-mm translation, a tilt pinned
// to degrees, the 1 rad prior), and an infinite one where the matrix is not positive definite.
TEST(MapperGraph, MahalanobisFactorIsTheCovariancesDistance) {
  std::mt19937_64 rng(17);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 50; ++trial) {
    Matrix6d random;
    for (int i = 0; i < 36; ++i) random(i) = n(rng);
    const Eigen::HouseholderQR<Matrix6d> qr(random);
    const Matrix6d q = qr.householderQ();
    Vector6d variances;
    for (int i = 0; i < 6; ++i) variances[i] = std::pow(10.0, -10.0 * (i + trial % 3) / 7.0);
    const Matrix6d covariance = q * variances.asDiagonal() * q.transpose();
    const MahalanobisFactor factor(covariance);
    ASSERT_TRUE(factor.valid()) << trial;
    for (int k = 0; k < 5; ++k) {
      Vector6d delta;
      for (int i = 0; i < 6; ++i) delta[i] = n(rng) * 1e-3;
      const double expected = delta.dot(covariance.ldlt().solve(delta));
      EXPECT_NEAR(factor.SquaredDistance(delta), expected, 1e-9 * expected) << trial << " " << k;
    }
  }
  Matrix6d indefinite = Matrix6d::Identity();
  indefinite(2, 2) = -1.0;
  EXPECT_FALSE(MahalanobisFactor(indefinite).valid());
  EXPECT_TRUE(std::isinf(MahalanobisFactor(indefinite).SquaredDistance(Vector6d::Ones())));
  EXPECT_TRUE(std::isinf(MahalanobisFactor().SquaredDistance(Vector6d::Ones())));
}

// ---------------------------------------------------------------------------------------------
// Ceres residual and manifold

TEST(MapperBundle, ManifoldPlusMinusRoundTrip) {
  LeftPoseManifold manifold;
  std::mt19937_64 rng(11);
  for (int trial = 0; trial < 20; ++trial) {
    const PoseBlock x = BlockFromRigid(RandomRigid(rng, 1.0));
    double delta[6] = {0.1, -0.2, 0.05, 0.01, 0.02, -0.03};
    PoseBlock y;
    ASSERT_TRUE(manifold.Plus(x.data(), delta, y.data()));
    double back[6];
    ASSERT_TRUE(manifold.Minus(y.data(), x.data(), back));
    for (int k = 0; k < 6; ++k) EXPECT_NEAR(back[k], delta[k], 1e-12);
    // Plus is the left perturbation of core's PerturbLeft for rotation, plain addition for translation.
    const Rigid3 px = RigidFromBlock(x.data()), py = RigidFromBlock(y.data());
    const Eigen::Matrix3d expected =
        RotationFromVector(Eigen::Vector3d(delta[0], delta[1], delta[2])) * px.linear();
    EXPECT_LT(RotationAngle(py.linear(), expected), 1e-12);
    EXPECT_LT((py.translation() - px.translation() - Eigen::Vector3d(delta[3], delta[4], delta[5])).norm(),
              1e-15);
  }
}

TEST(MapperBundle, ResidualJacobianMatchesNumericDifferentiation) {
  for (int distortion = 0; distortion < 6; ++distortion) {
    const bool weighted = distortion >= 3;  // corners weighed by their sides (CornerSqrtInformation)
    CameraModel model;
    model.width = 1280;
    model.height = 720;
    model.fx = 900;
    model.fy = 905;
    model.cx = 640;
    model.cy = 360;
    if (distortion % 3 == 1) {
      model.model = DistortionModel::kRadTan;
      model.distortion = {-0.3, 0.05, -0.004, 0.004, 0.06};
    } else if (distortion % 3 == 2) {
      model.model = DistortionModel::kFisheye;
      model.distortion = {0.05, -0.01, 0.002, -0.001};
    }
    const Rigid3 cam_from_rig = Pose(0.1, -0.3, 0.2, 0.05, -0.1, 0.8);
    const Rigid3 object_from_marker = Pose(0.2, 0.4, -0.1, 0.05, 0.02, 0.01);
    const Rigid3 rig_from_object = Pose(-0.2, 0.1, 0.3, 0.1, 0.0, 0.3);
    MarkerCorners2d observed;
    for (int k = 0; k < 4; ++k) observed[k] = Eigen::Vector2d(600 + 10 * k, 350 - 5 * k);
    const CornerWeights weights = CornerSqrtInformation(
        {Eigen::Vector2d(0, 0), Eigen::Vector2d(20, 3), Eigen::Vector2d(40, 0), Eigen::Vector2d(20, -3)},
        0.05);
    std::unique_ptr<ceres::CostFunction> cost(
        ReprojectionCost::Create(&model, observed, 0.04, weighted ? &weights : nullptr));
    std::array<PoseBlock, 3> blocks = {BlockFromRigid(cam_from_rig), BlockFromRigid(object_from_marker),
                                       BlockFromRigid(rig_from_object)};
    const double* params[3] = {blocks[0].data(), blocks[1].data(), blocks[2].data()};
    double residuals[8];
    Eigen::Matrix<double, 8, 7, Eigen::RowMajor> jac[3];
    double* jacobians[3] = {jac[0].data(), jac[1].data(), jac[2].data()};
    ASSERT_TRUE(cost->Evaluate(params, residuals, jacobians));
    // The residual itself: projection minus observation (weighed by the corner's W).
    const Eigen::Vector3d p =
        cam_from_rig * rig_from_object * object_from_marker * MarkerCornersInMarker(0.04)[2];
    const Eigen::Vector2d r =
        (weighted ? weights[2] : Eigen::Matrix2d::Identity()) * (model.Project(p) - observed[2]);
    EXPECT_NEAR(residuals[4], r.x(), 1e-9);
    EXPECT_NEAR(residuals[5], r.y(), 1e-9);
    LeftPoseManifold manifold;
    for (int b = 0; b < 3; ++b) {
      for (int k = 0; k < 6; ++k) {
        const double h = 1e-6;
        double delta[6] = {0, 0, 0, 0, 0, 0};
        PoseBlock plus, minus;
        delta[k] = h;
        manifold.Plus(blocks[b].data(), delta, plus.data());
        delta[k] = -h;
        manifold.Plus(blocks[b].data(), delta, minus.data());
        double rp[8], rm[8];
        const double* pp[3] = {params[0], params[1], params[2]};
        pp[b] = plus.data();
        ASSERT_TRUE(cost->Evaluate(pp, rp, nullptr));
        pp[b] = minus.data();
        ASSERT_TRUE(cost->Evaluate(pp, rm, nullptr));
        for (int r = 0; r < 8; ++r) {
          const double numeric = (rp[r] - rm[r]) / (2 * h);
          EXPECT_NEAR(jac[b](r, k), numeric, 1e-4 * std::max(1.0, std::abs(numeric)))
              << "distortion " << distortion << " block " << b << " tangent " << k << " residual " << r;
        }
      }
      for (int r = 0; r < 8; ++r) EXPECT_EQ(jac[b](r, 6), 0.0);
    }
  }
}

// The bundle keeps one ReprojectionCost per observation through its solves (with Ceres' Jacobian the
// mapper's peak memory): it stores only what it reads (448 bytes when it held a SelfCalibrationCost with
// the corners in 3-d, weights and a clock; 128 now) and computes exactly what SelfCalibrationCost computes
// with the intrinsics given and no clock.
TEST(MapperBundle, ReprojectionCostIsSmallAndEqualsTheSelfCalibrationCost) {
  EXPECT_LE(sizeof(ReprojectionCost), 160u);
  CameraModel model = CameraModel::Pinhole(1280, 720, 900, 640, 360);
  model.model = DistortionModel::kRadTan;
  model.distortion = {-0.3, 0.05, -0.004, 0.004, 0.06};
  MarkerCorners2d observed;
  for (int k = 0; k < 4; ++k) observed[k] = Eigen::Vector2d(600 + 10 * k, 350 - 5 * k);
  const CornerWeights weights = CornerSqrtInformation(
      {Eigen::Vector2d(0, 0), Eigen::Vector2d(20, 3), Eigen::Vector2d(40, 0), Eigen::Vector2d(20, -3)}, 0.05);
  std::array<PoseBlock, 3> blocks = {BlockFromRigid(Pose(0.1, -0.3, 0.2, 0.05, -0.1, 0.8)),
                                     BlockFromRigid(Pose(0.2, 0.4, -0.1, 0.05, 0.02, 0.01)),
                                     BlockFromRigid(Pose(-0.2, 0.1, 0.3, 0.1, 0.0, 0.3))};
  const double* params[3] = {blocks[0].data(), blocks[1].data(), blocks[2].data()};
  for (const CornerWeights* w : {static_cast<const CornerWeights*>(nullptr), &weights}) {
    const ReprojectionCost cost(&model, observed, 0.04, w);
    const SelfCalibrationCost reference(&model, observed, 0.04, false, nullptr, w);
    double r[2][8];
    Eigen::Matrix<double, 8, 7, Eigen::RowMajor> jac[2][3];
    double* j0[3] = {jac[0][0].data(), jac[0][1].data(), jac[0][2].data()};
    double* j1[3] = {jac[1][0].data(), jac[1][1].data(), jac[1][2].data()};
    ASSERT_TRUE(cost.Evaluate(params, r[0], j0));
    ASSERT_TRUE(reference.Evaluate(params, r[1], j1));
    for (int i = 0; i < 8; ++i) EXPECT_EQ(r[0][i], r[1][i]);
    for (int b = 0; b < 3; ++b) EXPECT_EQ(jac[0][b], jac[1][b]) << "block " << b;
  }
}

TEST(MapperBundle, PointBehindCameraFailsTheEvaluation) {
  CameraModel model = CameraModel::Pinhole(640, 480, 500, 320, 240);
  MarkerCorners2d observed{};
  std::unique_ptr<ceres::CostFunction> cost(ReprojectionCost::Create(&model, observed, 0.04));
  std::array<PoseBlock, 3> blocks = {BlockFromRigid(Pose(0, 0, 0, 0, 0, -1)),
                                     BlockFromRigid(Rigid3::Identity()), BlockFromRigid(Rigid3::Identity())};
  const double* params[3] = {blocks[0].data(), blocks[1].data(), blocks[2].data()};
  double residuals[8];
  EXPECT_FALSE(cost->Evaluate(params, residuals, nullptr));
}

// ---------------------------------------------------------------------------------------------
// Initialisation steps on a synthetic scene (refine = false): the graph initialisation alone must land
// near the truth, which needs the right IPPE hypotheses, the right MST paths and per-frame medoids.

TEST(MapperInit, InitialisationAloneIsCloseToTruth) {
  const sim::Session session = sim::SimulateSession(test::MapperSession(120, 1, 0.2));
  const sim::GroundTruth truth = session.Truth();
  MapperOptions options = test::MapperOptionsFor(truth);
  options.refine = false;
  const MapResult result = test::MapMessages(session.Messages(), options);
  EXPECT_GT(result.report.ambiguous_observations, 0) << "the scene should exercise both hypotheses";
  ASSERT_EQ(result.initial_map.cameras.size(), 5u);
  ASSERT_EQ(result.initial_map.markers.size(), 4u);
  const sim::EvalResult e = sim::Evaluate(truth, &result.initial_map, &result.initial_trajectory);
  EXPECT_LT(e.camera_position_mm.max, 30);
  EXPECT_LT(e.camera_rotation_deg.max, 2.0);
  EXPECT_LT(e.configuration_mm.max, 5);
  EXPECT_LT(e.object_translation_aligned_mm.mean, 10);
  EXPECT_LT(e.object_rotation_deg.mean, 5.0);  // single-square poses: degrees before refinement
  EXPECT_GE(e.frames_with_pose, 110);
  // The reference camera and marker are identity in the map.
  const MapCamera* ref = result.initial_map.FindCamera(result.initial_map.reference_camera);
  ASSERT_NE(ref, nullptr);
  EXPECT_LT(ref->rig_from_cam.translation().norm(), 1e-12);
  const MapMarker* refm = result.initial_map.FindMarker(result.initial_map.reference_marker);
  ASSERT_NE(refm, nullptr);
  EXPECT_LT(refm->object_from_marker.translation().norm(), 1e-12);
}

TEST(MapperInit, ConfiguredReferencesAreUsed) {
  const sim::Session session = sim::SimulateSession(test::MapperSession(60));
  const int marker = session.object().markers[2].id;
  MapperOptions options = test::MapperOptionsFor(session.Truth());
  options.reference_camera = "cam3";
  options.reference_marker = marker;
  options.refine = false;
  const MapResult result = test::MapMessages(session.Messages(), options);
  EXPECT_EQ(result.map.reference_camera, "cam3");
  EXPECT_EQ(result.map.reference_marker, marker);
  EXPECT_LT(result.map.FindCamera("cam3")->rig_from_cam.translation().norm(), 1e-12);
}

}  // namespace
}  // namespace mcmt
