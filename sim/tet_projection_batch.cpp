#include "sim/tet_projection_batch.hpp"

#include "sim/signed_svd.hpp"

#include <Eigen/Geometry>
#include <immintrin.h>

#include <algorithm>
#include <cmath>

namespace phantasm {
namespace {

/// turn_to_positive_pairs() on one lane's values, with the new rotation's quaternion (w, x, y, z)
/// written to q. Compiled for the baseline instruction set; the lanes kernels call it for the
/// rare lanes that need it.
void half_turns(double R[9], const double V[9], double lambda[3], double q[4]) {
  Eigen::Matrix3d rotation = Eigen::Map<const Eigen::Matrix3d>(R);
  Eigen::Vector3d values(lambda[0], lambda[1], lambda[2]);
  turn_to_positive_pairs(rotation, Eigen::Map<const Eigen::Matrix3d>(V), values);
  std::copy(rotation.data(), rotation.data() + 9, R);
  std::copy(values.data(), values.data() + 3, lambda);
  const Eigen::Quaterniond turned = Eigen::Quaterniond(rotation).normalized();
  q[0] = turned.w();
  q[1] = turned.x();
  q[2] = turned.y();
  q[3] = turned.z();
}

namespace sse2 {
constexpr int kLanes = 2;
using Lane = double __attribute__((vector_size(16)));
using Mask = long long __attribute__((vector_size(16)));
inline Lane lane_sqrt(Lane x) {
  return Lane(_mm_sqrt_pd(__m128d(x)));
}
inline bool lane_any(Mask m) {
  return _mm_movemask_pd(__m128d(m)) != 0;
}
#include "sim/tet_projection_lanes.inc"
} // namespace sse2

// The AVX2 lanes are compiled for AVX2 whatever the build's target; avx2_available() chooses
// them at run time. clang applies the target attribute to each function of the block instead.
#if defined(__clang__)
#pragma clang attribute push(__attribute__((target("avx2"))), apply_to = function)
#else
#pragma GCC push_options
#pragma GCC target("avx2")
#endif
namespace avx2 {
constexpr int kLanes = 4;
using Lane = double __attribute__((vector_size(32)));
using Mask = long long __attribute__((vector_size(32)));
inline Lane lane_sqrt(Lane x) {
  return Lane(_mm256_sqrt_pd(__m256d(x)));
}
inline bool lane_any(Mask m) {
  return _mm256_movemask_pd(__m256d(m)) != 0;
}
#include "sim/tet_projection_lanes.inc"
} // namespace avx2
#if defined(__clang__)
#pragma clang attribute pop
#else
#pragma GCC pop_options
#endif

} // namespace

bool avx2_available() {
  static const bool available = __builtin_cpu_supports("avx2");
  return available;
}

void project_tet_batch(TetBatch& batch, const SingularValueRange& strain_range,
                       const SingularValueRange& volume_range, SimdPath path) {
  if (batch.count <= 0) return;
  if (path != SimdPath::sse2 && avx2_available()) {
    avx2::project_batch(batch, 0, strain_range, volume_range);
    return;
  }
  for (int first = 0; first < batch.count; first += sse2::kLanes) {
    sse2::project_batch(batch, first, strain_range, volume_range);
  }
}

} // namespace phantasm
