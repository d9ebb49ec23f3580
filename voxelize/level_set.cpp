// The OpenVDB adapter of voxelize: level sets from patch surfaces and triangle meshes, and
// their sampling.

#include "voxelize/level_set.hpp"

#include "core/cancellation.hpp"
#include "geometry/mesh_signed_distance.hpp"

#include <omp.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/LevelSetUtil.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/Prune.h>
#include <openvdb/tools/SignedFloodFill.h>
#include <openvdb/util/NullInterrupter.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <mutex>

namespace phantasm {
namespace {

void initialize_openvdb() {
  static std::once_flag initialized;
  std::call_once(initialized, [] { openvdb::initialize(); });
}

/// Lets OpenVDB's tools (which poll their interrupter between leaf nodes) stop a cancelled run.
class CancellationInterrupter : public openvdb::util::NullInterrupter {
public:
  bool wasInterrupted(int /*percent*/ = -1) override { return cancellation_requested(); }
};

/// The bumps of one patch as heights over its base triangle: h(u, v) = sum a Q^3 [Q > 0] with
/// Q = 1 - d^T S d, d = (u, v) - c (docs/method.md section 1).
struct PatchHeights {
  std::vector<PatchBump> bumps;                 ///< with symmetric shapes
  Eigen::Vector3d origin, edge1, edge2, normal; ///< the frame: x = origin + u edge1 + v edge2 + h normal
  /// Bounds of the height over the triangle (patch_height_range): -below_mm <= h <= above_mm, so
  /// no point of the patch lies farther from its base than the larger of the two.
  double above_mm = 0.0, below_mm = 0.0;

  /// Which bumps may reach each part of the triangle (the surface's BumpLattice): the height
  /// sums those, the same terms in the same order as a sum over every bump.
  BumpLattice lattice;

  /// Height above base point (u, v), mm, its derivatives d/du, d/dv and, when `dd_uv` is
  /// given, its second derivatives (PatchBump::add_height, in bump order).
  double height(const Eigen::Vector2d& uv, Eigen::Vector2d* d_uv, Eigen::Matrix2d* dd_uv = nullptr) const {
    double h = 0.0;
    d_uv->setZero();
    if (dd_uv) dd_uv->setZero();
    for (const std::uint32_t n : lattice.at(uv.x(), uv.y()))
      bumps[n].add_height(uv, h, *d_uv, dd_uv);
    return h;
  }

  /// The height's second derivatives at (u, v): height()'s, the same terms in the same order.
  Eigen::Matrix2d height_hessian(const Eigen::Vector2d& uv) const {
    Eigen::Matrix2d dd_uv = Eigen::Matrix2d::Zero();
    for (const std::uint32_t n : lattice.at(uv.x(), uv.y()))
      bumps[n].add_hessian(uv, dd_uv);
    return dd_uv;
  }

  Eigen::Vector3d point(const Eigen::Vector2d& uv, double h) const {
    return origin + uv.x() * edge1 + uv.y() * edge2 + h * normal;
  }

  /// Distance from x to the patch, mm, from the base point (u, v) nearest x: two Gauss-Newton
  /// steps on f = |x - p(u, v)|^2 / 2 over the triangle, then Newton steps where f's Hessian is
  /// positive definite (Gauss-Newton elsewhere); each step is accepted only when it brings p
  /// nearer (halved up to five times, projected onto the triangle), so the result is at most the
  /// distance along the normal |x - p(u0, v0)|. With r = x - p and J = dp/d(u, v) =
  /// [e1 + h_u n, e2 + h_v n], the gradient is -J^T r and the Hessian J^T J - (r . n) h'' (the
  /// bumps curve p along n only). Gauss-Newton alone drops that term and converges slowly on
  /// narrow bumps (on the head most points took all 8 steps; now most take 3 to 5); Newton from
  /// the first step may head for a farther local minimum across a bump (the tests' many-bumps
  /// surface: 0.18 mm off), the Gauss-Newton steps first find the near one.
  /// @param h, d_uv the height and its derivatives at uv (height()): the caller has them
  double distance(const Eigen::Vector3d& x, Eigen::Vector2d uv, double h, Eigen::Vector2d d_uv) const {
    // The first two steps are Gauss-Newton, which needs no second derivatives. The later ones
    // need them at the point they start from (the last step's, since a step not taken ends the
    // search): summed there, not at every point a line search tries (many are not taken), nor
    // at the last point, where the search stops. The same sums, so the same bits.
    Eigen::Matrix2d dd_uv = Eigen::Matrix2d::Zero();
    Eigen::Vector3d r = x - point(uv, h);
    double best = r.squaredNorm();
    for (int iteration = 0; iteration < 8; ++iteration) {
      if (iteration >= 2) dd_uv = height_hessian(uv);
      Eigen::Matrix<double, 3, 2> J;
      J.col(0) = edge1 + d_uv.x() * normal;
      J.col(1) = edge2 + d_uv.y() * normal;
      const Eigen::Matrix2d JtJ = J.transpose() * J;
      const Eigen::Vector2d g = J.transpose() * r;
      const Eigen::Matrix2d H = JtJ - r.dot(normal) * dd_uv;
      const bool convex = iteration >= 2 && H(0, 0) > 0.0 && H.determinant() > 1e-12 * H(0, 0) * H(1, 1);
      const Eigen::Vector2d step = convex ? solve_2x2(H, g) : solve_2x2(JtJ, g);
      bool accepted = false, full_step = false;
      for (double scale = 1.0; scale > 1.0 / 64.0 && !accepted; scale *= 0.5) {
        Eigen::Vector2d next = uv + scale * step;
        next = next.cwiseMax(0.0);
        if (next.sum() > 1.0) next /= next.sum();
        Eigen::Vector2d next_d_uv;
        const double next_h = height(next, &next_d_uv);
        const Eigen::Vector3d next_r = x - point(next, next_h);
        if (next_r.squaredNorm() < best) {
          accepted = true;
          full_step = scale == 1.0;
          best = next_r.squaredNorm();
          uv = next;
          d_uv = next_d_uv;
          r = next_r;
        }
      }
      if (!accepted || step.squaredNorm() < 1e-16) break;
      // Newton converges quadratically: after a whole Newton step of under 1e-4 mm the next one
      // would move p by about 1e-8 mm, and the distance (stationary there) by far less.
      if (convex && full_step && (J * step).squaredNorm() < 1e-8) break;
    }
    return std::sqrt(best);
  }

  /// A^-1 b for a symmetric 2 x 2 matrix (Cramer's rule); zero when A is singular.
  static Eigen::Vector2d solve_2x2(const Eigen::Matrix2d& A, const Eigen::Vector2d& b) {
    const double det = A(0, 0) * A(1, 1) - A(0, 1) * A(1, 0);
    if (!(std::abs(det) > 0.0)) return Eigen::Vector2d::Zero();
    return Eigen::Vector2d(A(1, 1) * b.x() - A(0, 1) * b.y(), A(0, 0) * b.y() - A(1, 0) * b.x()) / det;
  }
};

/// Each base triangle's patch: its bumps (shape matrices symmetrized), height bounds and frame.
std::vector<PatchHeights> patch_heights(const PatchSurface& surface,
                                        const std::vector<HeightRange>* height_ranges) {
  const auto nf = static_cast<std::size_t>(surface.base_mesh().face_count());
  std::vector<PatchHeights> patches(nf);
  for (std::size_t t = 0; t < nf; ++t) {
    PatchHeights& p = patches[t];
    p.bumps = surface.bumps(static_cast<Eigen::Index>(t));
    for (PatchBump& b : p.bumps)
      b.shape_uv = 0.5 * (b.shape_uv + b.shape_uv.transpose()).eval();
    const HeightRange range = height_ranges ? (*height_ranges)[t] : patch_height_range(p.bumps);
    p.above_mm = std::max(0.0, range.highest);
    p.below_mm = std::max(0.0, -range.lowest);
    if (!p.bumps.empty()) {
      p.lattice = surface.bump_lattice(static_cast<Eigen::Index>(t));
      const PatchFrame f = surface.frame(static_cast<Eigen::Index>(t));
      p.origin = f.origin;
      p.edge1 = f.edge1;
      p.edge2 = f.edge2;
      p.normal = f.normal;
    }
  }
  return patches;
}

/// Marks the candidate voxels of base triangle t: those within `reach` of it and in the slab
/// -below <= n . (x - v0) <= above.
void mark_triangle_candidates(const SignedDistanceMesh& mesh, int t, double above, double below,
                              double voxel_size_mm, openvdb::MaskGrid::Accessor& accessor) {
  const auto& v = mesh.corners(t);
  const Eigen::Vector3d& n = mesh.face_normal(t);
  const double reach = std::max(above, below);
  const Eigen::Vector3d low = v[0].cwiseMin(v[1]).cwiseMin(v[2]).array() - reach;
  const Eigen::Vector3d high = v[0].cwiseMax(v[1]).cwiseMax(v[2]).array() + reach;
  int lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = static_cast<int>(std::ceil(low[a] / voxel_size_mm));
    hi[a] = static_cast<int>(std::floor(high[a] / voxel_size_mm));
  }
  // A degenerate face (zero normal) keeps its whole box.
  const bool flat = n.squaredNorm() > 0.5;
  // The box is walked in lines along the axis where the normal is largest (at least 1/sqrt(3)
  // of it), which the slab cuts to a short interval. Lines along a fixed axis once met faces
  // nearly parallel to it: a flat cap whose normal's x was 1e-10 put the interval's ends beyond
  // any int, their conversion (undefined) gave INT_MIN on x86, no voxel of the face was marked,
  // and the flood fill leaked through the hole in the shell.
  int along = 0;
  if (flat) n.cwiseAbs().maxCoeff(&along);
  const int second = (along + 1) % 3, third = (along + 2) % 3;
  openvdb::Coord ijk;
  for (int c = lo[third]; c <= hi[third]; ++c) {
    for (int b = lo[second]; b <= hi[second]; ++b) {
      Eigen::Vector3d line = Eigen::Vector3d::Zero();
      line[second] = voxel_size_mm * b;
      line[third] = voxel_size_mm * c;
      // The voxels of this line within the slab -below <= n . (x - v0) <= above: an interval.
      int first = lo[along], last = hi[along];
      if (flat) {
        const double offset = n.dot(line - v[0]);
        const double from = (-below - offset) / (n[along] * voxel_size_mm);
        const double to = (above - offset) / (n[along] * voxel_size_mm);
        first = std::max(first, static_cast<int>(std::floor(std::min(from, to))));
        last = std::min(last, static_cast<int>(std::ceil(std::max(from, to))));
      }
      ijk[second] = b;
      ijk[third] = c;
      for (int a = first; a <= last; ++a) {
        ijk[along] = a;
        if (accessor.isValueOn(ijk)) continue;
        const Eigen::Vector3d x = voxel_size_mm * Eigen::Vector3d(ijk.x(), ijk.y(), ijk.z());
        if (flat && (n.dot(x - v[0]) > above || n.dot(x - v[0]) < -below)) continue;
        const TriangleClosestPoint on_base = closest_point_on_triangle(x, v[0], v[1], v[2]);
        if ((x - on_base.point).squaredNorm() > reach * reach) continue;
        accessor.setValueOn(ijk);
      }
    }
  }
}

/// The candidate voxels of the band: a closed shell around the surface (see LevelSet's
/// constructor), in leaf order; none when cancelled.
std::vector<openvdb::Coord> band_candidates(const SignedDistanceMesh& mesh,
                                            const std::vector<PatchHeights>& patches, double band,
                                            double voxel_size_mm) {
  openvdb::MaskGrid candidates(false);
  {
    auto accessor = candidates.getAccessor();
    for (std::size_t t = 0; t < patches.size(); ++t) {
      // Built inside an OpenMP loop over organs, so a cancelled run returns (no exception may
      // leave the region) and the caller throws once the loop ends; the grid is left empty.
      if (cancellation_requested()) return {};
      const double above = band + patches[t].above_mm + 1e-9, below = band + patches[t].below_mm + 1e-9;
      mark_triangle_candidates(mesh, static_cast<int>(t), above, below, voxel_size_mm, accessor);
    }
  }
  std::vector<openvdb::Coord> coords;
  coords.reserve(static_cast<std::size_t>(candidates.activeVoxelCount()));
  for (auto it = candidates.cbeginValueOn(); it; ++it)
    coords.push_back(it.getCoord());
  return coords;
}

/// The signed distances of the candidates to the patch surface, clamped to the band.
std::vector<float> candidate_distances(const SignedDistanceMesh& mesh,
                                       const std::vector<PatchHeights>& patches,
                                       const std::vector<openvdb::Coord>& coords, double band,
                                       double voxel_size_mm) {
  std::vector<float> values(coords.size());
  const auto count = static_cast<std::ptrdiff_t>(coords.size());
  const auto position = [&](std::size_t i) {
    return Eigen::Vector3d(voxel_size_mm * Eigen::Vector3d(coords[i].x(), coords[i].y(), coords[i].z()));
  };
  // The signed distance of candidate i from its closest base triangle.
  const auto evaluate_one = [&](std::size_t i, const MeshClosestPoint& closest) {
    const Eigen::Vector3d x = position(i);
    double d = std::sqrt(closest.distance_squared);
    if (mesh.inside(x, closest)) d = -d;
    const PatchHeights& p = patches[static_cast<std::size_t>(closest.triangle)];
    if (!p.bumps.empty()) {
      // On an edge or corner of the base the bumps vanish (their ellipses lie inside the
      // triangle), so this corrects only points above a patch's interior: the side from the
      // height of the surface above the closest base point, the distance from the patch's
      // closest point.
      const Eigen::Vector2d uv = closest.on_triangle.barycentric.tail<2>();
      Eigen::Vector2d d_uv;
      const double h = p.height(uv, &d_uv);
      const double along_normal = d - h;
      // The patch may come within the band of x wherever its heights reach: x's height above
      // the base plane within the band of [-below, above]. A point a band width or more above the
      // surface point below it can still lie beside a bump's flank, nearer than the band (the
      // distance along the normal would be more than a voxel too large there on steep bumps). Farther, every
      // point of the patch is at least the band away and the value is the band's either way.
      const double z = p.normal.dot(x - p.origin);
      const double distance = z > -p.below_mm - band && z < p.above_mm + band ? p.distance(x, uv, h, d_uv)
                                                                              : std::abs(along_normal);
      d = along_normal < 0.0 ? -distance : distance;
    }
    values[i] = static_cast<float>(std::clamp(d, -band, band));
  };
  // Candidates come leaf by leaf (8^3 voxels); each leaf's are searched in blocks of 4^3, every
  // voxel of a block among the triangles the block needs (SignedDistanceMesh::near_box: the
  // same answer as a search from the tree's root each, at about three quarters of the cost).
  constexpr int k_block_shift = 2;
  const auto block_of = [&](std::size_t i) {
    const openvdb::Coord& ijk = coords[i];
    return std::array<int, 3>{ijk.x() >> k_block_shift, ijk.y() >> k_block_shift, ijk.z() >> k_block_shift};
  };
  const auto evaluate = [&](std::ptrdiff_t first, std::ptrdiff_t last) {
    SignedDistanceMesh::NearTriangles near;
    std::vector<std::size_t> leaf;
    for (std::ptrdiff_t start = first; start < last;) {
      if (cancellation_requested()) return;
      // This leaf's candidates (within the piece), grouped by block.
      const openvdb::Coord origin = coords[static_cast<std::size_t>(start)] & ~7;
      std::ptrdiff_t end = start;
      leaf.clear();
      while (end < last && (coords[static_cast<std::size_t>(end)] & ~7) == origin)
        leaf.push_back(static_cast<std::size_t>(end++));
      std::stable_sort(leaf.begin(), leaf.end(),
                       [&](std::size_t a, std::size_t b) { return block_of(a) < block_of(b); });
      for (std::size_t from = 0; from < leaf.size();) {
        std::size_t to = from;
        Eigen::Vector3d lo = position(leaf[from]), hi = lo;
        while (to < leaf.size() && block_of(leaf[to]) == block_of(leaf[from])) {
          lo = lo.cwiseMin(position(leaf[to]));
          hi = hi.cwiseMax(position(leaf[to]));
          ++to;
        }
        mesh.near_box(lo, hi, near);
        for (std::size_t k = from; k < to; ++k)
          evaluate_one(leaf[k], mesh.closest(position(leaf[k]), near));
        from = to;
      }
      start = end;
    }
  };
  // In pieces, each value its own (the result does not depend on the threads). Inside the
  // voxelizer's loop over organs the pieces are tasks: a thread done with its own organs takes
  // them up while it waits at the loop's end, instead of idling while the last organ is built.
  constexpr std::ptrdiff_t k_piece = 4096;
  const std::ptrdiff_t pieces = (count + k_piece - 1) / k_piece;
  if (omp_in_parallel()) {
#pragma omp taskloop grainsize(1)
    for (std::ptrdiff_t piece = 0; piece < pieces; ++piece)
      evaluate(piece * k_piece, std::min(count, (piece + 1) * k_piece));
  } else {
#pragma omp parallel for schedule(dynamic, 1)
    for (std::ptrdiff_t piece = 0; piece < pieces; ++piece)
      evaluate(piece * k_piece, std::min(count, (piece + 1) * k_piece));
  }
  return values;
}

} // namespace

struct LevelSet::Impl {
  /// Never null: a construction cut short by cancellation leaves an empty grid.
  openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create();
};

LevelSet::LevelSet(const PatchSurface& surface, double voxel_size_mm, double half_width_voxels,
                   const std::vector<HeightRange>* height_ranges)
    : m(std::make_unique<Impl>()), m_voxel_size(voxel_size_mm), m_half_width(half_width_voxels) {
  initialize_openvdb();
  const TriangleMesh& base = surface.base_mesh();
  SignedDistanceMesh mesh(base.faces);
  mesh.update(base.vertices);
  const double band = half_width_voxels * voxel_size_mm;
  const std::vector<PatchHeights> patches = patch_heights(surface, height_ranges);
  // A voxel x within the band of the surface point p = b + h n above base point b satisfies
  // |x - b| <= band + |h| and -band - below <= n . (x - v0) <= band + above, with the patch's
  // height bounds (patch_height_range). So the candidates are the voxels near each triangle by
  // its own patch's bounds: a closed shell around the surface. Each candidate then finds its
  // closest base triangle over the whole mesh (search tree; ties go to the lowest triangle
  // index, as in SignedDistanceMesh::closest()). Bounding each triangle by its own patch's
  // heights, not the largest of the surface's, and by the heights its bumps reach together, not
  // the sum of their amplitudes (about 4 times the true extremes on fitted anatomy), keeps the
  // shell thin: fewer candidates, each a closest-triangle search.
  const std::vector<openvdb::Coord> coords = band_candidates(mesh, patches, band, voxel_size_mm);
  if (cancellation_requested()) return;
  mesh.build_search_tree();
  const std::vector<float> values = candidate_distances(mesh, patches, coords, band, voxel_size_mm);
  if (cancellation_requested()) return;
  m->grid = openvdb::FloatGrid::create(static_cast<float>(band));
  m->grid->setTransform(openvdb::math::Transform::createLinearTransform(voxel_size_mm));
  {
    auto accessor = m->grid->getAccessor();
    for (std::size_t c = 0; c < coords.size(); ++c)
      accessor.setValueOn(coords[c], values[c]);
  }
  // The candidates form a closed shell around the surface, so the flood fill gives every voxel
  // off it the sign of its side; then only the narrow band stays active.
  openvdb::tools::signedFloodFill(m->grid->tree());
  for (auto leaf = m->grid->tree().beginLeaf(); leaf; ++leaf) {
    for (auto it = leaf->beginValueOn(); it; ++it)
      if (std::abs(*it) >= static_cast<float>(band)) it.setValueOff();
  }
  openvdb::tools::pruneLevelSet(m->grid->tree());
  m->grid->setGridClass(openvdb::GRID_LEVEL_SET);
}

LevelSet::LevelSet(const TriangleMesh& surface, double voxel_size_mm, double half_width_voxels)
    : m(std::make_unique<Impl>()), m_voxel_size(voxel_size_mm), m_half_width(half_width_voxels) {
  initialize_openvdb();
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
  // Passed as the base class, whose wasInterrupted is virtual: the call then matches the
  // instantiation compiled into libopenvdb (declared extern in MeshToVolume.h) instead of
  // instantiating the whole mesh-to-volume machinery in this file (minutes of compilation).
  CancellationInterrupter interrupter;
  openvdb::util::NullInterrupter& base_interrupter = interrupter;
  m->grid = openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(
      base_interrupter, *transform, points, triangles, static_cast<float>(half_width_voxels));
  if (cancellation_requested()) return; // cut short: the caller throws before reading it
  m->grid->setGridClass(openvdb::GRID_LEVEL_SET);
}

LevelSet::LevelSet(std::shared_ptr<void> grid, double voxel_size_mm, double half_width_voxels)
    : m(std::make_unique<Impl>()), m_voxel_size(voxel_size_mm), m_half_width(half_width_voxels) {
  initialize_openvdb();
  // A grid of its own around the stored tree: the transform and class as built, and none of the
  // metadata that storing may have added (a .vdb file written from it is then the same).
  m->grid = openvdb::FloatGrid::create(std::static_pointer_cast<openvdb::FloatGrid>(grid)->treePtr());
  m->grid->setTransform(openvdb::math::Transform::createLinearTransform(voxel_size_mm));
  m->grid->setGridClass(openvdb::GRID_LEVEL_SET);
}

LevelSet::~LevelSet() = default;
LevelSet::LevelSet(LevelSet&&) noexcept = default;
LevelSet& LevelSet::operator=(LevelSet&&) noexcept = default;

std::size_t LevelSet::active_voxel_count() const {
  return static_cast<std::size_t>(m->grid->activeVoxelCount());
}

std::vector<Eigen::AlignedBox3d> LevelSet::block_reach_mm() const {
  std::vector<Eigen::AlignedBox3d> out;
  out.reserve(static_cast<std::size_t>(m->grid->tree().leafCount()));
  const openvdb::math::Transform& transform = m->grid->transform();
  for (auto leaf = m->grid->tree().cbeginLeaf(); leaf; ++leaf) {
    // A sample's stencil reaches one voxel past the block; two more for rounding, as the probe.
    const openvdb::CoordBBox box = leaf->getNodeBoundingBox().expandBy(2);
    Eigen::AlignedBox3d reach;
    for (const openvdb::Coord& corner : {box.min(), box.max()}) {
      const openvdb::Vec3d x = transform.indexToWorld(corner);
      reach.extend(Eigen::Vector3d(x.x(), x.y(), x.z()));
    }
    out.push_back(reach);
  }
  return out;
}

const void* LevelSet::grid() const {
  return m->grid.get();
}

struct LevelSet::Probe::Impl {
  explicit Impl(const openvdb::FloatGrid& grid, double voxel_size)
      : accessor(grid.getConstAccessor()), transform(grid.transform()), background(grid.background()),
        inverse_voxel(1.0 / voxel_size) {
    // Beyond the leaves (and a margin for the trilinear stencil and rounding) every value is the
    // outside background: a closed surface's inside tiles lie within its band's leaves.
    // A uniform scale (every level set here) maps world to index by one product, the same
    // product OpenVDB's map computes: then the stencil needs no call through the map.
    const openvdb::Vec3d unit = transform.worldToIndex(openvdb::Vec3d(1.0, 1.0, 1.0));
    scale_only = transform.mapType() == openvdb::math::UniformScaleMap::mapType() &&
                 unit == openvdb::Vec3d(inverse_voxel, inverse_voxel, inverse_voxel);
    low = Eigen::Vector3d::Constant(1e300);
    high = -low;
    for (auto leaf = grid.tree().cbeginLeaf(); leaf; ++leaf) {
      const openvdb::CoordBBox box = leaf->getNodeBoundingBox();
      for (int a = 0; a < 3; ++a) {
        low[a] = std::min(low[a], static_cast<double>(box.min()[a]) - 2.0);
        high[a] = std::max(high[a], static_cast<double>(box.max()[a]) + 2.0);
      }
    }
  }
  openvdb::FloatGrid::ConstAccessor accessor;
  const openvdb::math::Transform& transform;
  float background;
  double inverse_voxel;
  bool scale_only = false;   ///< world to index is x * inverse_voxel
  Eigen::Vector3d low, high; ///< index-space box beyond which the value is the background
  /// The last stencil read: samples close together (a voxel's supersamples) mostly share it.
  openvdb::Coord cached_cell = openvdb::Coord::max();
  float cached[2][2][2] = {};

  /// Scratch of lattice(): per axis the points' cells and weights, the corners' values and the
  /// interpolations along z and then y.
  struct Axis {
    std::vector<int> cell;
    std::vector<double> weight;
    int first = 0, count = 0; ///< the corners' index range: first .. first + count - 1
  };
  Axis axes[3];
  std::vector<float> corners, along_z, along_y, values;

  /// Each point's cell and weight along one axis, as operator() computes them; false when a
  /// point lies beyond the stored blocks (its value is the background) or the map is not a
  /// uniform scale.
  bool set_axis(int a, const double* x, int n) {
    Axis& axis = axes[a];
    axis.cell.resize(static_cast<std::size_t>(n));
    axis.weight.resize(static_cast<std::size_t>(n));
    int low_cell = std::numeric_limits<int>::max(), high_cell = std::numeric_limits<int>::min();
    for (int i = 0; i < n; ++i) {
      const double index = x[i] * inverse_voxel;
      if (!(index >= low[a] && index <= high[a])) return false;
      const int cell = openvdb::math::Floor(index);
      axis.cell[static_cast<std::size_t>(i)] = cell;
      axis.weight[static_cast<std::size_t>(i)] = index - static_cast<double>(cell);
      low_cell = std::min(low_cell, cell);
      high_cell = std::max(high_cell, cell);
    }
    axis.first = low_cell;
    axis.count = high_cell - low_cell + 2;
    return true;
  }

  /// set_axis for the three axes, then read_corners; false: no lattice (see set_axis).
  bool prepare_lattice(const double* xs, int nx, const double* ys, int ny, const double* zs, int nz);
  /// The lattice's values from the corners read, into out[a + nx (b + ny c)].
  void interpolate_lattice(float* out);

  /// Reads the corners of every stencil (the box spanned by the axes' cells) into `corners`
  /// (z fastest): the values OpenVDB's accessor gives, as operator() reads them.
  void read_corners() {
    const int cx = axes[0].count, cy = axes[1].count, cz = axes[2].count;
    corners.resize(static_cast<std::size_t>(cx * cy * cz));
    const openvdb::Coord origin(axes[0].first, axes[1].first, axes[2].first);
    const openvdb::Coord last = origin + openvdb::Coord(cx - 1, cy - 1, cz - 1);
    using Leaf = openvdb::FloatGrid::TreeType::LeafNodeType;
    constexpr int mask = ~static_cast<int>(Leaf::DIM - 1);
    if ((origin.x() & mask) == (last.x() & mask) && (origin.y() & mask) == (last.y() & mask) &&
        (origin.z() & mask) == (last.z() & mask)) {
      // Within one 8^3 block: its leaf's values, or one constant tile.
      if (const Leaf* leaf = accessor.probeConstLeaf(origin)) {
        const openvdb::Index base = Leaf::coordToOffset(origin);
        std::size_t at = 0;
        for (int i = 0; i < cx; ++i)
          for (int j = 0; j < cy; ++j)
            for (int k = 0; k < cz; ++k)
              corners[at++] = leaf->getValue(
                  base + static_cast<openvdb::Index>((i << (2 * Leaf::LOG2DIM)) + (j << Leaf::LOG2DIM) + k));
      } else {
        std::fill(corners.begin(), corners.end(), accessor.getValue(origin));
      }
      return;
    }
    std::size_t at = 0;
    for (int i = 0; i < cx; ++i)
      for (int j = 0; j < cy; ++j)
        for (int k = 0; k < cz; ++k)
          corners[at++] = accessor.getValue(origin + openvdb::Coord(i, j, k));
  }
};

namespace {

/// OpenVDB's BoxSampler's step between two values (its _interpolate), the same arithmetic.
inline float interpolate(float a, float b, double weight) {
  const double temp = (b - a) * weight;
  return static_cast<float>(a + static_cast<float>(temp));
}

} // namespace

LevelSet::Probe::Probe(const LevelSet& level_set)
    : m(std::make_unique<Impl>(*level_set.m->grid, level_set.m_voxel_size)) {}
LevelSet::Probe::~Probe() = default;
LevelSet::Probe::Probe(Probe&&) noexcept = default;

double LevelSet::Probe::operator()(const Eigen::Vector3d& x) const {
  const Eigen::Vector3d index = x * m->inverse_voxel;
  if ((index.array() < m->low.array()).any() || (index.array() > m->high.array()).any())
    return static_cast<double>(m->background);
  // The trilinear stencil (the cell's 8 corners) mostly lies within one 8^3 block: then it is
  // read straight from that block's leaf, or, deep inside or outside, it is one constant tile
  // (no leaf) whose value is the sample. Either way the value is OpenVDB's BoxSampler's, bit for
  // bit: the same corners, the same interpolation (a + w (b - a), exact when a = b).
  const openvdb::Vec3d stencil = m->scale_only
                                     ? openvdb::Vec3d(index.x(), index.y(), index.z())
                                     : m->transform.worldToIndex(openvdb::Vec3d(x.x(), x.y(), x.z()));
  const openvdb::Coord cell = openvdb::Coord::floor(stencil);
  float(&data)[2][2][2] = m->cached;
  if (cell != m->cached_cell) {
    using Leaf = openvdb::FloatGrid::TreeType::LeafNodeType;
    constexpr int last_in_leaf = Leaf::DIM - 1;
    if ((cell.x() & last_in_leaf) != last_in_leaf && (cell.y() & last_in_leaf) != last_in_leaf &&
        (cell.z() & last_in_leaf) != last_in_leaf) {
      const Leaf* leaf = m->accessor.probeConstLeaf(cell);
      if (leaf == nullptr) {
        const float tile = m->accessor.getValue(cell);
        for (int i = 0; i < 2; ++i)
          for (int j = 0; j < 2; ++j)
            for (int k = 0; k < 2; ++k)
              data[i][j][k] = tile;
      } else {
        const openvdb::Index corner = Leaf::coordToOffset(cell);
        for (int i = 0; i < 2; ++i)
          for (int j = 0; j < 2; ++j)
            for (int k = 0; k < 2; ++k)
              data[i][j][k] = leaf->getValue(corner + static_cast<openvdb::Index>((i << (2 * Leaf::LOG2DIM)) +
                                                                                  (j << Leaf::LOG2DIM) + k));
      }
    } else {
      openvdb::tools::BoxSampler::probeValues(data, m->accessor, cell); // the sampler's own read
    }
    m->cached_cell = cell;
  }
  const openvdb::Vec3d uvw = stencil - openvdb::Vec3d(cell.x(), cell.y(), cell.z());
  return static_cast<double>(openvdb::tools::BoxSampler::trilinearInterpolation(data, uvw));
}

bool LevelSet::Probe::Impl::prepare_lattice(const double* xs, int nx, const double* ys, int ny,
                                            const double* zs, int nz) {
  if (!scale_only || !set_axis(0, xs, nx) || !set_axis(1, ys, ny) || !set_axis(2, zs, nz)) return false;
  read_corners();
  return true;
}

void LevelSet::Probe::Impl::interpolate_lattice(float* out) {
  const Axis &x = axes[0], &y = axes[1], &z = axes[2];
  const std::size_t sx = x.cell.size(), sy = y.cell.size(), sz = z.cell.size();
  const auto cx = static_cast<std::size_t>(x.count), cy = static_cast<std::size_t>(y.count),
             cz = static_cast<std::size_t>(z.count);
  // Along z at every corner column (i, j) and point c, then along y at (i, b, c), then along x:
  // the order of BoxSampler::trilinearInterpolation, each step on the same two values.
  along_z.resize(cx * cy * sz);
  for (std::size_t ij = 0; ij < cx * cy; ++ij)
    for (std::size_t c = 0; c < sz; ++c) {
      const auto k = static_cast<std::size_t>(z.cell[c] - z.first);
      along_z[ij * sz + c] = interpolate(corners[ij * cz + k], corners[ij * cz + k + 1], z.weight[c]);
    }
  along_y.resize(cx * sy * sz);
  for (std::size_t i = 0; i < cx; ++i)
    for (std::size_t b = 0; b < sy; ++b) {
      const auto j = static_cast<std::size_t>(y.cell[b] - y.first);
      const float* below = &along_z[(i * cy + j) * sz];
      const float* above = below + sz;
      float* row = &along_y[(i * sy + b) * sz];
      for (std::size_t c = 0; c < sz; ++c)
        row[c] = interpolate(below[c], above[c], y.weight[b]);
    }
  for (std::size_t a = 0; a < sx; ++a) {
    const auto i = static_cast<std::size_t>(x.cell[a] - x.first);
    for (std::size_t b = 0; b < sy; ++b) {
      const float* below = &along_y[(i * sy + b) * sz];
      const float* above = below + sy * sz;
      for (std::size_t c = 0; c < sz; ++c)
        out[a + sx * (b + sy * c)] = interpolate(below[c], above[c], x.weight[a]);
    }
  }
}

void LevelSet::Probe::lattice(const double* xs, int nx, const double* ys, int ny, const double* zs, int nz,
                              float* values) const {
  if (nx <= 0 || ny <= 0 || nz <= 0) return;
  if (m->prepare_lattice(xs, nx, ys, ny, zs, nz)) {
    m->interpolate_lattice(values);
    return;
  }
  // Beyond the blocks, or a map other than a scale: point by point.
  for (int c = 0; c < nz; ++c)
    for (int b = 0; b < ny; ++b)
      for (int a = 0; a < nx; ++a)
        values[a + nx * (b + ny * c)] = static_cast<float>((*this)(Eigen::Vector3d(xs[a], ys[b], zs[c])));
}

void LevelSet::Probe::lattice_inside(const double* xs, int nx, const double* ys, int ny, const double* zs,
                                     int nz, std::uint8_t* inside) const {
  if (nx <= 0 || ny <= 0 || nz <= 0) return;
  const std::size_t count =
      static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny) * static_cast<std::size_t>(nz);
  Impl& p = *m;
  p.values.resize(count);
  if (p.prepare_lattice(xs, nx, ys, ny, zs, nz)) {
    // Each step a + (b - a) w (w in [0, 1]) lies between a and b, rounded, when both are >= 0
    // or both <= 0: each rounding is monotone and a and b are representable. So corners all
    // >= 0 give values >= 0: none inside. Corners all in [-B, -m] give values within
    // 3 * 2^-22 B of that range (each step errs by at most 2^-22 B before its last rounding,
    // which keeps the sign), so all below zero when m >= 1e-5 B.
    float smallest = p.corners.front(), largest = smallest;
    bool finite = true;
    for (const float v : p.corners) {
      finite = finite && std::isfinite(v);
      smallest = std::min(smallest, v);
      largest = std::max(largest, v);
    }
    if (finite && smallest >= 0.0f) {
      std::fill(inside, inside + count, std::uint8_t{0});
      return;
    }
    if (finite && largest <= -std::max(1e-5f * -smallest, 1e-20f)) {
      std::fill(inside, inside + count, std::uint8_t{1});
      return;
    }
    p.interpolate_lattice(p.values.data());
  } else {
    lattice(xs, nx, ys, ny, zs, nz, p.values.data());
  }
  for (std::size_t s = 0; s < count; ++s)
    inside[s] = p.values[s] < 0.0f ? 1 : 0;
}

} // namespace phantasm
