// ElasticModel, the objective every solver minimizes: masses, tet, surface, volume and point
// constraints, obstacles and surface contacts; its building blocks, energy and gradient.
#pragma once

#include "sim/enclosed_volume.hpp"
#include "sim/obstacles.hpp"
#include "sim/surface_constraints.hpp"
#include "sim/surface_contacts.hpp"
#include "sim/tet_constraints.hpp"

#include <Eigen/Core>

#include <array>
#include <string>
#include <vector>

namespace phantasm {

/// A tet carrying a strain and a volume constraint. Positions are in metres inside the solver.
struct TetElement {
  std::array<int, 4> vertices{};
  /// F = X Q with X the 3x4 matrix of the tet's current vertex positions (columns).
  Eigen::Matrix<double, 4, 3> Q = Eigen::Matrix<double, 4, 3>::Zero();
  double rest_volume_m3 = 0.0;
  double strain_weight = 0.0; ///< 2 mu V (J per unit squared strain)
  double volume_weight = 0.0; ///< 3 lambda V
};

/// The bulk term of a group of tets on their volume-averaged deformation gradient (mean
/// dilatation): F_g = sum_t V_t F_t / V_g = X G with X the 3 x n matrix of the group's vertices
/// (columns) and G = sum_t V_t S_t Q_t / V_g (S_t placing tet t's corners among the group's
/// vertices), linear in the positions as a tet's F is. Energy w/2 |F_g - P_volume(F_g)|^2 with
/// w = 3 sum_t lambda_t V_t: for a uniform strain F_g = F_t, so it is exactly the sum of the
/// tets' volume terms; one constraint per group of about 5 tets does not lock as nu -> 1/2
/// (docs/deformation.md). A projective-dynamics constraint: w G G^T in the global matrix.
struct TetGroup {
  std::vector<int> tets;                      ///< the group's tets (indices into model.tets)
  std::vector<int> vertices;                  ///< distinct vertices of the group's tets
  Eigen::Matrix<double, Eigen::Dynamic, 3> G; ///< one row per vertex: F_g = X G
  double rest_volume_m3 = 0.0;                ///< V_g
  double weight = 0.0;                        ///< 3 sum_t lambda_t V_t
};

/// A point of the model (a vertex, or a barycentric combination of up to four vertices, e.g. a
/// point of an embedded organ) pulled to a target by a zero-rest-length spring:
/// energy stiffness / 2 |sum_k b_k x_k - target|^2.
struct PointConstraint {
  std::array<int, 4> vertices{};
  Eigen::Vector4d coefficients = Eigen::Vector4d::Zero();
  int count = 1;
  Eigen::Vector3d target_m = Eigen::Vector3d::Zero();
  double stiffness_N_m = 0.0;
};

/// An elastic solid: vertices with lumped masses, tet strain and volume constraints, point
/// constraints, vertices held in place (Dirichlet: the solvers never move them), and external
/// forces. The objective of one step (docs/method.md section 2.1) is
///   E(p) = a/2 (p - s)^T M (p - s) - f . p + sum_tets [ws/2 |F - P_strain(F)|^2 + wv/2 |F - P_volume(F)|^2]
///          + sum_surfaces w/2 |F - P(F)|^2 + sum_tet_groups w/2 |F_g - P_volume(F_g)|^2
///          + sum_volumes w/2 |X - P(X)|^2 + sum_points k/2 |b . x - t|^2
///          + sum_free vertices sum_obstacles kc/2 dist(x, allowed)^2
///          + sum_free vertices sum_surfaces it may not enter kc/2 dist(x, outside)^2
/// with a = 1/h^2 for a dynamic step (s the inertial target, gravity folded into s, f = 0) and
/// a = 0 for quasi-static equilibrium (f the external forces).
struct ElasticModel {
  Eigen::MatrixX3d rest_positions_m;
  Eigen::VectorXd masses_kg;
  std::vector<TetElement> tets;
  SingularValueRange strain_range;      ///< {1, 1}: as-rigid-as-possible
  SingularValueRange volume_range;      ///< {1, 1}: volume preserving
  std::vector<SurfaceElement> surfaces; ///< edge, triangle and bending constraints (sheets)
  std::vector<EnclosedVolume> volumes;  ///< volumes enclosed by closed shells (patch volume)
  std::vector<TetGroup> tet_groups;     ///< bulk terms of groups of tets (mean dilatation)
  std::vector<PointConstraint> points;
  std::vector<char> fixed;            ///< per vertex: held where the solver finds it
  Eigen::MatrixX3d external_forces_N; ///< per vertex; may be empty (no force)
  std::vector<Obstacle> obstacles;    ///< rigid obstacles the free vertices may not enter
  double contact_stiffness_N_m = 0.0; ///< kc of every vertex-obstacle and vertex-surface contact
  /// Closed surfaces of bodies, and the pairs of them that may not interpenetrate: a free vertex
  /// of one inside the other costs kc/2 |x - y|^2 with y = sum b_k x_k the closest point of the
  /// other's surface (docs/method.md section 3.8: projected onto the contact plane there), found anew at
  /// each step; the force acts on the vertex and, shared by b, on the triangle's vertices. The
  /// pairing is tested both ways.
  std::vector<ContactSurface> contact_surfaces;
  std::vector<std::array<int, 2>> contact_pairs;

  Eigen::Index vertex_count() const { return rest_positions_m.rows(); }
};

/// Lame parameters from Young's modulus and Poisson ratio.
struct LameParameters {
  double mu = 0.0;
  double lambda = 0.0;
};
LameParameters lame_parameters(double youngs_modulus_Pa, double poisson_ratio);

/// Appends a tet mesh (positions in metres, tets positively oriented) as a body of its own:
/// its vertices (free), its tets with the material's weights and lumped masses (a quarter of
/// each tet's mass per vertex). Weights [choice, docs/method.md section 3]: strain 2 mu V and volume
/// 3 lambda V. For small principal strains e_i the strain term is mu V |e|^2 and the volume
/// term (its distance to det = 1 is |tr e| / sqrt 3) lambda V (tr e)^2 / 2: together exactly
/// the linear-elastic energy, so E and nu mean what they mean in linear elasticity.
/// Returns the model index of the mesh's first vertex.
/// @throws std::invalid_argument for a tet with non-positive rest volume
int add_body(ElasticModel& model, const Eigen::MatrixX3d& rest_m, const Eigen::MatrixX4i& tets,
             const LameParameters& material, double density_kg_m3);

/// Appends an open triangle sheet (a membrane of thickness t, e.g. fabric or a thin organ wall)
/// as a body of its own: per triangle an as-rigid-as-possible strain constraint of weight
/// 2 mu t A and an area constraint of weight 2 lambda* t A (lambda* = 2 lambda mu / (lambda +
/// 2 mu), plane stress: together the linear membrane energy for small strains), per interior edge a bending
/// constraint of stiffness E t^3 / (12 (1 - nu^2)) toward its rest curvature, and lumped masses (a third of
/// each triangle's mass per vertex). Returns the model index of the sheet's first vertex.
/// @throws std::invalid_argument for a degenerate triangle
int add_sheet(ElasticModel& model, const Eigen::MatrixX3d& rest_m, const Eigen::MatrixX3i& faces,
              double youngs_modulus_Pa, double poisson_ratio, double density_kg_m3, double thickness_m);

/// The material of one tet.
struct TetMaterial {
  LameParameters lame;
  double density_kg_m3 = 1000.0;
};

/// As above, with a material per tet (e.g. from which organ holds the tet's centroid).
int add_body(ElasticModel& model, const Eigen::MatrixX3d& rest_m, const Eigen::MatrixX4i& tets,
             const std::vector<TetMaterial>& materials);

/// The inertial part of one step.
struct StepInertia {
  double weight = 0.0;       ///< 1/h^2, or 0 for quasi-static
  Eigen::MatrixX3d target_m; ///< s; unused when weight is 0
};

/// The deformation gradient F = X Q of a tet at positions p (one row per vertex).
Eigen::Matrix3d deformation_gradient(const TetElement& e, const Eigen::MatrixX3d& p);

/// The volume-averaged deformation gradient F_g = X G of a tet group at positions p.
Eigen::Matrix3d group_deformation_gradient(const TetGroup& g, const Eigen::MatrixX3d& p);

/// E(p) as above; p has one row per vertex, metres.
double model_energy(const ElasticModel& model, const StepInertia& inertia, const Eigen::MatrixX3d& p);

/// The gradient of E with respect to every vertex (rows of fixed vertices included).
Eigen::MatrixX3d model_gradient(const ElasticModel& model, const StepInertia& inertia,
                                const Eigen::MatrixX3d& p);

/// A free vertex inside a contact surface it may not enter, and the closest point there.
struct SurfaceContact {
  Eigen::Index vertex = 0;
  SurfaceQuery query;
};

/// The surface contacts of the model (model.contact_pairs) at positions p.
std::vector<SurfaceContact> surface_contacts(const ElasticModel& model, const Eigen::MatrixX3d& p);

/// Largest gradient row norm over the free vertices (the residual the solvers report), N.
double free_gradient_norm(const ElasticModel& model, const Eigen::MatrixX3d& gradient);

} // namespace phantasm
