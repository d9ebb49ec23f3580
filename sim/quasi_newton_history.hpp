// The pairs of an L-BFGS iteration and its two-loop recursion (the local/global solver's outer
// loop). Internal to the sim target.
#pragma once

#include <Eigen/Core>

#include <vector>

namespace phantasm::sim_detail {

/// The last `capacity` pairs (s, y) = (x_k+1 - x_k, grad_k+1 - grad_k) of an L-BFGS iteration
/// on points of n free vertices (n x 3), and the two loops of Nocedal's recursion around an
/// initial inverse Hessian H0 that the caller applies between them: first_loop(q), q <- H0 q,
/// second_loop(q) turns q = -grad into the quasi-Newton direction -H grad. A pair is kept only
/// when s . y > 0 (the curvature condition; else H would not be positive definite).
class QuasiNewtonHistory {
public:
  /// @param capacity pairs remembered (0: none, the direction is -H0 grad)
  explicit QuasiNewtonHistory(int capacity);

  /// Records the iterate x and its gradient: with the previous ones, a new pair.
  void add(const Eigen::MatrixX3d& x, const Eigen::MatrixX3d& gradient);
  /// Forgets the pairs (the last iterate stays: the next add() makes a pair with it).
  void clear() { m_size = 0; }
  /// Pairs remembered.
  int size() const { return m_size; }
  /// The newest pair's y and s . y (size() > 0): the scaling of H0.
  const Eigen::MatrixX3d& newest_y() const { return m_y[slot(m_size - 1)]; }
  double newest_sy() const { return 1.0 / m_rho[slot(m_size - 1)]; }

  /// q <- q - sum a_i y_i, newest pair first (a_i = rho_i s_i . q, kept for second_loop).
  void first_loop(Eigen::MatrixX3d& q);
  /// r <- r + sum (a_i - rho_i y_i . r) s_i, oldest pair first.
  void second_loop(Eigen::MatrixX3d& r) const;

private:
  /// The ring buffer's slot of the i-th oldest pair.
  std::size_t slot(int i) const { return static_cast<std::size_t>((m_first + i) % m_capacity); }

  int m_capacity = 0, m_size = 0, m_first = 0;
  std::vector<Eigen::MatrixX3d> m_s, m_y;
  std::vector<double> m_rho, m_a;
  Eigen::MatrixX3d m_x, m_gradient;  ///< the last iterate and its gradient
  Eigen::MatrixX3d m_s_new, m_y_new; ///< the pair being made
  bool m_has_last = false;
};

} // namespace phantasm::sim_detail
