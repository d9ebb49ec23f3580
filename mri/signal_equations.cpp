#include "mri/signal_equations.hpp"

namespace phantasm {

double sequence_signal(const SequenceSettings& sequence, const Relaxation& tissue) {
  return sequence_type(sequence.kind).signal(sequence, tissue);
}

double bloch_signal(const SequenceSettings& sequence, const Relaxation& tissue) {
  return sequence_type(sequence.kind).bloch(sequence, tissue);
}

} // namespace phantasm
