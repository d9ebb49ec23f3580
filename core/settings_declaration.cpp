#include "core/settings_declaration.hpp"

#include <sstream>

namespace phantasm {

std::string exact_text(double value) {
  std::ostringstream out;
  out << std::hexfloat << value;
  return out.str();
}

unsigned keys_changed_by(unsigned keys) {
  // Each cached result's key holds the key of the one it is made from.
  if (keys & cached_anatomy) keys |= cached_reference_state;
  if (keys & cached_reference_state) keys |= cached_reference_images;
  return keys;
}

} // namespace phantasm
