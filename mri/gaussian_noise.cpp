#include "mri/gaussian_noise.hpp"

#include <cmath>
#include <cstring>

namespace phantasm {
namespace {

// The 128-layer ziggurat's start of the tail and the common area of its layers (Marsaglia and
// Tsang 2000, for f(x) = exp(-x^2 / 2)).
constexpr double k_r = 3.442619855899;
constexpr double k_v = 9.91256303526217e-3;

double f(double x) {
  return std::exp(-0.5 * x * x);
}

std::uint64_t splitmix64(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

/// A deviate's magnitude with the sign of its draw: negative ? -x : x for bit 7 of the draw's
/// bits, as a flip of the sign bit (what negation is), without a branch that no predictor learns.
double with_sign(double x, std::uint64_t bits) {
  std::uint64_t magnitude;
  std::memcpy(&magnitude, &x, sizeof x);
  magnitude ^= (bits >> 7) << 63; // bit 7 of the draw to the sign bit
  std::memcpy(&x, &magnitude, sizeof x);
  return x;
}

} // namespace

NormalStream::NormalStream(std::uint64_t seed) : m_table(&table()) {
  for (auto& s : m_s)
    s = splitmix64(seed);
}

const NormalStream::Table& NormalStream::table() {
  static const Table table = [] {
    Table t{};
    t.x[0] = k_v / f(k_r);
    t.x[1] = k_r;
    for (int i = 1; i < 127; ++i)
      t.x[i + 1] = std::sqrt(-2.0 * std::log(f(t.x[i]) + k_v / t.x[i]));
    t.x[128] = 0.0;
    for (int i = 0; i <= 128; ++i)
      t.f[i] = f(t.x[i]);
    t.f[0] = f(k_r); // the base layer's top edge: its rectangle reaches f(r)
    return t;
  }();
  return table;
}

double NormalStream::slow_path(int layer, double x) {
  const Table& t = *m_table;
  if (layer == 0) {
    // Beyond r: r + a with a exponential of rate r, accepted with probability exp(-a^2 / 2).
    for (;;) {
      const double a = -std::log(uniform_open()) / k_r;
      const double b = -std::log(uniform_open());
      if (b + b >= a * a) return k_r + a;
    }
  }
  // The wedge of an upper layer between f(x[layer]) and f(x[layer + 1]).
  const double y = t.f[layer] + uniform_open() * (t.f[layer + 1] - t.f[layer]);
  return y < f(x) ? x : -1.0;
}

void NormalStream::fill(double* out, std::size_t count) {
  const double* const width = m_table->x;    // x[layer]
  const double* const edge = m_table->x + 1; // x[layer + 1]
  std::uint64_t s0 = m_s[0], s1 = m_s[1], s2 = m_s[2], s3 = m_s[3];
  for (std::size_t n = 0; n < count;) {
    // next_bits() on the local state.
    const std::uint64_t bits = rotate(s0 + s3, 23) + s0;
    const std::uint64_t shifted = s1 << 17;
    s2 ^= s0;
    s3 ^= s1;
    s1 ^= s2;
    s0 ^= s3;
    s2 ^= shifted;
    s3 = rotate(s3, 45);
    // operator()'s draw from these bits.
    const std::size_t layer = bits & 127u;
    const double u = static_cast<double>(bits >> 11) * 0x1.0p-53; // [0, 1)
    const double x = u * width[layer];
    if (x < edge[layer]) {
      out[n++] = with_sign(x, bits);
      continue;
    }
    // Outside the layer's rectangle (one draw in 36): the slow path continues the stream.
    m_s[0] = s0, m_s[1] = s1, m_s[2] = s2, m_s[3] = s3;
    const double y = slow_path(static_cast<int>(layer), x);
    s0 = m_s[0], s1 = m_s[1], s2 = m_s[2], s3 = m_s[3];
    if (y >= 0.0) out[n++] = with_sign(y, bits);
  }
  m_s[0] = s0, m_s[1] = s1, m_s[2] = s2, m_s[3] = s3;
}

} // namespace phantasm
