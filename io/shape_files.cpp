#include "io/shape_files.hpp"

#include "anatomy/shape_source.hpp"
#include "core/error.hpp"
#include "core/format.hpp"
#include "io/mesh_file.hpp"
#include "io/nifti_file.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <memory>
#include <set>
#include <sstream>

namespace phantasm {
namespace {

/// How far from the origin an imported shape may reach: 100 m, far beyond any body or scanner,
/// and the bound of the grid's centre (docs/scene-format.md). Coordinates beyond it (1e30 mm)
/// would make every later stage work on absurd extents instead of failing.
constexpr double k_max_coordinate_mm = 1e5;

/// Refuses a mesh with a non-finite coordinate or one beyond k_max_coordinate_mm.
void check_mesh_bounds(const std::filesystem::path& file, const TriangleMesh& mesh) {
  for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v) {
    for (int c = 0; c < 3; ++c) {
      const double x = mesh.vertices(v, c);
      if (!std::isfinite(x) || std::abs(x) > k_max_coordinate_mm) {
        throw InputError(file.string() + ": vertex " + std::to_string(v) +
                         ": expected coordinates within +-" + format_number(k_max_coordinate_mm) +
                         " mm, found " + format_number(x));
      }
    }
  }
}

/// Refuses a label volume whose affine is not finite or not invertible, or whose voxels reach
/// beyond k_max_coordinate_mm.
void check_volume_grid(const std::filesystem::path& file, const ImageGrid& grid) {
  const Eigen::Matrix4d& m = grid.world_from_voxel;
  if (!m.allFinite() || !std::isfinite(m.topLeftCorner<3, 3>().determinant()) ||
      m.topLeftCorner<3, 3>().determinant() == 0.0) {
    throw InputError(
        file.string() +
        ": expected a finite voxel-to-world affine (sform or qform) that can be inverted, found " +
        (m.allFinite() ? std::string("a singular one") : std::string("NaN or infinite entries")));
  }
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d ijk((corner & 1) ? grid.dims.x() : 0, (corner & 2) ? grid.dims.y() : 0,
                              (corner & 4) ? grid.dims.z() : 0);
    const Eigen::Vector3d world = grid.world_from_index(ijk);
    if (!world.allFinite() || world.cwiseAbs().maxCoeff() > k_max_coordinate_mm) {
      throw InputError(file.string() + ": expected voxels within +-" + format_number(k_max_coordinate_mm) +
                       " mm of the origin, found a corner of the volume at " +
                       format_number(world.cwiseAbs().maxCoeff()) + " mm");
    }
  }
}

/// A label volume as the organs share it, with each label's voxel box (from one pass).
struct LoadedVolume {
  ShapeData data;
  std::map<std::string, std::int32_t> names;
  std::map<std::int32_t, std::pair<Eigen::Vector3i, Eigen::Vector3i>> boxes; ///< label: first, last voxel
};

void measure_boxes(LoadedVolume& volume) {
  const ImageGrid& grid = *volume.data.label_grid;
  const std::vector<std::int32_t>& labels = *volume.data.labels;
  std::size_t n = 0;
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int i = 0; i < grid.dims.x(); ++i, ++n) {
        if (labels[n] == 0) continue;
        const Eigen::Vector3i at(i, j, k);
        const auto found = volume.boxes.find(labels[n]);
        if (found == volume.boxes.end()) {
          volume.boxes.emplace(labels[n], std::pair{at, at});
        } else {
          found->second.first = found->second.first.cwiseMin(at);
          found->second.second = found->second.second.cwiseMax(at);
        }
      }
}

std::string text(const Eigen::Vector3d& v) {
  return "[" + format_number(v.x()) + ", " + format_number(v.y()) + ", " + format_number(v.z()) + "]";
}

/// The world box (RAS mm) of a voxel box, voxels counted whole.
WorldBox world_box(const ImageGrid& grid, const Eigen::Vector3i& first, const Eigen::Vector3i& last) {
  WorldBox box{Eigen::Vector3d::Constant(1e300), Eigen::Vector3d::Constant(-1e300)};
  for (int corner = 0; corner < 8; ++corner) {
    Eigen::Vector3d at;
    for (int a = 0; a < 3; ++a)
      at[a] = ((corner >> a) & 1) ? last[a] + 0.5 : first[a] - 0.5;
    const Eigen::Vector3d p = grid.world_from_index(at);
    box.min_mm = box.min_mm.cwiseMin(p);
    box.max_mm = box.max_mm.cwiseMax(p);
  }
  return box;
}

/// The organ's labels as numbers: given numbers, or names looked up in the atlas's table.
std::vector<std::int32_t> resolve_labels(const ShapeSettings& shape, const LoadedVolume& volume,
                                         const std::string& organ) {
  std::vector<std::int32_t> out;
  for (const std::string& label : shape.labels) {
    if (!label.empty() && label.find_first_not_of("+-0123456789") == std::string::npos) {
      out.push_back(static_cast<std::int32_t>(std::stol(label)));
      continue;
    }
    const auto found = volume.names.find(label);
    if (found == volume.names.end()) {
      std::string known;
      for (const auto& [name, value] : volume.names)
        known += (known.empty() ? "" : ", ") + name;
      throw InputError(volume.data.source + ": expected a label of its table (" + known + ") for organ " +
                       organ + ", found '" + label + "'");
    }
    out.push_back(found->second);
  }
  if (out.empty()) out.push_back(shape.label);
  return out;
}

/// Whether `organ` lies inside `container` (directly or deeper).
bool nested_in(const std::map<std::string, std::string>& inside, std::string organ,
               const std::string& container) {
  for (std::size_t depth = 0; depth < inside.size(); ++depth) {
    const auto found = inside.find(organ);
    if (found == inside.end() || found->second.empty()) return false;
    if (found->second == container) return true;
    organ = found->second;
  }
  return false;
}

} // namespace

std::map<std::string, ShapeData> read_shape_files(const AnatomySettings& anatomy, const AtlasLoader& atlases,
                                                  const std::optional<ImageGrid>& scene_grid) {
  std::map<std::string, ShapeData> files;
  std::map<std::string, std::shared_ptr<LoadedVolume>> volumes; // by file path or "atlas:" name
  std::vector<std::string> volume_of(anatomy.organs.size());
  std::vector<std::vector<std::int32_t>> own(anatomy.organs.size());
  std::map<std::string, std::string> inside;
  for (const OrganSettings& organ : anatomy.organs)
    inside[organ.name] = organ.inside;

  const auto prefix = [](std::size_t i) { return "anatomy.organs[" + std::to_string(i) + "].shape."; };
  for (std::size_t i = 0; i < anatomy.organs.size(); ++i) {
    const OrganSettings& organ = anatomy.organs[i];
    const ShapeSettings& shape = organ.shape;
    const ShapeInput input = shape_source(shape.kind).input;
    if (input == ShapeInput::none) continue;
    const bool atlas = !shape.atlas.empty();
    std::string key = prefix(i) + (atlas ? "atlas" : "file");
    try {
      if (input == ShapeInput::triangle_mesh) {
        files[organ.name].mesh = read_triangle_mesh(shape.file);
        check_mesh_bounds(shape.file, *files[organ.name].mesh);
        continue;
      }
      volume_of[i] = atlas ? "atlas:" + shape.atlas : shape.file.string();
      auto& volume = volumes[volume_of[i]];
      if (!volume) {
        volume = std::make_shared<LoadedVolume>();
        ShapeData& data = volume->data;
        if (atlas) {
          if (!atlases) throw InputError("atlas " + shape.atlas + ": this run derives no atlases");
          AtlasLabelVolume derived = atlases(shape.atlas);
          data.label_grid = derived.grid;
          data.labels = derived.labels;
          data.source = derived.source;
          volume->names = std::move(derived.names);
        } else {
          data.label_grid.emplace();
          data.labels = std::make_shared<const std::vector<std::int32_t>>(
              read_nifti_labels(shape.file, &*data.label_grid));
          check_volume_grid(shape.file, *data.label_grid);
          data.source = shape.file.string();
        }
        measure_boxes(*volume);
      }
      key = prefix(i) + "label";
      own[i] = resolve_labels(shape, *volume, organ.name);
      for (const std::int32_t label : own[i]) {
        if (volume->boxes.count(label) == 0) {
          throw InputError(volume->data.source + ": expected voxels of label " + std::to_string(label) +
                           " (organ " + organ.name + "), found none");
        }
      }
    } catch (const InputError& error) {
      throw SettingError(key, error.what());
    }
  }

  // Each organ's target: its labels and those of the organs nested in it from the same volume.
  for (std::size_t i = 0; i < anatomy.organs.size(); ++i) {
    if (volume_of[i].empty()) continue;
    const OrganSettings& organ = anatomy.organs[i];
    const LoadedVolume& volume = *volumes.at(volume_of[i]);
    std::set<std::int32_t> target(own[i].begin(), own[i].end());
    for (std::size_t j = 0; j < anatomy.organs.size(); ++j) {
      if (j != i && volume_of[j] == volume_of[i] && nested_in(inside, anatomy.organs[j].name, organ.name))
        target.insert(own[j].begin(), own[j].end());
    }
    const ImageGrid& grid = *volume.data.label_grid;
    Eigen::Vector3i first = grid.dims, last = Eigen::Vector3i::Constant(-1);
    for (const std::int32_t label : target) {
      const auto& [low, high] = volume.boxes.at(label);
      // A label on the volume's outermost voxels has no outside there: its surface would be cut
      // open by the volume's edge.
      if ((low.array() == 0).any() || (high.array() == grid.dims.array() - 1).any()) {
        throw SettingError(prefix(i) + "label",
                           volume.data.source + ": label " + std::to_string(label) + " (organ " + organ.name +
                               ") touches the volume's edge (voxels " + text(low.cast<double>()) + " to " +
                               text(high.cast<double>()) + " of " + text(grid.dims.cast<double>()) +
                               "); its surface would be open there: expected a background margin");
      }
      first = first.cwiseMin(low);
      last = last.cwiseMax(high);
    }
    if (scene_grid) {
      const WorldBox labels = world_box(grid, first, last);
      const WorldBox scene =
          world_box(*scene_grid, Eigen::Vector3i::Zero(), scene_grid->dims - Eigen::Vector3i::Ones());
      if (!labels.intersects(scene)) {
        throw SettingError(
            prefix(i) + "label",
            volume.data.source + ": the voxels of organ " + organ.name + " (labels " + text(labels.min_mm) +
                " to " + text(labels.max_mm) + " mm) lie outside the scene grid (" + text(scene.min_mm) +
                " to " + text(scene.max_mm) + " mm): expected volumes in the same world space (RAS mm)");
      }
    }
    ShapeData& data = files[organ.name];
    data = volume.data;
    data.target_labels.assign(target.begin(), target.end());
  }
  return files;
}

} // namespace phantasm
