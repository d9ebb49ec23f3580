// Short text forms of numbers and vectors (up to 6 significant digits) for log lines and
// error messages.
#pragma once

#include <Eigen/Core>

#include <string>

namespace phantasm {

/// "(x, y, z)" with up to 6 significant digits, for log lines and messages.
std::string format_vector(const Eigen::Vector3d& v);

/// A number with up to 6 significant digits ("0.0001", "1e+10", "3").
std::string format_number(double value);

/// A byte as messages name one that cannot stand in a text: "byte 0x1f".
std::string format_byte(unsigned char byte);

} // namespace phantasm
