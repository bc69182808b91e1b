#include <gtest/gtest.h>

#include <random>

#include "core/medoid.h"

namespace mcmt {
namespace {

// Inliers: the truth perturbed by small noise; outliers: random transforms (wrong hypotheses).
std::vector<Rigid3> Candidates(const Rigid3& truth, int inliers, int outliers, std::mt19937_64& rng,
                               std::vector<bool>* is_inlier) {
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<Rigid3> out;
  is_inlier->clear();
  for (int i = 0; i < inliers; ++i) {
    Vector6d d;
    for (int k = 0; k < 3; ++k) d[k] = 0.01 * noise(rng);
    for (int k = 3; k < 6; ++k) d[k] = 0.005 * noise(rng);
    out.push_back(PerturbLeft(truth, d));
    is_inlier->push_back(true);
  }
  for (int i = 0; i < outliers; ++i) {
    out.push_back(RandomRigid(rng, 1.0));
    is_inlier->push_back(false);
  }
  // Shuffle so that position does not help.
  std::vector<int> order(out.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::shuffle(order.begin(), order.end(), rng);
  std::vector<Rigid3> shuffled;
  std::vector<bool> flags;
  for (int i : order) {
    shuffled.push_back(out[i]);
    flags.push_back((*is_inlier)[i]);
  }
  *is_inlier = flags;
  return shuffled;
}

TEST(Medoid, EmptyAndSingle) {
  EXPECT_EQ(TransformMedoid({}).index, -1);
  EXPECT_EQ(TransformMedoid({}).num_candidates, 0);
  const MedoidResult one = TransformMedoid({Rigid3::Identity()});
  EXPECT_EQ(one.index, 0);
  EXPECT_EQ(one.summed_distance, 0.0);
  EXPECT_EQ(one.MeanDistance(), 0.0);
}

TEST(Medoid, KnownDistances) {
  // Three translations along x: 0, 1, 3. Each probe point moves by the translation, so the distance
  // between candidates is 3 * |dx|. Sums: 0 -> 3+9 = 12, 1 -> 3+6 = 9, 3 -> 9+6 = 15.
  std::vector<Rigid3> c(3, Rigid3::Identity());
  c[1].translation() = Eigen::Vector3d(1, 0, 0);
  c[2].translation() = Eigen::Vector3d(3, 0, 0);
  const MedoidResult r = TransformMedoid(c);
  EXPECT_EQ(r.index, 1);
  EXPECT_EQ(r.num_candidates, 3);
  EXPECT_NEAR(r.summed_distance, 9.0, 1e-12);
  EXPECT_NEAR(r.MeanDistance(), 4.5, 1e-12);
  // e = (d / s) * max(1, tau_n / s) = (9 / 3) * (10 / 3).
  EXPECT_NEAR(MedoidEdgeCost(r, 10.0), 10.0, 1e-12);
  EXPECT_NEAR(MedoidEdgeCost(r, 2.0), 3.0, 1e-12);
}

TEST(Medoid, RotationsMoveProbePoints) {
  // Same translation, different rotations: probe scale matters.
  std::vector<Rigid3> c(2, Rigid3::Identity());
  c[1].linear() = Eigen::AngleAxisd(3.14159265358979323846, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  MedoidOptions o;
  o.point_scale = 0.5;
  // Rotation by pi about z: (s,0,0) -> (-s,0,0), (0,s,0) -> (0,-s,0), z fixed: distance 2s + 2s.
  EXPECT_NEAR(TransformMedoid(c, o).summed_distance, 2.0, 1e-12);
}

TEST(Medoid, PicksInlierUnderFortyPercentOutliersExact) {
  std::mt19937_64 rng(21);
  for (int trial = 0; trial < 50; ++trial) {
    const Rigid3 truth = RandomRigid(rng, 1.0);
    std::vector<bool> inlier;
    const auto c = Candidates(truth, 30, 20, rng, &inlier);  // 40 % outliers
    const MedoidResult r = TransformMedoid(c);
    ASSERT_GE(r.index, 0);
    EXPECT_TRUE(inlier[r.index]) << "trial " << trial;
    EXPECT_LT(RotationAngle(c[r.index], truth), 0.05);
  }
}

TEST(Medoid, PicksInlierUnderFortyPercentOutliersSubsampled) {
  std::mt19937_64 rng(22);
  MedoidOptions options;
  options.max_exact = 200;
  for (int trial = 0; trial < 20; ++trial) {
    const Rigid3 truth = RandomRigid(rng, 1.0);
    std::vector<bool> inlier;
    const auto c = Candidates(truth, 600, 400, rng, &inlier);
    const MedoidResult r = TransformMedoid(c, options);
    ASSERT_GE(r.index, 0);
    EXPECT_EQ(r.num_candidates, 1000);
    EXPECT_TRUE(inlier[r.index]) << "trial " << trial;
    // The estimated sum is close to the exact sum of the chosen candidate.
    MedoidOptions exact;
    exact.max_exact = 100000;
    const MedoidResult e = TransformMedoid(c, exact);
    EXPECT_TRUE(inlier[e.index]);
    // 200 references: the outlier share of the subset varies by ~9 % (one sigma).
    EXPECT_NEAR(r.summed_distance / e.summed_distance, 1.0, 0.35);
  }
}

TEST(Medoid, SubsampledIsDeterministicAndSameOnCleanData) {
  std::mt19937_64 rng(23);
  std::vector<Rigid3> c;
  // Clean data: one candidate is exactly the centre, the others are symmetric about it.
  const Rigid3 centre = RandomRigid(rng, 1.0);
  c.push_back(centre);
  for (int i = 0; i < 300; ++i) {
    Vector6d d = Vector6d::Zero();
    d[3 + i % 3] = 0.01 * (1 + i / 6) * (i % 6 < 3 ? 1 : -1);
    c.push_back(PerturbLeft(centre, d));
  }
  MedoidOptions sub;
  sub.max_exact = 100;
  const MedoidResult a = TransformMedoid(c, sub), b = TransformMedoid(c, sub);
  EXPECT_EQ(a.index, b.index);
  EXPECT_EQ(a.summed_distance, b.summed_distance);
  EXPECT_EQ(TransformMedoid(c).index, 0);
  EXPECT_EQ(a.index, 0);
}

}  // namespace
}  // namespace mcmt
