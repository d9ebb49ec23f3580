// Signed SVD, constraint projections, and finite-difference checks of every energy's gradient
// and Hessian.

#include "sim/elastic_model.hpp"
#include "sim/signed_svd.hpp"
#include "sim/tet_constraints.hpp"
#include "tests/support/finite_difference.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <random>

using namespace phantasm;
using namespace phantasm::testing;

namespace {

Eigen::Matrix3d random_matrix(std::mt19937& random, double scale) {
  std::normal_distribution<double> normal(0.0, scale);
  Eigen::Matrix3d m;
  for (int i = 0; i < 9; ++i)
    m.data()[i] = normal(random);
  return m;
}

Eigen::Matrix3d random_rotation(std::mt19937& random) {
  std::normal_distribution<double> normal;
  return Eigen::Quaterniond(normal(random), normal(random), normal(random), normal(random))
      .normalized()
      .toRotationMatrix();
}

} // namespace

TEST(SignedSvd, ReconstructsRotationsAndSignConventionIncludingInvertedMatrices) {
  std::mt19937 random(7);
  for (int trial = 0; trial < 500; ++trial) {
    Eigen::Matrix3d F = Eigen::Matrix3d::Identity() + random_matrix(random, trial < 250 ? 0.3 : 2.0);
    if (trial % 5 == 0) F.col(0) = -F.col(0); // inverted
    Eigen::Quaterniond warm = Eigen::Quaterniond::Identity();
    const SignedSvd svd = signed_svd(F, warm, 200);
    EXPECT_LT((svd.U * svd.sigma.asDiagonal() * svd.V.transpose() - F).norm(), 1e-9 * F.norm()) << F;
    EXPECT_NEAR(svd.U.determinant(), 1.0, 1e-9);
    EXPECT_NEAR(svd.V.determinant(), 1.0, 1e-9);
    EXPECT_GE(svd.sigma[0], svd.sigma[1]);
    EXPECT_GE(svd.sigma[1], svd.sigma[2]);
    EXPECT_GE(svd.sigma[1], 0.0);
    // |sigma| are the singular values; a negative one exactly when det F < 0, and the smallest.
    const Eigen::Vector3d reference = Eigen::JacobiSVD<Eigen::Matrix3d>(F).singularValues();
    Eigen::Vector3d magnitudes = svd.sigma.cwiseAbs();
    std::sort(magnitudes.data(), magnitudes.data() + 3, std::greater<>());
    EXPECT_LT((magnitudes - reference).norm(), 1e-9 * reference[0]);
    EXPECT_EQ(svd.sigma[2] < 0.0, F.determinant() < 0.0);
    EXPECT_NEAR(std::abs(svd.sigma[2]), reference[2], 1e-9 * reference[0]);
  }
}

TEST(SignedSvd, AWarmStartFromTheLastRotationConvergesInAFewIterations) {
  std::mt19937 random(3);
  const Eigen::Matrix3d R = random_rotation(random);
  const Eigen::Matrix3d F = R * Eigen::Vector3d(1.2, 0.9, 0.8).asDiagonal();
  Eigen::Quaterniond warm = Eigen::Quaterniond::Identity();
  signed_svd(F, warm, 200);
  const Eigen::Matrix3d turned = Eigen::AngleAxisd(0.01, Eigen::Vector3d::UnitX()).toRotationMatrix() * F;
  Eigen::Quaterniond from_last = warm;
  const SignedSvd svd = signed_svd(turned, from_last, 4);
  EXPECT_LT((svd.U * svd.sigma.asDiagonal() * svd.V.transpose() - turned).norm(), 1e-9);
}

TEST(TetProjections, LandInTheirSetsAtTheEdgesOfEveryRange) {
  const SingularValueRange rigid{1.0, 1.0}, limited{0.9, 1.1};
  for (const Eigen::Vector3d& sigma :
       {Eigen::Vector3d(1.5, 1.0, 0.5), Eigen::Vector3d(1.1, 1.0, 0.9), Eigen::Vector3d(2.0, 1.0, -0.3),
        Eigen::Vector3d(1e-9, 1e-9, 1e-9), Eigen::Vector3d(1e6, 1.0, 1.0), Eigen::Vector3d(1.0, 1.0, 1.0)}) {
    SCOPED_TRACE(sigma.transpose());
    EXPECT_EQ(project_strain(sigma, rigid), Eigen::Vector3d::Ones());
    const Eigen::Vector3d s = project_strain(sigma, limited);
    EXPECT_TRUE((s.array() >= 0.9).all() && (s.array() <= 1.1).all());
    EXPECT_EQ(project_strain(Eigen::Vector3d(1.05, 0.95, 1.0), limited), Eigen::Vector3d(1.05, 0.95, 1.0));
    for (const SingularValueRange& range : {rigid, SingularValueRange{0.95, 1.05}}) {
      const Eigen::Vector3d v = project_volume(sigma, range);
      EXPECT_GE(v.prod(), range.min * (1 - 1e-10));
      EXPECT_LE(v.prod(), range.max * (1 + 1e-10));
      EXPECT_TRUE((v.array() > 0.0).all());
    }
  }
  // Inside the volume range nothing moves; outside, the projection is the closest point: the
  // residual is normal to the constraint surface (parallel to grad prod).
  EXPECT_EQ(project_volume(Eigen::Vector3d(1.02, 1.0, 1.0), {0.95, 1.05}), Eigen::Vector3d(1.02, 1.0, 1.0));
  const Eigen::Vector3d sigma(1.5, 1.1, 0.7);
  const Eigen::Vector3d v = project_volume(sigma, {1.0, 1.0});
  const Eigen::Vector3d normal(v[1] * v[2], v[0] * v[2], v[0] * v[1]);
  EXPECT_LT((sigma - v).normalized().cross(normal.normalized()).norm(), 1e-9);
}

// The energy of a tet as a function of its 12 coordinates: gradient and (where it is PSD
// already, so projection changes nothing) Hessian against central differences.
TEST(TetEnergy, GradientAndHessianMatchFiniteDifferences) {
  std::mt19937 random(11);
  ElasticModel model;
  Eigen::MatrixX3d rest(4, 3);
  rest << 0, 0, 0, 0.01, 0, 0, 0, 0.01, 0, 0, 0, 0.01;
  Eigen::MatrixX4i tet(1, 4);
  tet << 0, 1, 2, 3;
  add_body(model, rest, tet, lame_parameters(1e4, 0.4), 1000.0);
  for (const SingularValueRange& strain : {SingularValueRange{1.0, 1.0}, SingularValueRange{0.9, 1.1}}) {
    model.strain_range = strain;
    model.volume_range = {0.98, 1.02};
    for (int trial = 0; trial < 20; ++trial) {
      // Stretched tets (all singular values > 1.2): every Hessian mode is non-negative.
      Eigen::MatrixX3d p = rest * 1.3;
      p += 0.001 *
           Eigen::MatrixX3d::NullaryExpr(4, 3, [&] { return std::normal_distribution<double>()(random); });
      const StepInertia none;
      const Eigen::MatrixX3d numeric = central_difference_gradient(
          [&](const Eigen::MatrixX3d& x) { return model_energy(model, none, x); }, p, 1e-8);
      EXPECT_TRUE(matches_finite_differences(model_gradient(model, none, p), numeric, 1e-5))
          << "strain range " << strain.min << " to " << strain.max << ", trial " << trial;
    }
  }
}

// Energies and gradients (model_energy, model_gradient) never read the Hessian: without it, the
// same value and gradient, bit for bit, and a zero Hessian, on and off both sets.
TEST(TetEnergy, WithoutTheHessianTheValueAndGradientAreTheSame) {
  std::mt19937 random(9);
  std::uniform_real_distribution<double> value(-0.5, 2.0);
  const SingularValueRange range{0.9, 1.1};
  int off_the_set = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Vector3d sigma(value(random), value(random), value(random));
    for (TetConstraintKind kind : {TetConstraintKind::strain, TetConstraintKind::volume}) {
      const SingularValueEnergy full = singular_value_energy(kind, range, 2.0, sigma);
      const SingularValueEnergy cheap = singular_value_energy(kind, range, 2.0, sigma, false);
      EXPECT_EQ(cheap.value, full.value);
      EXPECT_EQ(cheap.gradient, full.gradient);
      EXPECT_TRUE(cheap.hessian.isZero(0.0));
      if (!full.hessian.isZero(0.0)) ++off_the_set;
    }
  }
  EXPECT_GT(off_the_set, 100); // the comparison covered Hessians that are not zero
}

// The closed-form eigensystem gives the exact Hessian; its projection is PSD and changes nothing
// where the Hessian is PSD already (ARAP strain under stretch).
TEST(TetEnergy, HessianMatchesFiniteDifferencesAndItsProjectionIsPositive) {
  std::mt19937 random(5);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Matrix3d F = random_rotation(random) *
                              Eigen::Vector3d(1.4 + 0.1 * trial / 20.0, 1.3, 1.25).asDiagonal() *
                              random_rotation(random).transpose();
    for (TetConstraintKind kind : {TetConstraintKind::strain, TetConstraintKind::volume}) {
      const SingularValueRange range{1.0, 1.0};
      auto stress = [&](const Eigen::Matrix3d& G) {
        Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
        const SignedSvd s = signed_svd(G, q, 200);
        return Eigen::Matrix3d(s.U * singular_value_energy(kind, range, 2.0, s.sigma).gradient.asDiagonal() *
                               s.V.transpose());
      };
      Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
      const SignedSvd svd = signed_svd(F, q, 200);
      const SingularValueEnergy energy = singular_value_energy(kind, range, 2.0, svd.sigma);
      const Eigen::Matrix<double, 9, 9> H = projected_hessian(svd, energy, false);
      const Eigen::Matrix<double, 9, 9> projected = projected_hessian(svd, energy);
      const double smallest =
          Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 9, 9>>(projected).eigenvalues().minCoeff();
      EXPECT_GE(smallest, -1e-9 * projected.norm());
      if (kind == TetConstraintKind::strain) {
        EXPECT_LT((projected - H).norm(), 1e-9 * H.norm());
      }
      // The Hessian in column-major order of F is the Jacobian of the stress d E / d F.
      const Eigen::MatrixXd numeric = central_difference_jacobian(stress, F, 1e-6);
      EXPECT_TRUE(matches_finite_differences(H, numeric, 1e-4)) << "kind " << static_cast<int>(kind);
    }
  }
}
