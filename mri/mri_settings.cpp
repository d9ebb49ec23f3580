#include "mri/mri_settings.hpp"

#include <algorithm>
#include <cmath>

namespace phantasm {

const char* to_string(Readout readout) {
  return readout == Readout::spin_echo ? "spin_echo" : "gradient_echo";
}

const char* to_string(ImageDatatype datatype) {
  switch (datatype) {
  case ImageDatatype::float32: return "float32";
  case ImageDatatype::int16: return "int16";
  case ImageDatatype::uint16: return "uint16";
  }
  return "?";
}

const char* to_string(TextureSource source) {
  switch (source) {
  case TextureSource::none: return "none";
  case TextureSource::scan: return "scan";
  case TextureSource::random: return "random";
  }
  return "?";
}

double automatic_receiver_gain(double reference_signal, double brightest_signal) {
  constexpr double k_brightest_at_most = 20.0; // times the level: int16 holds it with room to spare
  const double reference =
      std::max(std::abs(reference_signal), std::abs(brightest_signal) / k_brightest_at_most);
  if (!(reference > 0.0) || !std::isfinite(reference)) return 1.0;
  return k_receiver_reference_level / reference;
}

} // namespace phantasm
