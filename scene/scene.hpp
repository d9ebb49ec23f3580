#pragma once

#include "core/grid.hpp"
#include "scene/diagnostic.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace phantasm {

/// The imaging grid of a scene (docs/scene-format.md, section grid).
struct GridSettings {
  Eigen::Vector3d field_of_view_mm{256, 256, 256}; ///< extent along i, j, k in mm
  Eigen::Vector3d voxel_size_mm{1, 1, 1};          ///< voxel size along i, j, k in mm
  Eigen::Vector3d center_mm{0, 0, 0};              ///< RAS mm position of the grid centre
  std::string orientation = "RAS";                 ///< axis code, see direction_from_axis_code()

  ImageGrid grid() const;
};

/// A named elastic material.
struct MaterialSettings {
  std::string name;
  double youngs_modulus_Pa = 3000.0;
  double poisson_ratio = 0.45;
  double density_kg_m3 = 1000.0;
};

/// A scene-supplied tissue value that replaces or completes the built-in table.
struct TissueOverride {
  std::string tissue;
  std::optional<double> T1_ms, T2_ms, T2star_ms, PD;
};

enum class ShapeKind { ellipsoid, superquadric, box, sheet, mesh, label_volume };

/// The target shape of an organ's surface.
struct ShapeSettings {
  ShapeKind kind = ShapeKind::ellipsoid;
  Eigen::Vector3d center_mm{0, 0, 0};    ///< ellipsoid / superquadric centre, RAS mm
  Eigen::Vector3d radii_mm{1, 1, 1};     ///< semi-axes before rotation, mm
  Eigen::Vector3d rotation_deg{0, 0, 0}; ///< rotations about x, then y, then z, degrees
  double exponent_1 = 1.0;               ///< superquadric north-south exponent (1 = ellipsoid)
  double exponent_2 = 1.0;               ///< superquadric east-west exponent (1 = ellipsoid)
  Eigen::Vector3d size_mm{10, 10, 10};   ///< box edge lengths; sheet: x and y extent (z unused)
  Eigen::Vector3i cells{1, 1, 1};        ///< box: hexahedral cells per axis (5 tets each); sheet: x, y
  std::filesystem::path file;            ///< mesh or label volume, resolved against the scene's folder
  int label = 0;                         ///< label value to extract from a label volume
};

/// One organ of the phantom.
struct OrganSettings {
  std::string name;
  std::string tissue;
  std::string material;        ///< a name from the scene's materials
  std::string inside;          ///< the organ that contains this one; empty for the outermost
  bool solid = true;           ///< true: tetrahedralized interior; false: surface (shell, sheet) only
  int base_mesh_triangles = 0; ///< this organ's patch base size; 0 = anatomy.base_mesh_triangles
  ShapeSettings shape;
  double thickness_mm = 1.0; ///< surface organs (solid: false) simulated as shells: wall thickness
  /// closed surface organs simulated as shells: their enclosed volume is kept within this
  /// fraction of rest (a fluid-filled organ); unset: free
  std::optional<double> enclosed_volume_tolerance;
};

struct AnatomySettings {
  double variation = 0.0;        ///< seeded relative variation of organ sizes, 0 = exact
  int base_mesh_triangles = 320; ///< patch base mesh size per organ (the anatomy accuracy knob)
  std::vector<OrganSettings> organs;
};

enum class DeformationMode { none, quasi_static, dynamic };
enum class SolverMethod { local_global, newton, gauss_seidel_pbd, jacobi_chebyshev, xpbd };

struct SolverSettings {
  SolverMethod method = SolverMethod::local_global;
  int max_iterations = 100;
  double relative_energy_tolerance = 1e-6; ///< stop when (E_k-1 - E_k) / E_k falls below this
  double position_tolerance_mm = 1e-4;     ///< stop when no vertex moves further in one iteration
  int threads = 0;                         ///< 0 = all cores
};

enum class LoadKind { gravity, displacement };
enum class MotionProfile { constant, ramp, sine };

/// An external load: gravity on organs, or a prescribed displacement of the part of an organ's
/// surface inside a sphere (a retractor, a probe, a compression paddle, a clamp that holds or
/// twists the end of a bar): each point x of the region goes to
/// c + R (x - c) + displacement_mm, R the turn by rotation_deg about rotation_axis through c =
/// rotation_center_mm (right-handed; 0 degrees: a pure translation).
struct LoadSettings {
  LoadKind kind = LoadKind::gravity;
  std::vector<std::string> organs; ///< gravity: organs it acts on (empty = all moving)
  Eigen::Vector3d acceleration_m_s2{0, 0, -9.81};
  std::string organ; ///< displacement: the organ pushed
  Eigen::Vector3d displacement_mm{0, 0, 0};
  Eigen::Vector3d region_center_mm{0, 0, 0};
  double region_radius_mm = 10.0;
  double rotation_deg = 0.0;                      ///< displacement: turn of the region's points
  Eigen::Vector3d rotation_axis{0, 0, 1};         ///< unit axis of the turn
  Eigen::Vector3d rotation_center_mm{0, 0, 0};    ///< a point of the axis
  MotionProfile motion = MotionProfile::constant; ///< how the load evolves in dynamic mode
  double period_s = 1.0;                          ///< ramp duration or sine period
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
};

struct VoxelizationSettings {
  int supersampling = 4;                  ///< samples per voxel edge for partial-volume fractions
  double tessellation_tolerance_mm = 0.2; ///< patch surface tessellation deviation
};

enum class SequenceKind { spin_echo, spoiled_gre, inversion_recovery, bssfp, mprage };
enum class Readout { gradient_echo, spin_echo };

/// One MR image to make, named by its BIDS suffix.
struct SequenceSettings {
  std::string name; ///< BIDS suffix, e.g. T1w, T2w, PDw, FLAIR, T2starw, UNIT1
  SequenceKind kind = SequenceKind::spin_echo;
  double TR_ms = 0.0;
  double TE_ms = 0.0;
  double flip_deg = 90.0;
  double TI_ms = 0.0;                       ///< inversion recovery and MPRAGE
  Readout readout = Readout::gradient_echo; ///< inversion recovery
  double echo_spacing_ms = 0.0;             ///< MPRAGE: gradient-echo spacing in the train
  int turbo_factor = 0;                     ///< MPRAGE: echoes per inversion
};

struct AcquisitionSettings {
  bool kspace = false;         ///< simulate k-space truncation (Gibbs ringing)
  int kspace_oversampling = 2; ///< object samples per acquired sample along each axis
  /// Acquired voxel size along i, j, k (replaces kspace_oversampling; anisotropic allowed).
  std::optional<Eigen::Vector3d> acquired_voxel_mm;
  double slice_thickness_mm = 0.0; ///< rectangular slice profile along k; 0 = none (3-D acquisition)
  double noise_percent = 0.0;      ///< 100 sigma / signal of the reference tissue (BrainWeb)
  std::string noise_reference_tissue = "white_matter";
  double bias_percent = 0.0; ///< peak-to-peak multiplicative bias field, percent
  int coils = 1;             ///< receive coils combined by sum of squares
};

struct OutputSettings {
  std::string subject = "01";
  bool images = true;
  bool labels = true;
  bool fractions = true;
  bool displacement_fields = true;
  bool jacobian = true;
  bool landmarks = true;
  bool meshes = true;
  bool vdb = false;
  bool previews = true;
  bool parameter_maps = true; ///< PD, T1, T2, T2* maps of each state
};

/// A parsed and validated scene file: typed settings for every stage.
struct Scene {
  std::filesystem::path file; ///< the scene file as given
  std::string sha256;         ///< hash of the file's bytes
  std::string source_text;    ///< the file's bytes, kept for the copy in the dataset
  std::string name;
  std::uint64_t seed = 0;
  double field_strength_T = 3.0;
  GridSettings grid;
  std::vector<MaterialSettings> materials;
  std::vector<TissueOverride> tissues;
  AnatomySettings anatomy;
  DeformationSettings deformation;
  VoxelizationSettings voxelization;
  std::vector<SequenceSettings> sequences;
  AcquisitionSettings acquisition;
  OutputSettings outputs;

  /// Where each key was found, by key path ("grid.voxel_size_mm"), for later messages.
  std::map<std::string, SourceLocation> locations;

  const MaterialSettings* find_material(const std::string& name) const;
  const OrganSettings* find_organ(const std::string& name) const;
  /// The location of a key path, or of the file when the path is unknown.
  SourceLocation location_of(const std::string& key_path) const;
};

/// The result of reading a scene: a scene when there was no problem, else every problem found.
struct SceneLoadResult {
  std::optional<Scene> scene;
  std::vector<Diagnostic> problems;
};

/// Reads, parses and validates a scene file (docs/scene-format.md). Never throws for bad input.
SceneLoadResult load_scene(const std::filesystem::path& file);

/// Parses scene text; `file` names it in messages and anchors relative paths.
SceneLoadResult parse_scene(const std::string& text, const std::filesystem::path& file);

const char* to_string(ShapeKind kind);
const char* to_string(DeformationMode mode);
const char* to_string(SolverMethod method);
const char* to_string(LoadKind kind);
const char* to_string(MotionProfile motion);
const char* to_string(ObstacleShape shape);
const char* to_string(SequenceKind kind);
const char* to_string(Readout readout);

} // namespace phantasm
