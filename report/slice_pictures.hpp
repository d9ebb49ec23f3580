// Pictures of a subject's volumes for the HTML report: the three orthogonal middle slices side
// by side (as io's previews lay them out), in grey, as label contours, or in a colour scale with
// its colour bar; each returned as PNG bytes (io's encoder).
#pragma once

#include <Eigen/Core>

#include <array>

#include <cstdint>
#include <string>
#include <vector>

namespace phantasm {

/// Where each pixel of a picture of three middle slices comes from: panels axial (k = nz/2,
/// i across, j up), coronal (j = ny/2, i across, k up) and sagittal (i = nx/2, j across, k up),
/// left to right, bottom-aligned, so that right, anterior and superior point right or up.
class SliceMontage {
public:
  /// @param dims voxels along i, j, k (each at least 1)
  explicit SliceMontage(const Eigen::Vector3i& dims);
  int width() const { return m_width; }
  int height() const { return m_height; }
  /// The voxel index (i fastest) shown at pixel (x, y), y = 0 the bottom row; -1 where no panel is.
  std::int64_t voxel(int x, int y) const { return m_voxel[static_cast<std::size_t>(y) * m_width + x]; }
  /// The panel of pixel column x: 0 axial, 1 coronal, 2 sagittal.
  int panel(int x) const;

private:
  Eigen::Vector3i m_dims;
  int m_width = 0, m_height = 0;
  std::vector<std::int64_t> m_voxel;
};

/// Grey levels from the 0.5th to the 99.5th percentile of the slices' values (0 when lower).
/// @param values one per voxel, i fastest
std::string grey_slices_png(const SliceMontage& montage, const std::vector<double>& values);

/// The boundaries between labels, each label's boundary in a colour of its own, transparent
/// elsewhere (RGBA): a pixel is on a boundary when a neighbour in its panel has another label.
std::string contour_slices_png(const SliceMontage& montage, const std::vector<std::int32_t>& labels);

/// A colour scale of an overlay: what a value means, the colours, the range of the bar.
struct ColourScale {
  enum class Kind {
    magnitude, ///< 0 .. high, dark blue to yellow; transparent below 2 % of high
    jacobian,  ///< a ratio around 1 on a log scale from low (blue) to high (red); transparent
               ///< within 1 % of 1; 0 or below in magenta
  };
  Kind kind = Kind::magnitude;
  double low = 0.0, high = 1.0;
  /// RGBA of a value.
  std::array<unsigned char, 4> colour(double value) const;
};

/// The overlay of `values` in `scale` (RGBA, transparent where the scale says so).
std::string colour_slices_png(const SliceMontage& montage, const std::vector<double>& values,
                              const ColourScale& scale);

/// The colour bar of `scale`, `width` x 14 pixels, low on the left (opaque RGB).
std::string colour_bar_png(const ColourScale& scale, int width = 256);

} // namespace phantasm
