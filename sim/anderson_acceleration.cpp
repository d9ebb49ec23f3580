// Anderson acceleration of the local/global iteration: the history of differences and the
// least-squares fit that proposes the accelerated point.
#include "sim/anderson_acceleration.hpp"

#include <Eigen/Cholesky>

#include <algorithm>

namespace phantasm::sim_detail {

AndersonAcceleration::AndersonAcceleration(Eigen::Index rows, int history)
    : m_rows(rows), m_history(history), m_dG(3 * rows, std::max(history, 1)),
      m_dF(3 * rows, std::max(history, 1)) {}

bool AndersonAcceleration::propose(const Eigen::MatrixX3d& g_matrix, const Eigen::MatrixX3d& x,
                                   Eigen::MatrixX3d& candidate) {
  if (m_history <= 0) return false;
  const Eigen::Index n = 3 * m_rows;
  const Eigen::Map<const Eigen::VectorXd> g(g_matrix.data(), n);
  const Eigen::Map<const Eigen::VectorXd> xv(x.data(), n);
  const Eigen::VectorXd f = g - xv;
  if (m_g_previous.size() == g.size()) {
    m_dG.col(m_next_column) = g - m_g_previous;
    m_dF.col(m_next_column) = f - m_f_previous;
    m_next_column = (m_next_column + 1) % m_history;
    m_stored = std::min(m_stored + 1, m_history);
  }
  m_g_previous = g;
  m_f_previous = f;
  if (m_stored == 0) return false;
  const Eigen::MatrixXd F = m_dF.leftCols(m_stored);
  Eigen::MatrixXd normal = F.transpose() * F;
  normal.diagonal().array() += 1e-10 * normal.diagonal().maxCoeff() + 1e-300;
  const Eigen::VectorXd theta = normal.ldlt().solve(F.transpose() * f);
  if (!theta.allFinite()) return false;
  candidate.resize(m_rows, 3);
  Eigen::Map<Eigen::VectorXd>(candidate.data(), n) = g - m_dG.leftCols(m_stored) * theta;
  return true;
}

void AndersonAcceleration::restart() {
  m_stored = 0;
  m_next_column = 0;
  m_g_previous.resize(0);
}

} // namespace phantasm::sim_detail
