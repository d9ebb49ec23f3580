#include "pipeline/cost_estimate.hpp"

#include "anatomy/shape_source.hpp"
#include "core/error.hpp"
#include "core/format.hpp"
#include "pipeline/cost_rates.hpp"
#include "sim/solver_type.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <functional>
#include <iomanip>
#include <numeric>
#include <sstream>

namespace phantasm {
namespace {

using namespace cost_rates;

/// Area and volume of an organ's shape as written (its source's). Shapes known only from their
/// file (meshes, label volumes, atlases) are guessed from the grid: the outermost fills the
/// inscribed ellipsoid of the field of view, each level of nesting a fraction of its container.
std::pair<double, double> shape_area_volume(const ShapeSettings& shape, const GridSettings& grid, int depth) {
  const ShapeSource& source = shape_source(shape.kind);
  if (source.area_volume != nullptr) return source.area_volume(shape);
  const Eigen::Vector3d radii = 0.5 * k_file_shape_extent * grid.field_of_view_mm *
                                std::pow(k_file_shape_nesting, static_cast<double>(depth));
  return {ellipsoid_area_mm2(radii), 4.0 / 3.0 * M_PI * radii.prod()};
}

/// Cell size bound of an organ's own tets for its base size (anatomy/tet_mesh.cpp,
/// criteria_for_boundary_size), mm.
double boundary_tet_size(double area_mm2, int base_triangles) {
  return 1.35 * std::sqrt(area_mm2 / (0.25 * std::sqrt(3.0) * std::max(1, base_triangles)));
}

/// How closely exported surfaces follow the patch surfaces (pipeline/dataset_writer.cpp,
/// mesh_export_tolerance_mm), mm.
double export_tolerance_mm(const Scene& scene) {
  return std::min(
      0.5, std::max(scene.voxelization.tessellation_tolerance_mm, 0.2 * scene.grid.voxel_size_mm.minCoeff()));
}

bool is_fixed(const Scene& scene, const std::string& organ) {
  const auto& fixed = scene.deformation.fixed;
  return std::find(fixed.begin(), fixed.end(), organ) != fixed.end();
}

std::string sci(double value) {
  std::ostringstream text;
  text.precision(2);
  if (value < 1e5)
    text << std::fixed << std::setprecision(0) << value;
  else
    text << value;
  return text.str();
}

std::string seconds_text(double seconds) {
  std::ostringstream text;
  text.precision(seconds < 10.0 ? 2 : 3);
  if (seconds < 120.0) {
    text << seconds << " s";
  } else if (seconds < 7200.0) {
    text << std::fixed << std::setprecision(1) << seconds / 60.0 << " min";
  } else {
    text << std::fixed << std::setprecision(1) << seconds / 3600.0 << " h";
  }
  return text.str();
}

/// What the organs add up to, beside each organ's own cost.
struct OrganTotals {
  int file_shapes = 0;          // organs whose shape is read from a file or an atlas
  std::string file_shape_organ; // the last of them
  double meshed_tets = 0.0, simulated_tets = 0.0, surface_area = 0.0, shell_triangles = 0.0;
  double fit_seconds = 0.0, fit_peak = 0.0; // processor time of the fits; the largest fit's memory
  std::size_t fit_peak_organ = 0;           // the organ whose fit peaks highest
  std::vector<double> fit_peaks;            // every fitted organ's
};

/// An organ's patches and its own tets (structured meshes of its source, as boxes and sheets,
/// or meshed from its base size), adding the meshed ones to `totals`.
void organ_mesh(const OrganSettings& settings, double area, double volume, OrganCost* organ,
                OrganTotals* totals) {
  const ShapeSource& source = shape_source(settings.shape.kind);
  if (source.structured != nullptr) {
    const StructuredCounts counts = source.structured(settings.shape, settings.solid);
    organ->patches = counts.patches;
    if (counts.tets > 0.0) {
      organ->tets = counts.tets;
      organ->tet_size_mm = counts.tet_size_mm;
      organ->tet_size_from = "shape.cells";
    }
  } else {
    organ->patches = organ->base_mesh_triangles;
    if (settings.solid) {
      organ->tet_size_mm = boundary_tet_size(area, organ->base_mesh_triangles);
      organ->tet_size_from = "base size";
      organ->tets = volume / (k_tet_volume_factor * std::pow(organ->tet_size_mm, 3.0));
      totals->meshed_tets += organ->tets;
    }
  }
}

/// A simulated body meshed as one (anatomy.tet_size_mm): the outermost solid organ that the scene
/// does not hold, with what it holds, gets a conforming mesh of that size as well.
void body_mesh(const Scene& scene, const OrganSettings& settings, double area, double volume, bool deformed,
               OrganCost* organ, OrganTotals* totals) {
  if (deformed && settings.solid && scene.anatomy.tet_size_mm > 0.0 && !is_fixed(scene, settings.name)) {
    const bool container_moves =
        !settings.inside.empty() && !is_fixed(scene, settings.inside) &&
        std::any_of(scene.anatomy.organs.begin(), scene.anatomy.organs.end(),
                    [&](const OrganSettings& o) { return o.name == settings.inside && o.solid; });
    if (!container_moves) {
      const double s = scene.anatomy.tet_size_mm;
      const double body = volume / (k_tet_volume_factor * s * s * s) + k_interface_tets * area / (s * s);
      organ->tets += body;
      totals->meshed_tets += body;
      organ->tet_size_mm = s;
      organ->tet_size_from = "anatomy.tet_size_mm";
    }
  }
}

/// The time and memory of fitting an organ's patches to its shape (none for structured meshes,
/// as boxes and sheets), into `totals`; `index` is the organ's place in the estimate.
void organ_fit(const OrganSettings& settings, const OrganCost& organ, std::size_t index,
               OrganTotals* totals) {
  if (shape_source(settings.shape.kind).structured != nullptr) return;
  // Fitting and measuring the fit take longer on coarse base meshes (their patches deviate
  // more from the target, so the measurement refines more) and on large ones (more patches).
  const double coarseness = 320.0 / std::max(1, organ.base_mesh_triangles);
  totals->fit_seconds += k_fit_seconds_at_320 * coarseness + k_seconds_per_patch * organ.patches;
  const double peak = k_fit_bytes_at_320 * coarseness + k_bytes_per_fitted_patch * organ.patches;
  totals->fit_peaks.push_back(peak);
  if (peak > totals->fit_peak) {
    totals->fit_peak = peak;
    totals->fit_peak_organ = index;
  }
}

/// Organ `i`'s cost, its share of the totals added to `totals`.
OrganCost organ_cost(const Scene& scene, std::size_t i, double tolerance, bool deformed, std::size_t index,
                     OrganTotals* totals) {
  const OrganSettings& settings = scene.anatomy.organs[i];
  const int depth = i < scene.organs.size() ? scene.organs[i].depth : 0;
  OrganCost organ;
  organ.name = settings.name;
  organ.own_base = settings.base_mesh_triangles > 0;
  organ.base_mesh_triangles =
      organ.own_base ? settings.base_mesh_triangles : scene.anatomy.base_mesh_triangles;
  organ.tessellation_tolerance_mm = tolerance;
  const auto [area, volume] = shape_area_volume(settings.shape, scene.grid, depth);
  organ.area_mm2 = area;
  organ.volume_mm3 = settings.solid ? volume : 0.0;
  if (shape_source(settings.shape.kind).input != ShapeInput::none) {
    ++totals->file_shapes;
    totals->file_shape_organ = settings.name;
  }
  organ_mesh(settings, area, volume, &organ, totals);
  body_mesh(scene, settings, area, volume, deformed, &organ, totals);
  if (deformed && !is_fixed(scene, settings.name)) {
    totals->simulated_tets += organ.tets;
    // A surface organ a load moves is solved as a shell (its triangles), unless it rides in a
    // solid organ that moves (then it follows that organ's tets).
    const bool embedded =
        std::any_of(scene.anatomy.organs.begin(), scene.anatomy.organs.end(), [&](const OrganSettings& o) {
          return o.name == settings.inside && o.solid && !is_fixed(scene, o.name);
        });
    if (!settings.solid && !embedded) totals->shell_triangles += organ.patches;
  }
  organ_fit(settings, organ, index, totals);
  totals->surface_area += area;
  return organ;
}

/// The memory of the meshes when they drive the peak: the largest fit, the body's tet size or
/// the largest organ's base size.
void mesh_memory_driver(const Scene& scene, const OrganTotals& totals, CostEstimate* estimate) {
  CostEstimate& e = *estimate;
  const auto largest =
      std::max_element(e.organs.begin(), e.organs.end(),
                       [](const OrganCost& a, const OrganCost& b) { return a.tets < b.tets; });
  if (totals.fit_peak >= e.tets * k_bytes_per_tet) {
    const OrganCost& organ = e.organs[totals.fit_peak_organ];
    e.memory_driver_key = organ.own_base ? "anatomy.organs." + organ.name + ".base_mesh_triangles"
                                         : "anatomy.base_mesh_triangles";
    e.memory_advice = "a base size nearer 320 in " + e.memory_driver_key +
                      " (a coarse base deviates more, and measuring its fit refines more)";
    e.memory_driver = e.memory_driver_key + " " + std::to_string(organ.base_mesh_triangles) +
                      ": fitting organ " + organ.name + " takes " + format_bytes(totals.fit_peak);
  } else if (largest->tet_size_from == "anatomy.tet_size_mm") {
    e.memory_driver_key = "anatomy.tet_size_mm";
    e.memory_advice = "a larger anatomy.tet_size_mm";
    e.memory_driver =
        "anatomy.tet_size_mm " + format_number(scene.anatomy.tet_size_mm) + " makes " + sci(e.tets) + " tets";
  } else {
    e.memory_driver_key = largest->own_base ? "anatomy.organs." + largest->name + ".base_mesh_triangles"
                                            : "anatomy.base_mesh_triangles";
    e.memory_advice = "a smaller " + e.memory_driver_key;
    e.memory_driver = e.memory_driver_key + " " + std::to_string(largest->base_mesh_triangles) + " makes " +
                      sci(largest->tets) + " tets of organ " + largest->name;
  }
}

/// The memory's parts, in bytes: the dense volumes, the meshes and fits, the level sets' bands and
/// the shapes from files.
struct MemoryParts {
  double dense = 0.0, meshes = 0.0, bands = 0.0, atlas = 0.0;
};

/// What drives the memory: the grid when its volumes are most of it, else the meshes.
void memory_driver(const Scene& scene, const OrganTotals& totals, const MemoryParts& m,
                   CostEstimate* estimate) {
  CostEstimate& e = *estimate;
  const double voxel_mm = scene.grid.voxel_size_mm.minCoeff();
  const double fov_mm3 = scene.grid.field_of_view_mm.prod();
  if (m.atlas >= m.dense && m.atlas >= m.meshes + m.bands) {
    e.memory_driver_key = "anatomy.organs." + totals.file_shape_organ + ".shape";
    e.memory_advice = "fewer organs from files, or a smaller grid.field_of_view_mm";
    e.memory_driver = std::to_string(totals.file_shapes) + " organs of shapes from files or atlases (" +
                      e.memory_driver_key + ") over a field of view of " + sci(fov_mm3 / 1000.0) + " ml";
  } else if (m.dense >= m.meshes + m.bands) {
    e.memory_driver_key = "grid.voxel_size_mm";
    e.memory_advice = "a coarser grid.voxel_size_mm";
    e.memory_driver = "grid.voxel_size_mm " + format_number(voxel_mm) + " makes " + sci(e.dense_voxels) +
                      " voxels of " + format_number(std::round(e.dense_bytes_per_voxel)) + " bytes";
  } else if (m.meshes >= m.bands) {
    mesh_memory_driver(scene, totals, estimate);
  } else {
    e.memory_driver_key = "grid.voxel_size_mm";
    e.memory_advice = "a coarser grid.voxel_size_mm";
    e.memory_driver = "grid.voxel_size_mm " + format_number(voxel_mm) + " makes " + sci(e.band_voxels) +
                      " narrow-band voxels";
  }
}

/// The number of distinct tissues of the scene's organs.
std::size_t tissue_count(const Scene& scene) {
  std::vector<std::string> names;
  for (const auto& o : scene.anatomy.organs)
    if (std::find(names.begin(), names.end(), o.tissue) == names.end()) names.push_back(o.tissue);
  return names.size();
}

/// Processor time per stage, into `e` (its volumes' sizes and counts already estimated).
void stage_seconds(const Scene& scene, const OrganTotals& totals, double crossed, double held, bool images,
                   double fov_mm3, CostEstimate* estimate) {
  CostEstimate& e = *estimate;
  const double voxel_mm = scene.grid.voxel_size_mm.minCoeff();
  const double voxel_area = voxel_mm * voxel_mm;
  const bool deformed = scene.deformation.mode != DeformationMode::none;
  const int coils = scene.mri.acquisition.coils;
  const bool kspace = scene.mri.acquisition.kspace;
  e.anatomy_seconds = totals.fit_seconds + totals.meshed_tets * k_seconds_per_tet +
                      totals.file_shapes * fov_mm3 * k_file_shape_seconds_per_mm3;
  const double steps =
      deformed ? std::max(1, scene.deformation.frames) * std::max(1, scene.deformation.load_steps) : 0.0;
  const bool contacts = !scene.deformation.collisions.empty() || !scene.deformation.obstacles.empty();
  e.sim_seconds =
      (totals.simulated_tets * k_seconds_per_tet_step +
       totals.shell_triangles * solver_type(scene.deformation.solver.method).seconds_per_shell_triangle_step +
       (contacts ? k_seconds_per_contact_step : 0.0)) *
      steps;
  e.voxelize_seconds = e.dense_voxels * e.states * k_seconds_per_dense_voxel +
                       e.band_voxels * k_seconds_per_band_voxel + e.supersamples * k_seconds_per_sample +
                       e.patches * e.states * k_seconds_per_level_set_patch_at_1mm / voxel_area +
                       (deformed ? crossed * k_seconds_per_moved_voxel : 0.0);
  e.mri_seconds = images ? e.dense_voxels * e.images *
                               (k_seconds_per_image_voxel + (kspace ? coils * k_seconds_per_coil_voxel : 0.0))
                         : 0.0;
  const double volumes_written = held / 4.0; // float volumes written, roughly
  e.write_seconds = e.dense_voxels * volumes_written * k_seconds_per_written_voxel +
                    e.patches * e.states * k_seconds_per_written_patch *
                        (k_written_patch_tolerance_mm / export_tolerance_mm(scene));
  e.cpu_seconds = k_base_seconds + e.anatomy_seconds + e.sim_seconds + e.voxelize_seconds + e.mri_seconds +
                  e.write_seconds;
}

} // namespace

CostEstimate estimate_cost(const Scene& scene) {
  CostEstimate e;
  const ImageGrid grid = scene.grid.grid();
  const double voxel_mm = scene.grid.voxel_size_mm.minCoeff();
  const double voxel_area = voxel_mm * voxel_mm;
  const bool deformed = scene.deformation.mode != DeformationMode::none;
  e.states = deformed ? 2 : 1;
  e.dense_voxels = static_cast<double>(grid.voxel_count());
  const double tolerance = scene.voxelization.level_sets_from_tessellation
                               ? scene.voxelization.tessellation_tolerance_mm
                               : export_tolerance_mm(scene);
  OrganTotals totals;
  for (std::size_t i = 0; i < scene.anatomy.organs.size(); ++i) {
    const OrganCost organ = organ_cost(scene, i, tolerance, deformed, e.organs.size(), &totals);
    e.patches += organ.patches;
    e.tets += organ.tets;
    e.organs.push_back(organ);
  }

  // Voxels: each organ's level set holds a band of k_band_width voxels across its surface per
  // state; partial volume takes supersampling^3 samples in the voxels a surface crosses.
  const double surface_area = totals.surface_area;
  const double crossed = std::min(e.dense_voxels, surface_area / voxel_area);
  e.band_voxels =
      std::min(e.dense_voxels * e.organs.size(), k_band_width * surface_area / voxel_area) * e.states;
  const int ss = scene.voxelization.supersampling;
  e.supersamples = k_crossed_voxels_per_area * crossed * ss * ss * ss * e.states;

  const std::size_t tissues = tissue_count(scene);
  const bool images = scene.mri.images && !scene.mri.sequences.empty();
  e.images = images ? static_cast<int>(scene.mri.sequences.size()) * e.states : 0;
  const int coils = scene.mri.acquisition.coils;

  // Memory: what the volumes of the run hold per voxel when the last image is made (labels,
  // background and a fraction per tissue per state, the fields, masks and Jacobians both ways,
  // every image and parameter map), and the largest transient on top of it.
  double held = e.states * (4.0 + 4.0 + 4.0 * static_cast<double>(tissues));
  if (deformed) held += 2 * 12.0 + 2 * 1.0 + 2 * 4.0;
  if (images) held += 4.0 * e.images;
  if (scene.outputs.parameter_maps) held += 16.0 * e.states;
  double transient = deformed ? k_field_transient_bytes : 0.0;
  if (images) transient = std::max(transient, k_image_transient_bytes + (coils > 1 ? 8.0 : 0.0));
  e.dense_bytes_per_voxel = held + transient;
  MemoryParts m;
  m.dense = e.dense_voxels * e.dense_bytes_per_voxel;
  // The anatomy fits its organs side by side, one per thread (anatomy/phantom.cpp): the largest
  // fits that can run at once add up, two of them on the 2 threads the estimate assumes (as its
  // wall time does; the estimate is part of the dataset, which is the same on any number of
  // threads).
  std::vector<double> fit_peaks = totals.fit_peaks;
  std::sort(fit_peaks.begin(), fit_peaks.end(), std::greater<double>());
  const auto concurrent_fits = std::min<std::size_t>(fit_peaks.size(), k_estimate_threads);
  const double fits_at_once = std::accumulate(fit_peaks.begin(), fit_peaks.begin() + concurrent_fits, 0.0);
  m.meshes = e.tets * k_bytes_per_tet + fits_at_once;
  m.bands = e.band_voxels * k_bytes_per_band_voxel;
  // A shape from a file is a distance field over its volume, sampled finely, kept for the run.
  const double fov_mm3 = scene.grid.field_of_view_mm.prod();
  m.atlas = totals.file_shapes * fov_mm3 * k_file_shape_bytes_per_mm3;
  e.peak_memory_bytes = k_base_bytes + m.dense + m.meshes + m.bands + m.atlas;

  stage_seconds(scene, totals, crossed, held, images, fov_mm3, &e);
  memory_driver(scene, totals, m, &e);
  return e;
}

double estimated_wall_seconds(const CostEstimate& e, int threads) {
  // The meshing and fitting run mostly on one thread; the voxel stages, the solver's local step
  // and the writer (files side by side) on all of them, at k_parallel_efficiency each.
  const double parallel = 1.0 + k_parallel_efficiency * (std::max(1, threads) - 1);
  return k_base_seconds + e.anatomy_seconds +
         (e.sim_seconds + e.voxelize_seconds + e.mri_seconds + e.write_seconds) / parallel;
}

std::vector<std::string> cost_lines(const CostEstimate& e) {
  std::vector<std::string> lines;
  for (const OrganCost& organ : e.organs) {
    std::ostringstream line;
    line << organ.name << ": base size " << organ.base_mesh_triangles
         << (organ.own_base ? " (its own)" : " (the scene's)");
    if (organ.tet_size_mm > 0.0)
      line << ", tets of " << format_number(std::round(organ.tet_size_mm * 10.0) / 10.0) << " mm (from "
           << organ.tet_size_from << ")";
    else
      line << ", no tets (surface only)";
    line << ", tessellation tolerance " << format_number(organ.tessellation_tolerance_mm) << " mm: about "
         << sci(organ.patches) << " patches, " << sci(organ.tets) << " tets";
    lines.push_back(line.str());
  }
  std::ostringstream total;
  total << sci(e.patches) << " patches, " << sci(e.tets) << " tets, " << sci(e.band_voxels)
        << " narrow-band voxels, " << sci(e.dense_voxels) << " dense voxels x " << e.states
        << (e.states == 1 ? " state" : " states") << ", " << e.images << " images";
  lines.push_back(total.str());
  std::ostringstream need;
  need << "peak memory " << format_bytes(e.peak_memory_bytes) << " (" << e.memory_driver
       << "), processor time " << seconds_text(e.cpu_seconds) << " (anatomy "
       << seconds_text(e.anatomy_seconds) << ", deformation " << seconds_text(e.sim_seconds)
       << ", voxelization " << seconds_text(e.voxelize_seconds) << ", images " << seconds_text(e.mri_seconds)
       << ", writing " << seconds_text(e.write_seconds) << "), wall time "
       << seconds_text(estimated_wall_seconds(e, k_estimate_threads)) << " on " << k_estimate_threads
       << " threads";
  lines.push_back(need.str());
  return lines;
}

nlohmann::json cost_json(const CostEstimate& e) {
  nlohmann::json organs = nlohmann::json::array();
  for (const OrganCost& o : e.organs) {
    organs.push_back({{"name", o.name},
                      {"base_mesh_triangles", o.base_mesh_triangles},
                      {"own_base_mesh_triangles", o.own_base},
                      {"tet_size_mm", o.tet_size_mm},
                      {"tet_size_from", o.tet_size_from},
                      {"tessellation_tolerance_mm", o.tessellation_tolerance_mm},
                      {"patches", std::round(o.patches)},
                      {"tets", std::round(o.tets)}});
  }
  return {{"organs", organs},
          {"patches", std::round(e.patches)},
          {"tets", std::round(e.tets)},
          {"narrow_band_voxels", std::round(e.band_voxels)},
          {"dense_voxels", std::round(e.dense_voxels)},
          {"states", e.states},
          {"images", e.images},
          {"peak_memory_bytes", std::round(e.peak_memory_bytes)},
          {"memory_driver", e.memory_driver_key},
          {"cpu_seconds", e.cpu_seconds},
          {"stage_cpu_seconds",
           {{"anatomy", e.anatomy_seconds},
            {"deformation", e.sim_seconds},
            {"voxelization", e.voxelize_seconds},
            {"mri", e.mri_seconds},
            {"writing", e.write_seconds}}},
          {"rates", k_rates_measured_by}};
}

double available_memory_bytes() {
  double available = 0.0;
  {
    std::ifstream meminfo("/proc/meminfo");
    std::string key;
    double kb = 0.0;
    std::string unit;
    while (meminfo >> key >> kb >> unit) {
      if (key == "MemAvailable:") {
        available = kb * 1024.0;
        break;
      }
    }
  }
  // A cgroup limit (a container, a Slurm job) below what the machine has is what counts.
  const auto read_number = [](const char* path) -> double {
    std::ifstream in(path);
    std::string text;
    if (!(in >> text) || text == "max") return 0.0;
    try {
      return std::stod(text);
    } catch (const std::exception&) {
      return 0.0;
    }
  };
  double limit = read_number("/sys/fs/cgroup/memory.max");
  double usage = read_number("/sys/fs/cgroup/memory.current");
  if (limit <= 0.0) {
    limit = read_number("/sys/fs/cgroup/memory/memory.limit_in_bytes");
    usage = read_number("/sys/fs/cgroup/memory/memory.usage_in_bytes");
    if (limit > 1e18) limit = 0.0; // v1's "unlimited"
  }
  if (limit > 0.0) {
    const double left = std::max(0.0, limit - usage);
    available = available > 0.0 ? std::min(available, left) : left;
  }
  return available;
}

double parse_memory_size(const std::string& text) {
  std::size_t used = 0;
  double value = 0.0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  std::string unit = text.substr(used);
  for (char& c : unit)
    c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  if (!unit.empty() && unit.back() == 'B') unit.pop_back();
  if (!unit.empty() && unit.back() == 'I') unit.pop_back(); // GiB
  double scale = 0.0;
  if (unit.empty()) scale = 1.0;
  if (unit == "K") scale = 1024.0;
  if (unit == "M") scale = 1024.0 * 1024.0;
  if (unit == "G") scale = 1024.0 * 1024.0 * 1024.0;
  if (unit == "T") scale = 1024.0 * 1024.0 * 1024.0 * 1024.0;
  if (used == 0 || scale == 0.0 || !(value > 0.0) || !std::isfinite(value))
    throw InputError("--max-memory: expected a size such as 4G, 512M or 2.5GB, found '" + text + "'");
  return value * scale;
}

std::string format_bytes(double bytes) {
  std::ostringstream text;
  text.precision(bytes >= 1e9 ? 3 : 2);
  if (bytes >= 1e12)
    text << bytes / 1e12 << " TB";
  else if (bytes >= 1e9)
    text << bytes / 1e9 << " GB";
  else
    text << std::fixed << std::setprecision(0) << bytes / 1e6 << " MB";
  return text.str();
}

void check_memory(const CostEstimate& estimate, double limit_bytes, const std::string& limit_source,
                  const std::string& what, int copies) {
  if (limit_bytes <= 0.0) return;
  const double need = estimate.peak_memory_bytes * std::max(1, copies);
  if (need <= limit_bytes) return;
  std::string message =
      what + ": " + estimate.memory_driver + ": estimated peak " + format_bytes(estimate.peak_memory_bytes);
  if (copies > 1) message += " x " + std::to_string(copies) + " jobs = " + format_bytes(need);
  message += " > " + format_bytes(limit_bytes) + " " + limit_source + "; expected " + estimate.memory_advice +
             (copies > 1 ? " or fewer --jobs" : "") +
             " (or a larger --max-memory if the estimate is wrong; docs/architecture.md, Cost estimate)";
  throw InputError(message);
}

} // namespace phantasm
