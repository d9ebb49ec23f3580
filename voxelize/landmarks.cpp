#include "voxelize/landmarks.hpp"

#include <cmath>
#include <cstdio>

namespace phantasm {

std::vector<Landmark> organ_landmarks(const Phantom& reference, const PhantomDeformation* deformation,
                                      const DeformationMap* map) {
  static const char* const k_directions[6] = {"left",     "right",    "posterior",
                                              "anterior", "inferior", "superior"};
  std::vector<Landmark> out;
  for (std::size_t o = 0; o < reference.organs.size(); ++o) {
    const Organ& organ = reference.organs[o];
    if (!organ.surface) continue;
    const Eigen::MatrixX3d& rest = organ.surface->rest_positions();
    const Eigen::MatrixX3d& moved = deformation ? deformation->organs[o].surface_mm : rest;
    Landmark centroid{organ.name + "_centroid", organ.name, rest.colwise().mean().transpose(),
                      Eigen::Vector3d::Zero()};
    // Organs the solver moved carry their centroid through the map; the others did not move.
    const bool moved_organ = deformation && (deformation->organs[o].moved_by == "solver" ||
                                             deformation->organs[o].moved_by.rfind("embedded", 0) == 0);
    centroid.deformed_mm = moved_organ && map ? map->forward(centroid.reference_mm) : centroid.reference_mm;
    out.push_back(centroid);
    for (int d = 0; d < 6; ++d) {
      // RAS: left is -x, posterior -y, inferior -z.
      const int axis = d / 2;
      const double sign = d % 2 == 0 ? -1.0 : 1.0;
      Eigen::Index best = 0;
      (sign * rest.col(axis)).maxCoeff(&best);
      out.push_back({organ.name + "_" + k_directions[d], organ.name, rest.row(best).transpose(),
                     moved.row(best).transpose()});
    }
  }
  return out;
}

std::string landmarks_csv(const std::vector<Landmark>& landmarks, bool deformed) {
  std::string text = "name,organ,x_mm,y_mm,z_mm\n";
  char line[256];
  for (const Landmark& l : landmarks) {
    // Rounded to the printed micrometre first, so a tiny negative value does not print as -0.000000.
    const Eigen::Vector3d x = ((deformed ? l.deformed_mm : l.reference_mm) * 1e6).array().round() / 1e6 + 0.0;
    std::snprintf(line, sizeof line, "%s,%s,%.6f,%.6f,%.6f\n", l.name.c_str(), l.organ.c_str(), x.x(), x.y(),
                  x.z());
    text += line;
  }
  return text;
}

} // namespace phantasm
