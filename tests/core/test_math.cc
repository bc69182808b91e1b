// core/math.h: the principal direction of a 2-D scatter.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <random>

#include "core/math.h"

namespace mcmt {
namespace {

TEST(PrincipalDirection2d, ExactOnTheAxesAndDiagonals) {
  EXPECT_EQ(PrincipalDirection2d(4, 0, 1), Eigen::Vector2d(1, 0));
  EXPECT_EQ(PrincipalDirection2d(1, 0, 4), Eigen::Vector2d(0, 1));
  EXPECT_EQ(PrincipalDirection2d(2, 0, 2), Eigen::Vector2d(1, 0));  // isotropic: the x axis
  EXPECT_EQ(PrincipalDirection2d(0, 0, 0), Eigen::Vector2d(1, 0));
  const double h = std::sqrt(0.5);
  EXPECT_NEAR((PrincipalDirection2d(3, 1, 3) - Eigen::Vector2d(h, h)).norm(), 0, 1e-15);
  EXPECT_NEAR((PrincipalDirection2d(3, -1, 3) - Eigen::Vector2d(h, -h)).norm(), 0, 1e-15);
}

// Against Eigen's eigen-solver and the angle form 0.5 * atan2(2 sxy, sxx - syy) on random scatters of
// every orientation and elongation, down to nearly isotropic ones; the sign is x > 0.
TEST(PrincipalDirection2d, IsTheLargerEigenvector) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> angle_rad(-M_PI, M_PI), log_ratio(-12, -0.1);
  for (int i = 0; i < 2000; ++i) {
    const double a = angle_rad(rng), small = std::pow(10.0, log_ratio(rng) / 2);
    const Eigen::Vector2d d(std::cos(a), std::sin(a)), n(-d.y(), d.x());
    const Eigen::Matrix2d s = 3.0 * d * d.transpose() + 3.0 * small * n * n.transpose();
    const Eigen::Vector2d got = PrincipalDirection2d(s(0, 0), s(0, 1), s(1, 1));
    SCOPED_TRACE(testing::Message() << "angle " << a << " rad, ratio " << small);
    EXPECT_NEAR(got.norm(), 1.0, 1e-15);
    EXPECT_TRUE(got.x() > 0 || (got.x() == 0 && got.y() > 0));
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> solver(s);
    const Eigen::Vector2d largest = solver.eigenvectors().col(1);
    // The direction is determined to about eps / (1 - small), the eigenvalues' relative gap.
    const double tolerance = 1e-13 / (1 - small);
    EXPECT_LT(std::min((got - largest).norm(), (got + largest).norm()), tolerance);
    const double half = 0.5 * std::atan2(2 * s(0, 1), s(0, 0) - s(1, 1));
    EXPECT_LT((got - Eigen::Vector2d(std::cos(half), std::sin(half))).norm(), tolerance);
  }
}

}  // namespace
}  // namespace mcmt
