// The L-BFGS pairs and the two-loop recursion of the local/global solver.
#include "sim/quasi_newton_history.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

namespace phantasm::sim_detail {

namespace {
double dot(const Eigen::MatrixX3d& a, const Eigen::MatrixX3d& b) {
  return a.cwiseProduct(b).sum();
}
} // namespace

QuasiNewtonHistory::QuasiNewtonHistory(int capacity)
    : m_capacity(std::max(0, capacity)), m_s(static_cast<std::size_t>(m_capacity)),
      m_y(static_cast<std::size_t>(m_capacity)), m_rho(static_cast<std::size_t>(m_capacity), 0.0),
      m_a(static_cast<std::size_t>(m_capacity), 0.0) {}

void QuasiNewtonHistory::add(const Eigen::MatrixX3d& x, const Eigen::MatrixX3d& gradient) {
  if (m_capacity > 0 && m_has_last) {
    m_s_new = x - m_x;
    m_y_new = gradient - m_gradient;
    const double sy = dot(m_s_new, m_y_new);
    // The curvature condition, with a margin for round-off (s and y nearly orthogonal).
    if (sy > 1e-12 * std::sqrt(dot(m_s_new, m_s_new) * dot(m_y_new, m_y_new))) {
      // Into the next free slot, or over the oldest pair once the buffer is full.
      const std::size_t at = slot(m_size < m_capacity ? m_size : 0);
      std::swap(m_s[at], m_s_new);
      std::swap(m_y[at], m_y_new);
      m_rho[at] = 1.0 / sy;
      if (m_size < m_capacity)
        ++m_size;
      else
        m_first = (m_first + 1) % m_capacity;
    }
  }
  m_x = x;
  m_gradient = gradient;
  m_has_last = true;
}

void QuasiNewtonHistory::first_loop(Eigen::MatrixX3d& q) {
  for (int i = m_size - 1; i >= 0; --i) {
    const std::size_t k = slot(i);
    m_a[k] = m_rho[k] * dot(m_s[k], q);
    q -= m_a[k] * m_y[k];
  }
}

void QuasiNewtonHistory::second_loop(Eigen::MatrixX3d& r) const {
  for (int i = 0; i < m_size; ++i) {
    const std::size_t k = slot(i);
    const double b = m_rho[k] * dot(m_y[k], r);
    r += (m_a[k] - b) * m_s[k];
  }
}

} // namespace phantasm::sim_detail
