// SingleThreadedBlas: BLAS on one thread while CHOLMOD's supernodal factorizations run (the
// Newton check's Hessian, the local/global solver's global matrix). Internal to sim.
#pragma once

#ifdef _OPENMP
#include <omp.h>
#endif

namespace phantasm {

/// OpenMP's thread count of the calling thread set to one while it lives: CHOLMOD's supernodal
/// factor calls BLAS, whose OpenMP build takes the thread count from there. On one thread the
/// factor is the same bits on any machine, and a busy second core (a test or a second subject
/// beside the solve) cannot stall it: the Colin head's 27 000-row Hessian factored in 2-3 s on
/// one thread and in 17 s on two with the other core loaded.
class SingleThreadedBlas {
public:
#ifdef _OPENMP
  SingleThreadedBlas() : threads_(omp_get_max_threads()) {
    omp_set_num_threads(1);
  }
  ~SingleThreadedBlas() {
    omp_set_num_threads(threads_);
  }

private:
  int threads_;
#endif
public:
  SingleThreadedBlas(const SingleThreadedBlas&) = delete;
  SingleThreadedBlas& operator=(const SingleThreadedBlas&) = delete;
};

} // namespace phantasm
