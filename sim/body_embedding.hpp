// Bodies of the deformation stage: which organs form a body, where its vertices are in the model,
// and how organs nested in it are embedded in its tets and follow them. Internal to sim.
#pragma once

#include "anatomy/phantom.hpp"
#include "core/organ_table.hpp"
#include "core/stage_report.hpp"
#include "geometry/tet_location.hpp"
#include "sim/deform_phantom.hpp"
#include "sim/sim_plan.hpp"
#include "sim/sim_settings.hpp"

#include <Eigen/Core>

#include <array>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace phantasm::sim_detail {

inline constexpr double k_mm = 1e-3; ///< metres per millimetre (the scene is in mm, the model in m)

/// A point given by barycentric coordinates in one tet of the model.
struct Embedding {
  std::array<int, 4> vertices{};
  Eigen::Vector4d coefficients = Eigen::Vector4d::Zero();
};

/// Locates points in a body's rest tets: the tet where the smallest barycentric coordinate is
/// largest (TetMeshLocator::nearest: inside when it is >= 0; a point just outside the mesh
/// extrapolates from the nearest tet, which keeps the map smooth across the faceted boundary).
class TetLocator {
public:
  /// @param rest_mm tet vertices (mm); @param tets their tets, which must outlive the locator
  /// @param first_vertex the model vertex of the mesh's vertex 0
  TetLocator(const Eigen::MatrixX3d& rest_mm, const Eigen::MatrixX4i& tets, int first_vertex)
      : m_tets(tets), m_first(first_vertex), m_locator(rest_mm, tets) {}

  /// The embedding of x (mm) over model vertices.
  Embedding locate(const Eigen::Vector3d& x) const;

private:
  const Eigen::MatrixX4i& m_tets;
  int m_first = 0;
  TetMeshLocator m_locator;
};

/// The point an embedding gives at positions p (one row per model vertex).
Eigen::Vector3d interpolate(const Embedding& e, const Eigen::MatrixX3d& p);

/// A body of the model: the organ simulated, its vertices in the model.
struct Body {
  int organ = -1;
  int first_vertex = 0;
  Eigen::Index vertex_count = 0;
  std::unique_ptr<TetLocator> locator; ///< solids only
  /// solids: the tets solved, the organ's own mesh or, when organs are nested in it, the mesh of
  /// all of them (tissue interfaces as faces)
  std::shared_ptr<const TetMesh> mesh;
  /// solids: for each tet of `mesh`, the organ (index in the organ table) whose material it takes
  std::vector<int> tet_organ;
  bool shell = false; ///< a surface organ: its triangles carry the load
};

/// The triangles a surface organ is simulated with: its sheet, or its patch base mesh.
const TriangleMesh* shell_mesh(const Organ& organ);

/// How the organs relate to the bodies (all per organ, in the organ table's order; the nesting
/// is the table's).
struct BodyAssignment {
  std::vector<OrganMotion> motion;
  std::vector<int> body_of; ///< the organ whose body moves it, -1 when no body does
};

/// The body of each organ: its topmost simulated ancestor-or-self. A surface organ (no tet
/// mesh) is simulated as a shell of its triangles; organs nested in it have nothing to follow
/// (no interior) and stay in place, which goes into `report` as skipped.
BodyAssignment assign_bodies(const DeformationSettings& deformation, const OrganTable& organs,
                             const Phantom& phantom, StageReport& report);

/// The index in `bodies` of the body of `organ` (-1: none).
int body_index(const std::vector<Body>& bodies, int organ);

/// A point of organ i's rest surface (mm; its vertex `surface_vertex`) as an embedding in the
/// body that moves the organ.
Embedding embed(const Phantom& phantom, const BodyAssignment& assignment, const std::vector<Body>& bodies,
                std::size_t i, Eigen::Index surface_vertex, const Eigen::Vector3d& x_mm);

/// Every organ's vertices, and the solid bodies' tet meshes, at the solved positions `deformed_mm`
/// (one row per model vertex) into `result`.
void collect_deformations(const OrganTable& organs, const Phantom& phantom, const BodyAssignment& assignment,
                          const std::vector<Body>& bodies, const Eigen::MatrixX3d& deformed_mm,
                          PhantomDeformation& result);

} // namespace phantasm::sim_detail
