// The scene keys of the load types (sim/load_type.hpp) made in one call each: numbers and vectors
// with their bounds, and the keys more than one type declares (the organ it acts on, the motion
// of a dynamic scene). Internal to the load types.
#pragma once

#include "sim/load_type.hpp"

namespace phantasm::load_keys {

/// A number in [min, max] (`min_exclusive`: (min, max]).
inline LoadParameter number(const char* key, double LoadSettings::*member, double min, double max,
                            const char* unit, bool required = true, bool min_exclusive = false) {
  LoadParameter p{key, LoadParameter::Kind::number};
  p.number = member;
  p.min = min;
  p.max = max;
  p.min_exclusive = min_exclusive;
  p.unit = unit;
  p.required = required;
  return p;
}

/// A number above 0.
inline LoadParameter positive(const char* key, double LoadSettings::*member, const char* unit,
                              bool required = true) {
  return number(key, member, 0.0, std::numeric_limits<double>::infinity(), unit, required, true);
}

/// Three numbers, each within `bound` of 0.
inline LoadParameter vector3(const char* key, Eigen::Vector3d LoadSettings::*member, double bound,
                             const char* unit, bool required = true) {
  LoadParameter p{key, LoadParameter::Kind::vector3};
  p.vector = member;
  p.min = -bound;
  p.max = bound;
  p.unit = unit;
  p.required = required;
  return p;
}

/// A point in mm, each coordinate within 1e5 mm.
inline LoadParameter coordinate(const char* key, Eigen::Vector3d LoadSettings::*member) {
  return vector3(key, member, 1e5, "mm");
}

/// `organ`: the organ it acts on (an organ of the scene, not a fixed one).
inline LoadParameter organ() {
  LoadParameter p{"organ", LoadParameter::Kind::organ};
  p.text = &LoadSettings::organ;
  p.required = true;
  return p;
}

/// `motion` and `period_s`: how it evolves in a dynamic scene (constant, a ramp or a sine over
/// the period).
inline std::vector<LoadParameter> motion() {
  return {LoadParameter{"motion", LoadParameter::Kind::motion},
          positive("period_s", &LoadSettings::period_s, "s", false)};
}

} // namespace phantasm::load_keys
