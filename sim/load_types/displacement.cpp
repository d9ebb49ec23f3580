// A prescribed displacement of the part of an organ's surface inside a sphere (a retractor, a
// probe, a paddle, a clamp holding or twisting a bar's end), with an optional turn about an axis.
#include "core/format.hpp"
#include "sim/load_types/load_keys.hpp"

#include <sstream>

namespace phantasm {

const LoadType& displacement_load_type() {
  static const LoadType type = [] {
    using namespace load_keys;
    LoadParameter displacement = vector3("displacement_mm", &LoadSettings::displacement_mm, 1e3, "mm");
    displacement.unless = "rotation"; // a turn alone (a clamp twisting a bar's end) needs no displacement
    LoadParameter axis = vector3("rotation.axis", &LoadSettings::rotation_axis, 1e6, "");
    axis.unit_vector = true;
    LoadParameter region{"region", LoadParameter::Kind::mapping};
    region.required = true;
    region.expected = "a mapping with center_mm and radius_mm (the part of the surface moved)";
    LoadType t{LoadKind::displacement,
               "displacement",
               "a prescribed displacement_mm, and a turn (rotation), of the part of an organ's surface "
               "inside a sphere (region)",
               {organ(), displacement, LoadParameter{"rotation", LoadParameter::Kind::mapping},
                number("rotation.angle_deg", &LoadSettings::rotation_deg, -360.0, 360.0, "degrees"),
                coordinate("rotation.center_mm", &LoadSettings::rotation_center_mm), axis, region,
                coordinate("region.center_mm", &LoadSettings::region_center_mm),
                positive("region.radius_mm", &LoadSettings::region_radius_mm, "mm")}};
    for (const LoadParameter& p : motion())
      t.parameters.push_back(p);
    t.acts_on = [](const LoadSettings& load, const std::string& organ) { return load.organ == organ; };
    t.plan = [](const LoadSettings& load) {
      std::ostringstream line;
      line << "displacement " << format_vector(load.displacement_mm) << " mm";
      if (load.rotation_deg != 0.0)
        line << " and turn of " << load.rotation_deg << " degrees about " << format_vector(load.rotation_axis)
             << " through " << format_vector(load.rotation_center_mm) << " mm";
      line << " of " << load.organ << " within " << load.region_radius_mm << " mm of "
           << format_vector(load.region_center_mm);
      return line.str();
    };
    t.summary = [](const LoadSettings& load) {
      return "the displacement of " + load.organ + " by " + format_number(load.displacement_mm.norm()) +
             " mm" +
             (load.rotation_deg != 0.0 ? " and a turn of " + format_number(load.rotation_deg) + " degrees"
                                       : std::string());
    };
    return t;
  }();
  return type;
}

} // namespace phantasm
