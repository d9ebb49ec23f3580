// The local step's batched tet projections: the same projections as the scalar signed SVD and
// projections, lane by lane, with bits that depend neither on the lane nor on the SIMD path.

#include "sim/signed_svd.hpp"
#include "sim/tet_constraints.hpp"
#include "sim/tet_projection_batch.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <vector>

using namespace phantasm;

namespace {

/// A tet's state and results as the local step keeps them.
struct TetState {
  Eigen::Matrix3d F;
  double strain_weight = 1.0, volume_weight = 1.0;
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  Eigen::Matrix3d eigenvectors = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d projection = Eigen::Matrix3d::Zero();
  double energy = 0.0;
};

void project(std::vector<TetState*> tets, const SingularValueRange& strain, const SingularValueRange& volume,
             SimdPath path = SimdPath::best) {
  TetBatch batch;
  batch.count = static_cast<int>(tets.size());
  for (std::size_t i = 0; i < tets.size(); ++i) {
    batch.F[i] = tets[i]->F;
    batch.strain_weight[i] = tets[i]->strain_weight;
    batch.volume_weight[i] = tets[i]->volume_weight;
    batch.rotation[i] = &tets[i]->rotation;
    batch.eigenvectors[i] = &tets[i]->eigenvectors;
    batch.projection[i] = &tets[i]->projection;
    batch.energy[i] = &tets[i]->energy;
  }
  project_tet_batch(batch, strain, volume, path);
}

/// Deformation gradients of every kind a solve meets: nearly rigid, stretched, rotated by large
/// angles, inverted, collapsed to a plane or a line, and zero.
std::vector<Eigen::Matrix3d> test_matrices(std::mt19937& random) {
  std::normal_distribution<double> normal;
  auto rotation = [&] {
    return Eigen::Quaterniond(normal(random), normal(random), normal(random), normal(random))
        .normalized()
        .toRotationMatrix();
  };
  std::vector<Eigen::Matrix3d> matrices;
  for (int k = 0; k < 400; ++k) {
    const double spread = k % 4 == 0 ? 1e-3 : k % 4 == 1 ? 0.05 : k % 4 == 2 ? 0.5 : 2.0;
    Eigen::Vector3d sigma(1.0 + spread * normal(random), 1.0 + spread * normal(random),
                          1.0 + spread * normal(random));
    if (k % 7 == 0) sigma[2] = -std::abs(sigma[2]); // inverted
    if (k % 11 == 0) sigma[2] = 0.0;                // flat
    if (k % 13 == 0) sigma[1] = sigma[2] = 0.0;     // a line
    matrices.push_back(rotation() * sigma.asDiagonal() * rotation().transpose());
  }
  matrices.push_back(Eigen::Matrix3d::Zero());
  matrices.push_back(-Eigen::Matrix3d::Identity()); // inverted three times: a half turn away
  return matrices;
}

bool same_bits(const TetState& a, const TetState& b) {
  return std::memcmp(a.projection.data(), b.projection.data(), sizeof(double) * 9) == 0 &&
         std::memcmp(&a.energy, &b.energy, sizeof(double)) == 0 &&
         std::memcmp(a.eigenvectors.data(), b.eigenvectors.data(), sizeof(double) * 9) == 0 &&
         std::memcmp(a.rotation.coeffs().data(), b.rotation.coeffs().data(), sizeof(double) * 4) == 0;
}

} // namespace

TEST(TetProjectionBatch, EqualsTheScalarSignedSvdAndProjections) {
  std::mt19937 random(11);
  const std::vector<Eigen::Matrix3d> matrices = test_matrices(random);
  for (const SingularValueRange& range : {SingularValueRange{1.0, 1.0}, SingularValueRange{0.9, 1.1}}) {
    for (std::size_t first = 0; first < matrices.size(); first += 3) { // batches of 3: a lane unused
      std::vector<TetState> states;
      for (std::size_t i = first; i < std::min(first + 3, matrices.size()); ++i) {
        TetState s;
        s.F = matrices[i];
        s.strain_weight = 2.0;
        s.volume_weight = 13.5;
        states.push_back(s);
      }
      std::vector<TetState*> pointers;
      for (TetState& s : states)
        pointers.push_back(&s);
      project(pointers, range, range);
      for (const TetState& s : states) {
        Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
        const SignedSvd svd = signed_svd(s.F, q, 40);
        const Eigen::Vector3d strain = project_strain(svd.sigma, range);
        const Eigen::Vector3d volume = project_volume(svd.sigma, range);
        const Eigen::Matrix3d expected =
            svd.V * (s.strain_weight * strain + s.volume_weight * volume).asDiagonal() * svd.U.transpose();
        const double energy = 0.5 * (s.strain_weight * (svd.sigma - strain).squaredNorm() +
                                     s.volume_weight * (svd.sigma - volume).squaredNorm());
        // The rotation, and so the projection, is unique unless the two smallest singular values
        // sum to zero (F of rank one or zero: any turn about the remaining direction is as close).
        const double scale = 1.0 + s.F.norm();
        if (std::abs(svd.sigma[1] + svd.sigma[2]) > 1e-6 * scale) {
          EXPECT_LT((s.projection - expected).norm(), 1e-10 * scale * 15.5) << s.F;
        }
        EXPECT_NEAR(s.energy, energy, 1e-10 * (1.0 + energy)) << s.F;
        // The warm starts written back: a unit quaternion, a rotation V, and R = U V^T.
        EXPECT_NEAR(s.rotation.norm(), 1.0, 1e-12);
        EXPECT_LT((s.eigenvectors.transpose() * s.eigenvectors - Eigen::Matrix3d::Identity()).norm(), 1e-10);
        EXPECT_NEAR(s.eigenvectors.determinant(), 1.0, 1e-10);
        ASSERT_TRUE(s.projection.allFinite());
      }
    }
  }
}

TEST(TetProjectionBatch, ResultsDependNeitherOnTheLaneNorOnTheInstructionSet) {
  std::mt19937 random(5);
  const std::vector<Eigen::Matrix3d> matrices = test_matrices(random);
  const SingularValueRange strain{0.95, 1.05}, volume{1.0, 1.0};
  for (std::size_t k = 0; k + 4 <= matrices.size(); k += 4) {
    // Tet k alone, then in each lane among three others (which converge in other numbers of
    // iterations), on both instruction sets.
    TetState alone;
    alone.F = matrices[k];
    project({&alone}, strain, volume);
    for (SimdPath path : {SimdPath::sse2, SimdPath::avx2}) {
      for (std::size_t lane = 0; lane < 4; ++lane) {
        TetState states[4];
        for (std::size_t i = 0; i < 4; ++i)
          states[i].F = matrices[k + (i + 4 - lane) % 4];
        project({&states[0], &states[1], &states[2], &states[3]}, strain, volume, path);
        ASSERT_TRUE(same_bits(states[lane], alone))
            << "tet " << k << " in lane " << lane << " on " << (path == SimdPath::sse2 ? "SSE2" : "AVX2");
      }
    }
  }
  // Without AVX2 the avx2 path runs SSE2 and the comparison above is between SSE2 runs.
  if (!avx2_available()) std::printf("this processor has no AVX2: only the SSE2 path was compared\n");
}

TEST(TetProjectionBatch, WarmStartsFromTheLastCallAgreeWithColdStarts) {
  // A tet turning and stretching a little per call, as in a running solve: warm starts from
  // the last call give the projection of a cold start.
  TetState warm;
  for (int step = 0; step < 50; ++step) {
    const double angle = 0.05 * step;
    warm.F = Eigen::AngleAxisd(angle, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix() *
             Eigen::Vector3d(1.0 + 0.004 * step, 1.0, 1.0 - 0.002 * step).asDiagonal();
    project({&warm}, SingularValueRange{}, SingularValueRange{});
    TetState cold;
    cold.F = warm.F;
    project({&cold}, SingularValueRange{}, SingularValueRange{});
    EXPECT_LT((warm.projection - cold.projection).norm(), 1e-11) << step;
    EXPECT_NEAR(warm.energy, cold.energy, 1e-13) << step;
  }
}
