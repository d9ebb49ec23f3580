#include "mri/gaussian_noise.hpp"

#include <cmath>

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
  const Table& t = table();
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

} // namespace phantasm
