// The OpenVDB adapter of voxelize: level sets from triangle meshes, and their sampling.

#include "voxelize/level_set.hpp"

#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/MeshToVolume.h>

#include <mutex>

namespace phantasm {

struct LevelSet::Impl {
  openvdb::FloatGrid::Ptr grid;
};

LevelSet::LevelSet(const TriangleMesh& surface, double voxel_size_mm, double half_width_voxels)
    : m(std::make_unique<Impl>()), m_voxel_size(voxel_size_mm), m_half_width(half_width_voxels) {
  static std::once_flag initialized;
  std::call_once(initialized, [] { openvdb::initialize(); });
  std::vector<openvdb::Vec3s> points(static_cast<std::size_t>(surface.vertex_count()));
  for (Eigen::Index v = 0; v < surface.vertex_count(); ++v) {
    points[static_cast<std::size_t>(v)] =
        openvdb::Vec3s(static_cast<float>(surface.vertices(v, 0)), static_cast<float>(surface.vertices(v, 1)),
                       static_cast<float>(surface.vertices(v, 2)));
  }
  std::vector<openvdb::Vec3I> triangles(static_cast<std::size_t>(surface.face_count()));
  for (Eigen::Index f = 0; f < surface.face_count(); ++f) {
    triangles[static_cast<std::size_t>(f)] =
        openvdb::Vec3I(static_cast<unsigned>(surface.faces(f, 0)), static_cast<unsigned>(surface.faces(f, 1)),
                       static_cast<unsigned>(surface.faces(f, 2)));
  }
  const openvdb::math::Transform::Ptr transform =
      openvdb::math::Transform::createLinearTransform(voxel_size_mm);
  m->grid = openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*transform, points, triangles,
                                                               static_cast<float>(half_width_voxels));
  m->grid->setGridClass(openvdb::GRID_LEVEL_SET);
}

LevelSet::~LevelSet() = default;
LevelSet::LevelSet(LevelSet&&) noexcept = default;
LevelSet& LevelSet::operator=(LevelSet&&) noexcept = default;

std::size_t LevelSet::active_voxel_count() const {
  return static_cast<std::size_t>(m->grid->activeVoxelCount());
}

const void* LevelSet::grid() const {
  return m->grid.get();
}

struct LevelSet::Probe::Impl {
  explicit Impl(const openvdb::FloatGrid& grid)
      : accessor(grid.getConstAccessor()), sampler(accessor, grid.transform()) {}
  openvdb::FloatGrid::ConstAccessor accessor;
  openvdb::tools::GridSampler<openvdb::FloatGrid::ConstAccessor, openvdb::tools::BoxSampler> sampler;
};

LevelSet::Probe::Probe(const LevelSet& level_set) : m(std::make_unique<Impl>(*level_set.m->grid)) {}
LevelSet::Probe::~Probe() = default;
LevelSet::Probe::Probe(Probe&&) noexcept = default;

double LevelSet::Probe::operator()(const Eigen::Vector3d& x) const {
  return static_cast<double>(m->sampler.wsSample(openvdb::Vec3d(x.x(), x.y(), x.z())));
}

} // namespace phantasm
