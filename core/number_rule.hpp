// The values a numeric setting accepts: a range with open or closed ends and its unit. The scene's
// parser checks a value with it and its messages describe it; a setting's declaration
// (core/settings_declaration.hpp) holds it, and the bounds the settings' tables show are written
// from it, so that what is checked and what is shown cannot differ.
#pragma once

#include "core/format.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace phantasm {

/// The allowed range of a number, and its unit for messages.
struct NumberRule {
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_exclusive = false;
  bool max_exclusive = false;
  std::string unit = "";

  /// "a number in mm greater than 0", "a number in [0, 1]": what a message expects.
  std::string describe() const {
    std::string text = "a number";
    if (!unit.empty()) text += " in " + unit;
    const bool has_min = std::isfinite(min), has_max = std::isfinite(max);
    if (has_min && has_max) {
      text += std::string(" in ") + (min_exclusive ? "(" : "[") + format_number(min) + ", " +
              format_number(max) + (max_exclusive ? ")" : "]");
    } else if (has_min) {
      text += (min_exclusive ? " greater than " : " at least ") + format_number(min);
    } else if (has_max) {
      text += (max_exclusive ? " less than " : " at most ") + format_number(max);
    }
    return text;
  }

  /// "an integer in [1, 16]": what a message expects of an integer (both ends closed).
  std::string describe_integer() const {
    return "an integer in [" + std::to_string(static_cast<long long>(min)) + ", " +
           std::to_string(static_cast<long long>(max)) + "]";
  }

  bool accepts(double value) const {
    if (min_exclusive ? !(value > min) : !(value >= min)) return false;
    if (max_exclusive ? !(value < max) : !(value <= max)) return false;
    return true;
  }

  /// Whether any number is accepted.
  bool any() const { return !std::isfinite(min) && !std::isfinite(max); }

  /// The range as the settings' tables show it: "above 0", "0 to 1e5", "above 0 to 1000",
  /// "0 to below 0.5", "0 or above"; integers written out ("1 to 100000"); empty when any.
  std::string bounds_text(bool integer = false) const {
    const auto number = [integer](double v) {
      return integer ? std::to_string(static_cast<long long>(v)) : compact_number(v);
    };
    const bool low = std::isfinite(min), high = std::isfinite(max);
    const std::string from = (min_exclusive ? "above " : "") + number(min);
    const std::string to = (max_exclusive ? "below " : "") + number(max);
    if (low && high) return from + " to " + to;
    if (low) return min_exclusive ? from : from + " or above";
    if (high) return max_exclusive ? to : to + " or below";
    return "";
  }

  /// A number as a bound is written: "1e5" for 100000 and beyond, "1e-6", else as format_number.
  static std::string compact_number(double v) {
    if (v == std::floor(v) && std::abs(v) >= 1e5 && std::abs(v) < 1e300) {
      double mantissa = std::abs(v);
      int exponent = 0;
      while (std::fmod(mantissa, 10.0) == 0.0) {
        mantissa /= 10.0;
        ++exponent;
      }
      if (exponent >= 5) return (v < 0 ? "-" : "") + format_number(mantissa) + "e" + std::to_string(exponent);
    }
    std::string text = format_number(v); // "1e-06", "1e+12"
    const std::size_t e = text.find('e');
    if (e == std::string::npos) return text;
    std::string exponent = text.substr(e + 1);
    const bool negative = exponent[0] == '-';
    if (exponent[0] == '-' || exponent[0] == '+') exponent.erase(0, 1);
    exponent.erase(0, std::min(exponent.find_first_not_of('0'), exponent.size() - 1));
    return text.substr(0, e + 1) + (negative ? "-" : "") + exponent;
  }
};

/// Numbers greater than 0.
inline NumberRule positive(std::string unit) {
  NumberRule rule;
  rule.min = 0.0;
  rule.min_exclusive = true;
  rule.unit = std::move(unit);
  return rule;
}

/// Numbers of 0 and above.
inline NumberRule non_negative(std::string unit) {
  NumberRule rule;
  rule.min = 0.0;
  rule.unit = std::move(unit);
  return rule;
}

/// Numbers in [min, max].
inline NumberRule between(double min, double max, std::string unit) {
  NumberRule rule;
  rule.min = min;
  rule.max = max;
  rule.unit = std::move(unit);
  return rule;
}

} // namespace phantasm
