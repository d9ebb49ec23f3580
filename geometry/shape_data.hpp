// ShapeData: the dense triangle mesh or label volume an organ's shape is made of, as read from a
// file or derived from an atlas (io/shape_files.hpp) before the anatomy stage builds the organ.
#pragma once

#include "core/grid.hpp"
#include "geometry/triangle_mesh.hpp"

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace phantasm {

/// A dense triangle mesh or a label volume (read from a file or derived from an atlas), for
/// organs whose shape is one. Organs of one volume share its labels.
struct ShapeData {
  std::optional<TriangleMesh> mesh;
  std::optional<ImageGrid> label_grid;
  std::shared_ptr<const std::vector<std::int32_t>> labels; ///< label_grid.voxel_count() values, i fastest
  /// The labels whose union is the organ's solid: its own and those of the organs nested in it
  /// (their surfaces lie inside its surface); empty: shape.label alone.
  std::vector<std::int32_t> target_labels;
  std::string source; ///< the file or the atlas, for messages
};

} // namespace phantasm
