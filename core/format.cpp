#include "core/format.hpp"

#include <sstream>

namespace phantasm {

std::string format_number(double value) {
  std::ostringstream text;
  text << value;
  return text.str();
}

std::string format_vector(const Eigen::Vector3d& v) {
  return "(" + format_number(v.x()) + ", " + format_number(v.y()) + ", " + format_number(v.z()) + ")";
}

} // namespace phantasm
