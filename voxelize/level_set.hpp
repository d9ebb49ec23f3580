// LevelSet: a narrow-band signed distance grid (OpenVDB) of a closed surface, sampled by
// per-thread probes in the tissue voxelization and written to .vdb files.
#pragma once

#include "anatomy/patch_surface.hpp"
#include "geometry/triangle_mesh.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <memory>
#include <vector>

namespace phantasm {

/// A narrow-band signed distance level set of a closed surface (OpenVDB FloatGrid, world RAS mm,
/// axis-aligned voxels of one size), negative inside. Built from a patch surface directly, or
/// from a triangle mesh (e.g. a patch surface tessellated within a stated tolerance); deep inside
/// and outside it holds -/+ the band width.
class LevelSet {
public:
  /// From a triangle mesh (OpenVDB's mesh-to-volume: exact distances to the triangles).
  /// @param surface closed, outward-oriented mesh, RAS mm
  /// @param voxel_size_mm the level set's voxel edge
  /// @param half_width_voxels narrow band half width
  LevelSet(const TriangleMesh& surface, double voxel_size_mm, double half_width_voxels = 3.0);
  /// From a patch surface without tessellating it: the candidates are the voxels within the band
  /// plus each patch's own bump reach of its base triangle (a closed shell around the surface),
  /// and each finds its closest base triangle through a search tree (ties go to the lowest
  /// triangle index, as in a scan). Where
  /// that patch has bumps, the side comes from the height of the surface above the closest base
  /// point and the distance from the patch's closest point (Gauss-Newton over the triangle);
  /// elsewhere both from the base mesh (sign from pseudonormals; exact there, the bumps vanish on
  /// base edges). Parallel over voxels (OpenMP); the result does not depend on the thread count.
  /// @param surface closed patch surface at its current positions, RAS mm
  /// @param voxel_size_mm the level set's voxel edge
  /// @param half_width_voxels narrow band half width
  /// @param height_ranges the patches' height bounds (patch_height_ranges) when already known,
  ///        e.g. from the other state of the same organ; null: computed here
  LevelSet(const PatchSurface& surface, double voxel_size_mm, double half_width_voxels = 3.0,
           const std::vector<HeightRange>* height_ranges = nullptr);
  /// A level set stored before (io/vdb_file.hpp, decode_float_grids): the stored tree as it is,
  /// on the transform that the other constructors give voxel_size_mm; the same values, probes and
  /// blocks as the level set it was stored from.
  /// @param grid an openvdb::FloatGrid (opaque, so that callers need no OpenVDB), taken over
  LevelSet(std::shared_ptr<void> grid, double voxel_size_mm, double half_width_voxels);
  ~LevelSet();
  LevelSet(LevelSet&&) noexcept;
  LevelSet& operator=(LevelSet&&) noexcept;

  double voxel_size_mm() const { return m_voxel_size; }
  double half_width_mm() const { return m_half_width * m_voxel_size; }
  double half_width_voxels() const { return m_half_width; }
  /// Voxels of the narrow band (the sparse storage; memory follows the surface area).
  std::size_t active_voxel_count() const;
  /// World boxes (mm), one per 8^3 block of stored voxels, each grown by the reach of a
  /// trilinear sample and a margin: at any point outside all of them a probe reads constant
  /// tiles only and returns exactly the band width, negative inside the surface, positive
  /// outside. The blocks hold the whole band, so a region no box reaches lies on one side.
  std::vector<Eigen::AlignedBox3d> block_reach_mm() const;

  /// Trilinear samples with a cached tree accessor; one probe per thread.
  class Probe {
  public:
    explicit Probe(const LevelSet& level_set);
    ~Probe();
    Probe(Probe&&) noexcept;
    /// Signed distance at a world point, mm (negative inside), clamped to the band.
    double operator()(const Eigen::Vector3d& x) const;
    /// The values at the points (xs[a], ys[b], zs[c]) of an axis-aligned lattice of world
    /// points, into values[a + nx (b + ny c)]: each the same, bit for bit, as operator() at that
    /// point (as a float), but the stencils' shared corners read once and the interpolation
    /// taken axis by axis (z, then y, then x, as OpenVDB's BoxSampler), each partial result
    /// shared by the points that need it: a voxel's supersamples.
    void lattice(const double* xs, int nx, const double* ys, int ny, const double* zs, int nz,
                 float* values) const;
    /// Whether each point of the lattice lies inside (its value as lattice() gives it is
    /// negative), into inside[a + nx (b + ny c)]. When every corner of the stencils is
    /// positive, or every one negative and well away from zero, so is every value: then
    /// nothing is interpolated.
    void lattice_inside(const double* xs, int nx, const double* ys, int ny, const double* zs, int nz,
                        std::uint8_t* inside) const;

  private:
    struct Impl;
    std::unique_ptr<Impl> m;
  };

  /// The OpenVDB grid (openvdb::FloatGrid), for writing .vdb files; opaque here so that only
  /// voxelize and io include OpenVDB.
  const void* grid() const;

private:
  struct Impl;
  std::unique_ptr<Impl> m;
  double m_voxel_size = 1.0;
  double m_half_width = 3.0;
};

} // namespace phantasm
