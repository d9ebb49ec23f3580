// The settings the deformation stage reads (materials, solver, loads, obstacles, collisions),
// filled by the scene parser, and how each organ moves under them; Eigen, the organ table and
// the standard library only, so the scene needs no solver.
#pragma once

#include "core/grid.hpp"
#include "core/organ_table.hpp"

#include <Eigen/Core>

#include <cmath>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace phantasm {

/// A named elastic material.
struct MaterialSettings {
  std::string name;
  double youngs_modulus_Pa = 3000.0;
  double poisson_ratio = 0.45;
  double density_kg_m3 = 1000.0;
};

enum class DeformationMode { none, quasi_static, dynamic };
enum class SolverMethod { local_global, newton, gauss_seidel_pbd, jacobi_chebyshev, xpbd };

struct SolverSettings {
  SolverMethod method = SolverMethod::local_global;
  int max_iterations = 2000;
  double relative_energy_tolerance = 1e-6; ///< stop when (E_k-1 - E_k) / E_k falls below this
  double position_tolerance_mm = 1e-4;     ///< stop when no vertex moves further in one iteration
  /// converged (and stop) when the largest free gradient row is at most this fraction of the
  /// solve's force scale (docs/deformation.md, stopping test)
  double relative_residual_tolerance = 1e-3;
  int threads = 0; ///< 0 = all cores
};

/// Where the tets' bulk (lambda) energy lives (deformation.volume; docs/deformation.md).
enum class VolumeFormulation {
  tet,         ///< per tet: wv/2 |F - P_volume(F)|^2 with wv = 3 lambda V (locks as nu -> 1/2)
  vertex_star, ///< per vertex: the volume of the union of its tets, an EnclosedVolume with K = lambda / 4
  tet_group,   ///< per group of about 5 tets: one constraint on the group's volume-averaged F
  /// per group as tet_group, with a small share of the bulk weight left on each tet (tet_bulk_share)
  tet_group_and_tet
};

enum class LoadKind { gravity, displacement, growth };
enum class MotionProfile { constant, ramp, sine };

/// An external load: gravity on organs, or a prescribed displacement of the part of an organ's
/// surface inside a sphere (a retractor, a probe, a compression paddle, a clamp that holds or
/// twists the end of a bar): each point x of the region goes to
/// c + R (x - c) + displacement_mm, R the turn by rotation_deg about rotation_axis through c =
/// rotation_center_mm (right-handed; 0 degrees: a pure translation). Or the growth (atrophy when
/// negative) of an organ's tets, or of the tets whose centroid lies in atlas regions: a change of
/// their rest volume by the fraction volume_change.
struct LoadSettings {
  LoadKind kind = LoadKind::gravity;
  std::vector<std::string> organs; ///< gravity: organs it acts on (empty = all moving)
  Eigen::Vector3d acceleration_m_s2{0, 0, -9.81};
  std::string organ; ///< displacement: the organ pushed; growth: the organ that grows
  Eigen::Vector3d displacement_mm{0, 0, 0};
  Eigen::Vector3d region_center_mm{0, 0, 0};
  double region_radius_mm = 10.0;
  double rotation_deg = 0.0;                      ///< displacement: turn of the region's points
  Eigen::Vector3d rotation_axis{0, 0, 1};         ///< unit axis of the turn
  Eigen::Vector3d rotation_center_mm{0, 0, 0};    ///< a point of the axis
  MotionProfile motion = MotionProfile::constant; ///< how the load evolves in dynamic mode
  double period_s = 1.0;                          ///< ramp duration or sine period
  double volume_change = 0.0;       ///< growth: the rest volume's relative change, > -1 (-0.05: 5 % atrophy)
  std::vector<std::string> regions; ///< growth: atlas regions or groups of them (instead of an organ)
  std::string atlas;                ///< growth: the atlas the regions are of ("aal")
};

/// The regions of a label atlas that growth loads name, on its voxel grid (in world space, so a
/// tet's centroid finds its region without registration). Not a scene key: the pipeline reads
/// the atlas a growth load names and sets DeformationSettings::region_atlas.
struct RegionAtlas {
  std::string name;   ///< as scenes name it ("aal")
  std::string source; ///< the files it was read from, for messages
  ImageGrid grid;
  std::vector<std::int32_t> labels;                       ///< grid.voxel_count() labels, i fastest
  std::map<std::string, std::int32_t> regions;            ///< label by region name
  std::map<std::string, std::vector<std::string>> groups; ///< named sets of regions ("Hippocampus": both)

  /// The label of the voxel nearest to `world_mm`; 0 (background) outside the grid.
  std::int32_t label_at(const Eigen::Vector3d& world_mm) const {
    const Eigen::Vector3d index = grid.index_from_world(world_mm);
    Eigen::Vector3i v;
    for (int a = 0; a < 3; ++a) {
      const double r = std::round(index[a]);
      if (!(r >= 0.0 && r < grid.dims[a])) return 0;
      v[a] = static_cast<int>(r);
    }
    return labels[static_cast<std::size_t>(voxel_index(grid.dims, v.x(), v.y(), v.z()))];
  }
};

enum class ObstacleShape { half_space, sphere };

/// A rigid obstacle no simulated vertex may enter (a compression plate, a table, a probe tip),
/// moved by displacement_mm: in quasi-static mode over the load steps, in dynamic mode by its
/// motion profile.
struct ObstacleSettings {
  ObstacleShape shape = ObstacleShape::half_space;
  Eigen::Vector3d point_mm{0, 0, 0}; ///< half_space: a point of the plane; sphere: the centre
  Eigen::Vector3d normal{0, 0, 1};   ///< half_space: unit normal out of the obstacle
  double radius_mm = 10.0;           ///< sphere
  Eigen::Vector3d displacement_mm{0, 0, 0};
  MotionProfile motion = MotionProfile::constant;
  double period_s = 1.0;
};

/// Two simulated organs whose surfaces may not pass through each other.
struct CollisionSettings {
  std::vector<std::string> organs; ///< two organ names
};

/// What the deformation stage reads of one organ (written under anatomy.organs in the scene).
struct OrganMechanics {
  std::string material;      ///< a name from the materials
  bool solid = true;         ///< false: a surface organ, simulated as a shell
  double thickness_mm = 1.0; ///< shells: wall thickness
  /// closed shells: their enclosed volume is kept within this fraction of rest; unset: free
  std::optional<double> enclosed_volume_tolerance;
};

/// A homogeneous growth of the whole head (deformation.head_scale), applied after the solve:
/// every deformed position x goes to c + A (x - c), A = scale diag(axes) and c = center_mm (unset:
/// the centre of the box of the phantom's organs at rest). Stress-free, so for an isotropic A the
/// solve on the grown head is the grown solve (A F A^-1 = F): the subject's map is A after the
/// regional one, exact wherever that is (docs/batch.md, Population sweeps).
struct HeadScaleSettings {
  double scale = 1.0;                       ///< the linear scale of the whole head
  Eigen::Vector3d axes{1.0, 1.0, 1.0};      ///< shape: per-axis factors (x, y, z) on top of it
  std::optional<Eigen::Vector3d> center_mm; ///< the fixed point; unset: the head's centre

  /// The factors along x, y and z.
  Eigen::Vector3d factors() const { return scale * axes; }
  /// No change of size or shape: the deformation is the solve's alone.
  bool identity() const { return (factors().array() == 1.0).all(); }
};

struct DeformationSettings {
  DeformationMode mode = DeformationMode::none;
  SolverSettings solver;
  double time_step_s = 1.0 / 30.0;
  int frames = 1;
  std::vector<std::string> fixed; ///< organs held in place
  std::vector<LoadSettings> loads;
  std::vector<ObstacleSettings> obstacles;
  std::vector<CollisionSettings> collisions;
  int load_steps = 1; ///< quasi-static: loads and obstacles applied in this many equal increments
  /// where the solid bodies' bulk term lives (per_tet, tet_groups, tet_groups_and_tets,
  /// vertex_stars). Groups and tets by default: per tet locks as nu -> 1/2 (the cantilever's tip
  /// -15 % from 0.45 to 0.499), groups alone let single tets invert (the coarse Colin head: 2
  /// tets, det F -1.86); groups with a capped share per tet do neither (docs/deformation.md,
  /// Volume locking)
  VolumeFormulation volume = VolumeFormulation::tet_group_and_tet;
  HeadScaleSettings head_scale;            ///< a change of the whole head's size and shape after the solve
  std::vector<MaterialSettings> materials; ///< the scene's materials section
  /// Per organ in scene order, set by the scene from anatomy.organs.
  std::vector<OrganMechanics> organs;
  /// The atlas whose regions growth loads name, set by the pipeline (null: none named).
  std::shared_ptr<const RegionAtlas> region_atlas;

  const MaterialSettings* find_material(const std::string& name) const;
};

/// How the deformation stage treats each organ.
enum class OrganMotion {
  simulated, ///< a load acts on it: its vertices are solved for
  fixed,     ///< held in place by the scene (an attachment)
  rigid,     ///< nothing moves it: carried along rigidly, not simulated
};

/// The motion class of every organ of the table, in its order. With no deformation every organ
/// is rigid. A function of the settings alone, so that the scene can resolve what depends on
/// it (the gap tissue) without the solver.
std::vector<OrganMotion> classify_organ_motion(const DeformationSettings& deformation,
                                               const OrganTable& organs);

/// What a growth load grows, for messages: its organ, or its regions and their atlas
/// ("Hippocampus_L, Hippocampus_R (atlas aal)").
std::string growth_target(const LoadSettings& load);

const char* to_string(DeformationMode mode);
/// the solver's name in the scene (sim/solver_type.hpp)
const char* to_string(SolverMethod method);
/// the load type's name in the scene (sim/load_type.hpp)
const char* to_string(LoadKind kind);
/// the scene's words: per_tet, vertex_stars, tet_groups, tet_groups_and_tets
const char* to_string(VolumeFormulation volume);
const char* to_string(MotionProfile motion);
const char* to_string(ObstacleShape shape);

} // namespace phantasm
