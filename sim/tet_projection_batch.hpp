// The local step for several tets at once in SIMD lanes (AVX2 or SSE2): signed SVD, strain and
// volume projections and right-hand-side terms, the same per lane as one tet alone.
#pragma once

#include "sim/tet_constraints.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>

namespace phantasm {

/// How many tets project_tet_batch() handles at once.
constexpr int tet_batch_size = 4;

/// The local step's work for up to tet_batch_size tets at once: the signed SVD of each
/// deformation gradient (the algorithm of signed_svd(): warm-started rotation iteration, Jacobi
/// sweeps from the last eigenvectors), the strain and volume projections of its singular values
/// and the term w_s T_s^T + w_v T_v^T = V diag(w_s s_s + w_v s_v) U^T of the right-hand side.
///
/// The tets are the lanes of SIMD vectors (four AVX2 lanes where the processor has AVX2, two
/// SSE2 lanes twice otherwise), running the same operations in lockstep: a lane that has
/// converged is masked, not updated, so every lane computes exactly what it would alone. Results
/// therefore depend neither on which tets share a batch nor on the processor (no fused
/// multiply-adds), only on each tet's own input. Rare cases (inverted tets whose rotation needs a
/// half turn, volume projections whose Newton iteration does not settle) are finished per lane
/// by the scalar routines.
struct TetBatch {
  int count = 0; ///< lanes in use, 1..tet_batch_size
  std::array<Eigen::Matrix3d, tet_batch_size> F;
  std::array<double, tet_batch_size> strain_weight{};
  std::array<double, tet_batch_size> volume_weight{};
  /// Warm starts, read and written: the rotation R = U V^T and the right singular vectors V.
  std::array<Eigen::Quaterniond*, tet_batch_size> rotation{};
  std::array<Eigen::Matrix3d*, tet_batch_size> eigenvectors{};
  /// Results: V diag(w_s s_s + w_v s_v) U^T and w_s/2 |sigma - s_s|^2 + w_v/2 |sigma - s_v|^2.
  std::array<Eigen::Matrix3d*, tet_batch_size> projection{};
  std::array<double*, tet_batch_size> energy{};
};

/// Which instruction set project_tet_batch() runs on.
enum class SimdPath { best, sse2, avx2 };

/// Whether this processor runs the AVX2 path.
bool avx2_available();

/// Projects the tets of `batch` (see TetBatch). `path` forces an instruction set (for tests;
/// avx2 falls back to sse2 where the processor lacks it).
void project_tet_batch(TetBatch& batch, const SingularValueRange& strain_range,
                       const SingularValueRange& volume_range, SimdPath path = SimdPath::best);

} // namespace phantasm
