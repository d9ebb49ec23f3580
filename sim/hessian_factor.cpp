#include "sim/hessian_factor.hpp"

#include "sim/single_threaded_blas.hpp"

#include <Eigen/CholmodSupport>

#include <algorithm>
#include <vector>

namespace phantasm {

struct HessianFactor::Impl {
  Eigen::CholmodDecomposition<Eigen::SparseMatrix<double>, Eigen::Lower> cholmod;
  std::vector<int> outer, inner; // the analysed pattern

  bool same_pattern(const Eigen::SparseMatrix<double>& H) const {
    return H.isCompressed() && outer.size() == static_cast<std::size_t>(H.outerSize() + 1) &&
           inner.size() == static_cast<std::size_t>(H.nonZeros()) &&
           std::equal(outer.begin(), outer.end(), H.outerIndexPtr()) &&
           std::equal(inner.begin(), inner.end(), H.innerIndexPtr());
  }
};

HessianFactor::HessianFactor(Eigen::Index rows, Factorization kind)
    : m(std::make_unique<Impl>()),
      m_supernodal(kind == Factorization::supernodal ||
                   (kind == Factorization::automatic && rows >= k_supernodal_rows)) {
  m->cholmod.setMode(m_supernodal ? Eigen::CholmodSupernodalLLt : Eigen::CholmodSimplicialLLt);
}

HessianFactor::~HessianFactor() = default;

bool HessianFactor::factorize(const Eigen::SparseMatrix<double>& H, double shift) {
  const SingleThreadedBlas one_thread;
  if (!m->same_pattern(H)) {
    m->cholmod.analyzePattern(H);
    m->outer.assign(H.outerIndexPtr(), H.outerIndexPtr() + H.outerSize() + 1);
    m->inner.assign(H.innerIndexPtr(), H.innerIndexPtr() + H.nonZeros());
  }
  m->cholmod.setShift(shift);
  m->cholmod.factorize(H);
  return m->cholmod.info() == Eigen::Success;
}

Eigen::VectorXd HessianFactor::solve(const Eigen::VectorXd& b) const {
  const SingleThreadedBlas one_thread;
  return m->cholmod.solve(b);
}

} // namespace phantasm
