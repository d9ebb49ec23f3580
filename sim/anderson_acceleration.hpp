// Anderson acceleration of a fixed-point iteration x -> G(x) over a window of past iterations
// (the local/global solver's outer loop). Internal to the sim target.
#pragma once

#include <Eigen/Core>

namespace phantasm::sim_detail {

/// Anderson acceleration (type II) of x -> G(x) for points of n free vertices (n x 3, metres):
/// from the last `history` differences of G and of the residual f = G(x) - x it proposes
/// G(x) - dG theta, with theta the least-squares fit of f by dF (normal equations, slightly
/// regularized). The caller decides whether to keep the proposal (Peng et al. 2018 keep it only
/// when it lowers the energy) and restarts the history when it does not.
class AndersonAcceleration {
public:
  /// @param rows free vertices of the points
  /// @param history iterations remembered (0: off, propose() never proposes)
  AndersonAcceleration(Eigen::Index rows, int history);

  bool enabled() const { return m_history > 0; }

  /// Records g = G(x) at x and writes the accelerated point into `candidate` (rows x 3).
  /// Returns false, leaving `candidate` alone, when nothing is remembered yet or the fit fails.
  bool propose(const Eigen::MatrixX3d& g, const Eigen::MatrixX3d& x, Eigen::MatrixX3d& candidate);

  /// Forgets the history: the next propose() only records.
  void restart();

private:
  Eigen::Index m_rows = 0;
  int m_history = 0;
  Eigen::MatrixXd m_dG, m_dF; ///< 3 rows x history: columns of differences, a ring buffer
  Eigen::VectorXd m_g_previous, m_f_previous;
  int m_stored = 0, m_next_column = 0;
};

} // namespace phantasm::sim_detail
