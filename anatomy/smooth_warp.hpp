// Seeded variation of anatomy read from files: a smooth random warp of space applied to every
// label volume and mesh of a scene at once, so that a sweep yields many different brains from one
// labelled head and the organs stay nested (one diffeomorphism moves them all).
#pragma once

#include "anatomy/organ.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace phantasm {

/// A smooth displacement d(x) of space (RAS mm): a sum of random plane waves of wavelengths 60 to
/// 120 mm, faded to zero over `ramp_mm` inside the faces of a window box and zero outside it.
/// Its amplitude and gradient are bounded so that x -> x + d(x) is one-to-one (|grad d| < 1/2).
class SmoothWarp {
public:
  /// The identity (d = 0).
  SmoothWarp() = default;
  /// @param seed the scene's seed (the warp is a function of it alone for given bounds)
  /// @param amplitude_mm bound of |d|, mm (lowered when needed to keep |grad d| below 1/2)
  /// @param window_min, window_max the box outside which d vanishes, RAS mm
  SmoothWarp(std::uint64_t seed, double amplitude_mm, const Eigen::Vector3d& window_min,
             const Eigen::Vector3d& window_max);

  /// d(x), mm.
  Eigen::Vector3d displacement(const Eigen::Vector3d& x) const;
  /// The bound of |d| the warp keeps, mm (0 for the identity).
  double amplitude_mm() const { return m_amplitude; }
  bool identity() const { return m_waves.empty(); }

private:
  struct Wave {
    Eigen::Vector3d amplitude;  ///< mm
    Eigen::Vector3d wavevector; ///< rad / mm
    double phase = 0.0;
  };
  double window(const Eigen::Vector3d& x) const;

  std::vector<Wave> m_waves;
  Eigen::Vector3d m_min = Eigen::Vector3d::Zero(), m_max = Eigen::Vector3d::Zero();
  double m_ramp = 1.0;
  double m_amplitude = 0.0;
};

/// The warp of a scene's file and atlas shapes for seeded variation: amplitude `variation` x 50 mm
/// over the box of all their label volumes and meshes; the identity when variation is 0 or
/// there are none.
SmoothWarp draw_shape_warp(const std::map<std::string, ShapeData>& files, double variation,
                           std::uint64_t seed);

/// The shape data warped: label volumes resampled (nearest label at x + d(x), on the same grid),
/// mesh vertices moved by -d (the same deformation, to first order). Organs sharing a label
/// volume still share one (the warped copy).
std::map<std::string, ShapeData> warped_shapes(const std::map<std::string, ShapeData>& files,
                                               const SmoothWarp& warp);

} // namespace phantasm
