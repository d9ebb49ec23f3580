// The cantilever under its own weight, the benchmark of volume locking (#16): a box held at
// one end, on a structured or a CGAL tet mesh, with the bulk term per tet, per vertex star or
// per group of tets; its tip deflection against beam theory.
#pragma once

#include "sim/elastic_model.hpp"
#include "sim/sim_settings.hpp"

#include <Eigen/Core>

namespace phantasm {

/// A box of size_mm (long axis z, from z = 0 to size_mm.z, cross-section centred on x = y =
/// size / 2), its z = 0 face held, gravity along -y as external forces (quasi-static).
struct CantileverSettings {
  Eigen::Vector3d size_mm{20, 20, 100};
  /// structured mesh: cells of 5 tets (tet_group: the cells are the groups)
  Eigen::Vector3i cells{4, 4, 20};
  /// > 0: an unstructured CGAL Mesh_3 tet mesh of the box at this tet size instead (seeded;
  /// tet_group: group_tets' clusters)
  double tet_size_mm = 0.0;
  int group_size = 0; ///< tets per group on the CGAL mesh (0: tets_per_group)
  double youngs_modulus_Pa = 2.5e5;
  double poisson_ratio = 0.45;
  double density_kg_m3 = 1000.0;
  double gravity_m_s2 = 9.81;
  VolumeFormulation volume = VolumeFormulation::tet;
};

/// The cantilever's model (positions in metres).
ElasticModel cantilever_model(const CantileverSettings& settings);

/// The mean downward (-y) displacement of the vertices of the free end's face (z within
/// 1e-3 mm of its largest value; a CGAL mesh's face vertices lie on the plane), mm.
double cantilever_tip_deflection_mm(const ElasticModel& model, const Eigen::MatrixX3d& positions_m);

/// Beam theory's tip deflection of the cantilever under its weight: Euler-Bernoulli q L^4 / (8
/// E I); with `timoshenko`, plus the shear term q L^2 / (2 kappa G A) with Cowper's kappa = 10
/// (1 + nu) / (12 + 11 nu) of a square section.
double cantilever_beam_theory_mm(const CantileverSettings& settings, bool timoshenko);

} // namespace phantasm
