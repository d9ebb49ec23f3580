#include "core/settings_declaration.hpp"

#include <cstdio>
#include <sstream>

namespace phantasm {

std::string exact_text(double value) {
  std::ostringstream out;
  out << std::hexfloat << value;
  return out.str();
}

std::string json_string(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (byte < 0x20) {
      char escaped[8];
      std::snprintf(escaped, sizeof escaped, "\\u%04x", byte);
      out += escaped;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

std::string json_number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", value);
  std::string out = text;
  if (out.find_first_of(".eEn") == std::string::npos) out += ".0";
  return out;
}

unsigned keys_changed_by(unsigned keys) {
  // Each cached result's key holds the key of the one it is made from.
  if (keys & cached_anatomy) keys |= cached_reference_state | cached_body_meshes;
  if (keys & cached_reference_state) keys |= cached_reference_images;
  return keys;
}

} // namespace phantasm
