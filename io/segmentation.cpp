#include "io/segmentation.hpp"

#include "core/error.hpp"
#include "core/format.hpp"

namespace phantasm {
namespace {

constexpr const char* k_segmentation_prefix = "segmentation:";
constexpr const char* k_t1_separator = "|t1:";

std::string world_text(const Eigen::Vector3d& v) {
  return "[" + format_number(v.x()) + ", " + format_number(v.y()) + ", " + format_number(v.z()) + "]";
}

} // namespace

std::string segmentation_atlas_name(const std::filesystem::path& labels, const std::filesystem::path& t1) {
  return k_segmentation_prefix + labels.string() + k_t1_separator + t1.string();
}

bool is_segmentation_atlas(const std::string& atlas, std::filesystem::path* labels,
                           std::filesystem::path* t1) {
  if (atlas.rfind(k_segmentation_prefix, 0) != 0) return false;
  const std::size_t separator = atlas.find(k_t1_separator);
  if (separator == std::string::npos) return false;
  const std::size_t start = std::string(k_segmentation_prefix).size();
  if (labels) *labels = atlas.substr(start, separator - start);
  if (t1) *t1 = atlas.substr(separator + std::string(k_t1_separator).size());
  return true;
}

void check_t1_covers_labels(const std::filesystem::path& labels_file, const ImageGrid& label_grid,
                            const std::vector<std::int32_t>& labels, const std::filesystem::path& t1_file,
                            const ImageGrid& t1_grid) {
  Eigen::Vector3i first = label_grid.dims, last = Eigen::Vector3i::Constant(-1);
  std::size_t n = 0;
  for (int k = 0; k < label_grid.dims.z(); ++k)
    for (int j = 0; j < label_grid.dims.y(); ++j)
      for (int i = 0; i < label_grid.dims.x(); ++i, ++n)
        if (labels[n] != 0) {
          first = first.cwiseMin(Eigen::Vector3i(i, j, k));
          last = last.cwiseMax(Eigen::Vector3i(i, j, k));
        }
  if ((last.array() < 0).any()) return; // no labels: nothing to cover
  for (int corner = 0; corner < 8; ++corner) {
    Eigen::Vector3d ijk;
    for (int a = 0; a < 3; ++a)
      ijk[a] = ((corner >> a) & 1) ? last[a] : first[a];
    const Eigen::Vector3d world = label_grid.world_from_index(ijk);
    const Eigen::Vector3d at = t1_grid.index_from_world(world);
    for (int a = 0; a < 3; ++a) {
      if (at[a] >= -0.5 - 1e-6 && at[a] <= t1_grid.dims[a] - 0.5 + 1e-6) continue;
      throw InputError(t1_file.string() + ": expected a T1 whose grid covers the labelled voxels of " +
                       labels_file.string() + " (the same subject in the same world space), found a " +
                       "labelled voxel at " + world_text(world) + " mm outside the T1's grid (at its voxel " +
                       world_text(at) + ", the grid being " + world_text(t1_grid.dims.cast<double>()) +
                       " voxels)");
    }
  }
}

} // namespace phantasm
