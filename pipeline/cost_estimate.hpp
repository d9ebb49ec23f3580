// The cost of a run before the work (docs/architecture.md, "Cost estimate"): each organ's
// effective settings, what the stages will build (patches, tets, narrow-band and dense voxels),
// and the peak memory and time that takes on this machine, from the rates in
// pipeline/cost_rates.hpp. `phantasm info` prints it, `run` and `batch` refuse a scene whose
// peak memory exceeds what the machine has, and every run's log and provenance.json start with it.
#pragma once

#include "scene/scene.hpp"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace phantasm {

/// One organ's effective settings and what the anatomy stage builds of it.
struct OrganCost {
  std::string name;
  int base_mesh_triangles = 0; ///< the organ's own base size, or the scene's
  bool own_base = false;       ///< the organ sets base_mesh_triangles itself
  double tet_size_mm = 0.0;    ///< cell size bound of its tets (0: surface only)
  std::string tet_size_from;   ///< "anatomy.tet_size_mm" or "base size"
  /// how closely its surface is tessellated where a tessellation is made (exported meshes, or
  /// the level sets with voxelization.level_sets_from_tessellation), mm
  double tessellation_tolerance_mm = 0.0;
  double area_mm2 = 0.0;   ///< surface area of its shape (estimated for file and atlas shapes)
  double volume_mm3 = 0.0; ///< enclosed volume (0 for sheets)
  double patches = 0.0;    ///< fitted patches (base triangles), or sheet triangles
  double tets = 0.0;       ///< tets of its own mesh, and of the body mesh it heads (tet_size_mm)
};

/// What a run will build and need, before it runs.
struct CostEstimate {
  std::vector<OrganCost> organs;
  double patches = 0.0;
  double tets = 0.0;
  double dense_voxels = 0.0;          ///< voxels of the image grid
  double band_voxels = 0.0;           ///< narrow-band voxels of every organ's level set, all states
  double supersamples = 0.0;          ///< partial-volume samples near surfaces, all states
  int states = 1;                     ///< 2 when the scene deforms
  int images = 0;                     ///< MR images (sequences x states)
  double dense_bytes_per_voxel = 0.0; ///< what the volumes of the run hold per voxel at the peak
  double peak_memory_bytes = 0.0;     ///< peak resident memory of the process
  double cpu_seconds = 0.0;           ///< processor time, all threads
  double anatomy_seconds = 0.0, sim_seconds = 0.0, voxelize_seconds = 0.0, mri_seconds = 0.0,
         write_seconds = 0.0; ///< processor time per stage
  /// the setting that drives the peak memory, as a key path, and a sentence on how
  std::string memory_driver_key;
  std::string memory_driver;
  std::string memory_advice; ///< what would lower it ("a coarser grid.voxel_size_mm")
};

/// Estimates a scene's run from its settings alone (nothing is read or built).
/// @param scene a validated scene
CostEstimate estimate_cost(const Scene& scene);

/// Wall time of the run, s: the processor time spread over `threads` threads as the stages
/// parallelize (the anatomy's meshing is mostly serial).
double estimated_wall_seconds(const CostEstimate& estimate, int threads);

/// The estimate as log lines: one per organ (effective settings), then the totals. Deterministic
/// for a scene (no machine state), so the log of a run stays the same from run to run.
std::vector<std::string> cost_lines(const CostEstimate& estimate);

/// The estimate for provenance.json.
nlohmann::json cost_json(const CostEstimate& estimate);

/// Memory this process may still use, bytes: MemAvailable of /proc/meminfo, lowered to the
/// cgroup's limit less its usage when one is set (cgroup v2 memory.max, or v1); 0 when unknown.
double available_memory_bytes();

/// "4G", "512M", "2.5GB", "1073741824" -> bytes (K, M, G, T: powers of 1024).
/// @throws InputError for anything else
double parse_memory_size(const std::string& text);

/// "1.4 GB", "310 MB".
std::string format_bytes(double bytes);

/// Refuses a run whose peak memory exceeds `limit_bytes` (0: no check), naming the setting that
/// drives it. `what` starts the message ("scene head.yaml", "sub-003 x 2 jobs"), `copies` is how
/// many runs share the machine at once (batch --jobs).
/// @throws InputError "... estimated peak 31 GB > 22 GB available"
void check_memory(const CostEstimate& estimate, double limit_bytes, const std::string& limit_source,
                  const std::string& what, int copies = 1);

} // namespace phantasm
