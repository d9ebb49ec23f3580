// Exact Euclidean distance transforms on image grids.
#pragma once

#include "core/grid.hpp"

#include <vector>

namespace phantasm {

/// Exact Euclidean distance (mm, the grid's spacing along each axis) from every voxel centre to
/// the nearest voxel centre where `feature` is set; infinity everywhere when none is. The grid's
/// axes are taken as orthogonal (every grid here: an orientation and a spacing). Separable
/// lower-envelope algorithm (Felzenszwalb and Huttenlocher 2012, Theory of Computing 8:415),
/// parallel over lines; the result does not depend on the thread count.
/// @param feature grid.voxel_count() flags, voxel_index order
/// Throws Cancelled when cancellation was requested (checked between the three passes).
std::vector<double> distance_to(const std::vector<bool>& feature, const ImageGrid& grid);

} // namespace phantasm
