// Gravity: a uniform acceleration of the masses of the bodies it acts on (every moving organ, or
// those it names).
#include "core/format.hpp"
#include "sim/load_types/load_keys.hpp"

#include <algorithm>
#include <sstream>

namespace phantasm {

const LoadType& gravity_load_type() {
  static const LoadType type = [] {
    LoadParameter organs{"organs", LoadParameter::Kind::organs};
    organs.names = &LoadSettings::organs;
    LoadType t{
        LoadKind::gravity,
        "gravity",
        "a uniform acceleration of the bodies' masses: acceleration_m_s2, on the organs named (default: "
        "every organ that is not fixed)",
        {load_keys::vector3("acceleration_m_s2", &LoadSettings::acceleration_m_s2, 1e4, "m/s^2"), organs}};
    for (const LoadParameter& p : load_keys::motion())
      t.parameters.push_back(p);
    t.accelerates_masses = true;
    t.acts_on = [](const LoadSettings& load, const std::string& organ) {
      return load.organs.empty() ||
             std::find(load.organs.begin(), load.organs.end(), organ) != load.organs.end();
    };
    t.plan = [](const LoadSettings& load) {
      std::ostringstream line;
      line << "gravity " << format_vector(load.acceleration_m_s2) << " m/s^2";
      return line.str();
    };
    t.summary = [](const LoadSettings& load) {
      return "gravity (" + format_number(load.acceleration_m_s2.norm()) + " m/s^2)";
    };
    return t;
  }();
  return type;
}

} // namespace phantasm
