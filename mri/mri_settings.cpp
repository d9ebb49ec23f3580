#include "mri/mri_settings.hpp"

namespace phantasm {

const char* to_string(Readout readout) {
  return readout == Readout::spin_echo ? "spin_echo" : "gradient_echo";
}

} // namespace phantasm
