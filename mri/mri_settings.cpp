#include "mri/mri_settings.hpp"

namespace phantasm {

const char* to_string(SequenceKind kind) {
  switch (kind) {
  case SequenceKind::spin_echo: return "spin_echo";
  case SequenceKind::spoiled_gre: return "spoiled_gre";
  case SequenceKind::inversion_recovery: return "inversion_recovery";
  case SequenceKind::bssfp: return "bssfp";
  case SequenceKind::mprage: return "mprage";
  }
  return "?";
}

const char* to_string(Readout readout) {
  return readout == Readout::spin_echo ? "spin_echo" : "gradient_echo";
}

} // namespace phantasm
