#include "core/format.hpp"

#include <sstream>

namespace phantasm {

std::string format_byte(unsigned char byte) {
  static const char* digits = "0123456789abcdef";
  return std::string("byte 0x") + digits[byte >> 4] + digits[byte & 15];
}

std::string format_number(double value) {
  std::ostringstream text;
  text << value;
  return text.str();
}

std::string format_vector(const Eigen::Vector3d& v) {
  return "(" + format_number(v.x()) + ", " + format_number(v.y()) + ", " + format_number(v.z()) + ")";
}

} // namespace phantasm
