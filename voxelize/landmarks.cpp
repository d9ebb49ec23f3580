#include "voxelize/landmarks.hpp"

#include "anatomy/mesh_distance.hpp"
#include "core/cancellation.hpp"
#include "core/progress.hpp"
#include "geometry/distance_transform.hpp"
#include "geometry/mesh_signed_distance.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <limits>
#include <memory>
#include <numeric>
#include <optional>
#include <stdexcept>

namespace phantasm {
namespace {

/// The organs' surfaces for distance queries, each tessellated within the tolerance once when
/// first needed (an organ is its own material's outer surface and the inner one of the organ it
/// is nested in) and dropped after its last use (done() of itself and of that organ), so that
/// few are held at once. prepare() builds an organ's missing surfaces and the next organ's
/// together, one per thread: a tessellation and its search tree are built largely serially (on
/// the Colin head up to 2 s per surface), so two at once keep both cores busy.
class OrganDistances {
public:
  OrganDistances(const Phantom& phantom, double tolerance_mm)
      : m_phantom(phantom), m_tolerance_mm(tolerance_mm), m_meshes(phantom.organs.size()),
        m_uses(phantom.organs.size(), 1) {
    for (const Organ& organ : phantom.organs)
      for (std::size_t p = 0; p < phantom.organs.size(); ++p)
        if (organ.surface && phantom.organs[p].surface && phantom.organs[p].name == organ.inside)
          ++m_uses[&organ - phantom.organs.data()];
  }

  /// Organ o's material is done: its surface and those nested in it lose one use.
  void done(std::size_t o) {
    release(o);
    for (std::size_t n = 0; n < m_phantom.organs.size(); ++n)
      if (m_phantom.organs[n].inside == m_phantom.organs[o].name && m_phantom.organs[n].surface) release(n);
  }

  /// Builds the surfaces organ o's material needs (its own and those nested in it) that are not
  /// built yet and, when there are any, those the next organ with a surface needs, in parallel.
  /// Each surface is built the same way on any thread: the distances do not depend on the
  /// thread count. Throws Cancelled when cancellation was requested.
  void prepare(std::size_t o) {
    std::vector<std::size_t> missing;
    const auto add_missing = [&](std::size_t k) {
      for (std::size_t n = 0; n < m_phantom.organs.size(); ++n) {
        const bool needed = n == k || (m_phantom.organs[n].inside == m_phantom.organs[k].name);
        if (needed && m_phantom.organs[n].surface && !m_meshes[n] &&
            std::find(missing.begin(), missing.end(), n) == missing.end())
          missing.push_back(n);
      }
    };
    add_missing(o);
    if (missing.empty()) return;
    std::size_t next = o + 1;
    while (next < m_phantom.organs.size() && !m_phantom.organs[next].surface)
      ++next;
    if (next < m_phantom.organs.size()) add_missing(next);
    // No exception may leave the OpenMP region: each surface's is kept and the first rethrown.
    std::vector<std::exception_ptr> failures(missing.size());
    const auto count = static_cast<std::ptrdiff_t>(missing.size());
#pragma omp parallel for schedule(dynamic, 1) if (count > 1)
    for (std::ptrdiff_t i = 0; i < count; ++i) {
      if (cancellation_requested()) continue;
      try {
        m_meshes[missing[static_cast<std::size_t>(i)]] = build(missing[static_cast<std::size_t>(i)]);
      } catch (...) {
        failures[static_cast<std::size_t>(i)] = std::current_exception();
      }
    }
    for (const std::exception_ptr& failure : failures)
      if (failure) std::rethrow_exception(failure);
    throw_if_cancelled();
  }

  const MeshDistance& of(std::size_t o) {
    if (!m_meshes[o]) m_meshes[o] = build(o);
    return *m_meshes[o];
  }

private:
  std::unique_ptr<MeshDistance> build(std::size_t o) const {
    return std::make_unique<MeshDistance>(m_phantom.organs[o].surface->tessellate(m_tolerance_mm));
  }

  void release(std::size_t o) {
    if (m_uses[o] > 0 && --m_uses[o] == 0) m_meshes[o].reset();
  }

  const Phantom& m_phantom;
  double m_tolerance_mm;
  std::vector<std::unique_ptr<MeshDistance>> m_meshes;
  std::vector<int> m_uses;
};

} // namespace

// Outside the unnamed namespace: OrganMaterial (landmarks.hpp) holds it.
namespace landmarks_detail {

/// Which side of an organ's surface a point lies on, decided as the voxelizer decides it
/// (voxelize/level_set.cpp): the closest triangle of the base mesh, the side of it from the base
/// mesh's pseudonormals, and then the height of that patch's bumps above the closest base point.
/// The tessellation's own pseudonormals cannot tell the side where it folds over itself (bumps
/// that cross a neighbouring patch; two triangles of opposite normals on one edge): a whole cone
/// of space beyond such a fold counted as inside the organ, and on the Colin head the compass
/// search climbed it out of the head (the white matter's deepest point) or the deepest points
/// fell in nested organs (the csf's and grey matter's).
class OrganSide {
public:
  explicit OrganSide(const PatchSurface& surface) : m_surface(&surface), m_base(surface.base_mesh().faces) {
    m_base.update(surface.rest_positions());
    m_base.build_search_tree();
  }

  /// @param hint the closest base triangle of a point asked for before, -1 for none; set to x's
  bool inside(const Eigen::Vector3d& x, int& hint) const {
    const MeshClosestPoint c = m_base.closest(x, hint);
    hint = c.triangle;
    if (c.triangle < 0) return false;
    const double d = std::sqrt(c.distance_squared);
    double along_normal = m_base.inside(x, c) ? -d : d;
    if (!m_surface->bumps(c.triangle).empty()) {
      const Eigen::Vector2d uv = c.on_triangle.barycentric.tail<2>();
      along_normal -= m_surface->height(c.triangle, uv.x(), uv.y());
    }
    return along_normal < 0.0;
  }

private:
  const PatchSurface* m_surface;
  SignedDistanceMesh m_base;
};

} // namespace landmarks_detail

using landmarks_detail::OrganSide;

struct OrganMaterial::Sides {
  std::vector<OrganSide> sides; ///< the organ's own surface first, then the nested organs'
  std::vector<int> hints;       ///< per surface: the closest base triangle of the last point
};

OrganMaterial::OrganMaterial(const Phantom& phantom, std::size_t organ) : m_sides(std::make_unique<Sides>()) {
  m_sides->sides.emplace_back(*phantom.organs[organ].surface);
  for (const Organ& nested : phantom.organs)
    if (nested.inside == phantom.organs[organ].name && nested.surface)
      m_sides->sides.emplace_back(*nested.surface);
  m_sides->hints.assign(m_sides->sides.size(), -1);
}

OrganMaterial::~OrganMaterial() = default;
OrganMaterial::OrganMaterial(OrganMaterial&&) noexcept = default;

bool OrganMaterial::contains(const Eigen::Vector3d& x) {
  std::vector<int>& hints = m_sides->hints;
  if (!m_sides->sides[0].inside(x, hints[0])) return false;
  for (std::size_t s = 1; s < m_sides->sides.size(); ++s)
    if (m_sides->sides[s].inside(x, hints[s])) return false;
  return true;
}

namespace {

/// How far a point is inside an organ's own material: the distance to the organ's surface or to
/// the nearest organ nested in it, whichever is closer (mm); outside that material a value <= 0.
/// Distances from the tessellations (within their tolerance of the surfaces), sides from OrganSide.
/// The sides come first: a point outside the material (outside the organ or inside a nested one)
/// is told so without a distance search, the most of the work (the tessellations' search trees
/// hold up to millions of triangles); every use of a clearance <= 0 is that the point is not a
/// candidate. Each query starts from the closest triangles of the point asked before with the
/// same hints (a neighbour along a ray or the grid, or the compass search's last point): fewer
/// boxes are opened, and the answers, ties included, are those of a search without hints.
class OwnMaterial {
public:
  OwnMaterial(const Phantom& phantom, std::size_t o, OrganDistances& distances)
      : m_own{&distances.of(o), OrganSide(*phantom.organs[o].surface)} {
    for (std::size_t n = 0; n < phantom.organs.size(); ++n) {
      if (phantom.organs[n].inside == phantom.organs[o].name && phantom.organs[n].surface)
        m_nested.push_back({&distances.of(n), OrganSide(*phantom.organs[n].surface)});
    }
  }

  /// The closest triangles of the last point asked for: two per surface (its tessellation's and
  /// its base mesh's), the organ's own first; -1 for none yet. One set per thread.
  using Hints = std::vector<int>;
  Hints no_hints() const { return Hints(2 * (1 + m_nested.size()), -1); }

  /// The clearance at x inside the material; outside it 0 (not the distance: no candidate).
  double clearance(const Eigen::Vector3d& x, Hints& hints) const {
    if (!m_own.side.inside(x, hints[1])) return 0.0;
    for (std::size_t n = 0; n < m_nested.size(); ++n)
      if (m_nested[n].side.inside(x, hints[2 * (n + 1) + 1])) return 0.0;
    double c = m_own.distance_to(x, hints[0]);
    for (std::size_t n = 0; n < m_nested.size(); ++n)
      c = std::min(c, m_nested[n].distance_to(x, hints[2 * (n + 1)]));
    return c;
  }

private:
  struct Surface {
    const MeshDistance* distance;
    OrganSide side;
    /// Unsigned distance to the tessellation, mm; hint: its closest triangle, updated to x's.
    double distance_to(const Eigen::Vector3d& x, int& hint) const {
      const MeshClosestPoint closest = distance->closest(x, hint);
      hint = closest.triangle;
      return std::sqrt(closest.distance_squared);
    }
  };
  Surface m_own;
  std::vector<Surface> m_nested;
};

struct Candidate {
  Eigen::Vector3d x;
  double clearance;
};

/// Candidate points of an organ's own material: a grid over its bounds (12 steps along the
/// longest side) and, for shells thinner than that grid, points stepped inward from every base
/// vertex along its normal until they leave the material again. The clearances are evaluated in
/// parallel (grid points, then rays); the list is in the same order on any number of threads.
std::vector<Candidate> candidates(const PatchSurface& surface, const OwnMaterial& material) {
  const Eigen::MatrixX3d& rest = surface.rest_positions();
  const Eigen::Vector3d low = rest.colwise().minCoeff().transpose(),
                        high = rest.colwise().maxCoeff().transpose();
  const double step = (high - low).maxCoeff() / 12.0;
  std::vector<Candidate> out;
  const Eigen::Vector3i points = ((high - low) / step).array().ceil().cast<int>() + 1;
  const std::ptrdiff_t grid_count = std::ptrdiff_t{points.x()} * points.y() * points.z();
  // Grid point n, x fastest.
  auto grid_point = [&](std::ptrdiff_t n) {
    const std::ptrdiff_t row = n / points.x();
    return Eigen::Vector3d(low + step * Eigen::Vector3d(static_cast<double>(n % points.x()),
                                                        static_cast<double>(row % points.y()),
                                                        static_cast<double>(row / points.y())));
  };
  std::vector<double> grid_clearance(static_cast<std::size_t>(grid_count));
#pragma omp parallel
  {
    OwnMaterial::Hints hints = material.no_hints();
#pragma omp for schedule(dynamic, 16)
    for (std::ptrdiff_t n = 0; n < grid_count; ++n) {
      if (cancellation_requested()) continue;
      grid_clearance[static_cast<std::size_t>(n)] = material.clearance(grid_point(n), hints);
    }
  }
  throw_if_cancelled();
  for (std::ptrdiff_t n = 0; n < grid_count; ++n) {
    const double c = grid_clearance[static_cast<std::size_t>(n)];
    if (c > 0.0) out.push_back({grid_point(n), c});
  }
  // Area-weighted vertex normals of the base mesh (outward).
  const Eigen::MatrixX3i& faces = surface.base_mesh().faces;
  Eigen::MatrixX3d normals = Eigen::MatrixX3d::Zero(rest.rows(), 3);
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    const Eigen::Vector3d a = rest.row(faces(f, 0)), b = rest.row(faces(f, 1)), c = rest.row(faces(f, 2));
    const Eigen::RowVector3d n = (b - a).cross(c - a).transpose();
    for (int k = 0; k < 3; ++k)
      normals.row(faces(f, k)) += n;
  }
  const double ray_step = step / 10.0;
  std::vector<std::vector<Candidate>> rays(static_cast<std::size_t>(rest.rows()));
  const auto vertex_count = static_cast<std::ptrdiff_t>(rest.rows());
#pragma omp parallel
  {
    OwnMaterial::Hints hints = material.no_hints();
#pragma omp for schedule(dynamic, 8)
    for (std::ptrdiff_t v = 0; v < vertex_count; ++v) {
      if (cancellation_requested() || !(normals.row(v).norm() > 0.0)) continue;
      const Eigen::Vector3d origin = rest.row(v).transpose(),
                            inward = -normals.row(v).normalized().transpose();
      std::vector<Candidate>& ray = rays[static_cast<std::size_t>(v)];
      double best = 0.0;
      for (int s = 1; s * ray_step < (high - low).norm(); ++s) {
        const Eigen::Vector3d x = origin + s * ray_step * inward;
        const double c = material.clearance(x, hints);
        if (c > 0.0) ray.push_back({x, c});
        best = std::max(best, c);
        if (best > 0.0 && c < 0.5 * best) break; // past the deepest point of this ray
      }
    }
  }
  throw_if_cancelled();
  for (const std::vector<Candidate>& ray : rays)
    out.insert(out.end(), ray.begin(), ray.end());
  return out;
}

/// Moves x uphill in clearance by a compass search (steps halved down to 0.01 mm), so the point
/// is the local deepest point whatever the candidate spacing was.
Candidate refine(Candidate best, const OwnMaterial& material, double step) {
  OwnMaterial::Hints hints = material.no_hints();
  while (step > 0.01) {
    bool improved = false;
    for (int axis = 0; axis < 3 && !improved; ++axis) {
      for (const double sign : {1.0, -1.0}) {
        Eigen::Vector3d x = best.x;
        x[axis] += sign * step;
        const double c = material.clearance(x, hints);
        if (c > best.clearance) {
          best = {x, c};
          improved = true;
          break;
        }
      }
    }
    if (!improved) step *= 0.5;
  }
  return best;
}

/// True when the ground-truth map around x (the 8 corners of a cube of half the map's extension,
/// two voxels wide, which holds every voxel a trilinear lookup at x reads) is the exact motion of
/// x's material: solved tets for an organ the solver moved, no motion at all (but the head's
/// growth) for one it did not.
bool exact_around(const DeformationMap& map, const Eigen::Vector3d& x, bool moved) {
  const double half = 0.5 * map.extension_mm();
  for (int corner = 0; corner < 9; ++corner) {
    Eigen::Vector3d q = x;
    if (corner < 8) {
      for (int axis = 0; axis < 3; ++axis)
        q[axis] += (corner >> axis & 1) ? half : -half;
    }
    bool exact = false;
    const Eigen::Vector3d y = map.forward(q, &exact);
    if (!exact || (!moved && y != map.head().apply(q))) return false;
  }
  return true;
}

/// The deepest point of an organ's own material (inside it, outside the organs nested in it):
/// the candidate of largest clearance, refined; with a map, the deepest whose surroundings the
/// map moves exactly with the organ (else the deepest of all). None when no candidate lies in
/// that material (organs nested in it fill it).
std::optional<Eigen::Vector3d> deepest_point(const Phantom& phantom, std::size_t o, OrganDistances& distances,
                                             const DeformationMap* map, bool moved) {
  const PatchSurface& surface = *phantom.organs[o].surface;
  distances.prepare(o);
  const OwnMaterial material(phantom, o, distances);
  std::vector<Candidate> list = candidates(surface, material);
  if (list.empty()) return std::nullopt;
  std::vector<std::size_t> order(list.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return list[a].clearance > list[b].clearance; });
  const Eigen::MatrixX3d& rest = surface.rest_positions();
  const double step = (rest.colwise().maxCoeff() - rest.colwise().minCoeff()).maxCoeff() / 40.0;
  const Candidate deepest = refine(list[order[0]], material, step);
  if (!map || exact_around(*map, deepest.x, moved)) return deepest.x;
  // Try the next candidates, each from a different neighbourhood (one candidate spacing apart).
  std::vector<Eigen::Vector3d> tried;
  for (std::size_t n = 1; n < order.size() && tried.size() < 64; ++n) {
    const Candidate& c = list[order[n]];
    bool near = false;
    for (const Eigen::Vector3d& t : tried)
      near |= (t - c.x).norm() < step;
    if (near) continue;
    tried.push_back(c.x);
    const Candidate refined = refine(c, material, 0.25 * step);
    if (exact_around(*map, refined.x, moved)) return refined.x;
  }
  return deepest.x;
}

/// Where each label lies on the grid: the index box of its voxels and whether any lies on the
/// grid's border (then the organ may reach beyond the grid).
struct LabelExtents {
  std::vector<Eigen::AlignedBox3i> box; ///< by label value; empty for a label with no voxel
  std::vector<bool> on_border;

  LabelExtents(const ImageGrid& grid, const std::vector<std::int32_t>& labels, std::size_t label_count)
      : box(label_count + 1), on_border(label_count + 1, false) {
    const Eigen::Vector3i& dims = grid.dims;
    for (int k = 0; k < dims.z(); ++k)
      for (int j = 0; j < dims.y(); ++j)
        for (int i = 0; i < dims.x(); ++i) {
          const std::int32_t l = labels[voxel_index(dims, i, j, k)];
          if (l <= 0 || static_cast<std::size_t>(l) > label_count) continue;
          box[static_cast<std::size_t>(l)].extend(Eigen::Vector3i(i, j, k));
          if (i == 0 || j == 0 || k == 0 || i == dims.x() - 1 || j == dims.y() - 1 || k == dims.z() - 1)
            on_border[static_cast<std::size_t>(l)] = true;
        }
  }
};

/// Whether the grid's axes are orthogonal with lengths its spacing (a distance transform in
/// index space with that spacing is then the world one).
bool orthogonal_axes(const ImageGrid& grid) {
  const Eigen::Matrix3d axes = grid.world_from_voxel.topLeftCorner<3, 3>();
  for (int a = 0; a < 3; ++a) {
    if (!(std::abs(axes.col(a).norm() - grid.spacing_mm[a]) <= 1e-9 * grid.spacing_mm[a])) return false;
    for (int b = a + 1; b < 3; ++b)
      if (!(std::abs(axes.col(a).dot(axes.col(b))) <= 1e-9 * grid.spacing_mm[a] * grid.spacing_mm[b]))
        return false;
  }
  return true;
}

/// Whether organ n lies inside organ o, directly or through organs nested in between.
bool nested_in(const Phantom& phantom, std::size_t n, std::size_t o) {
  for (std::size_t steps = 0; steps < phantom.organs.size() && !phantom.organs[n].inside.empty(); ++steps) {
    const Organ* container = phantom.find(phantom.organs[n].inside);
    if (!container) return false;
    n = static_cast<std::size_t>(container - phantom.organs.data());
    if (n == o) return true;
  }
  return false;
}

/// The candidates for the deepest point of an organ's own material from the reference labels
/// (organ_landmarks), handed to `take` in turn until it returns true: the centres of the voxels of
/// its label in order of their distance from every other voxel (the exact distance transform of
/// the label, over the label's box and one voxel around it, all of which lies outside the label:
/// a voxel beyond that ring is never nearer than the ring's voxel it projects to), deepest first,
/// that lie in the organ's own material by the patches; after the first, only those a step from
/// each one taken after it (candidates from different neighbourhoods, as the tessellation path),
/// up to 64 of them. None when the labels cannot tell (see organ_landmarks); then the
/// tessellations do.
void labelled_candidates(const Phantom& phantom, std::size_t o, const ReferenceLabels& labels,
                         const LabelExtents& extents,
                         const std::function<bool(const Eigen::Vector3d&)>& take) {
  const auto label = static_cast<std::size_t>(o) + 1;
  if (extents.box[label].isEmpty()) return;
  for (std::size_t n = 0; n < phantom.organs.size(); ++n)
    if ((n == o || nested_in(phantom, n, o)) && extents.on_border[n + 1]) return;
  const ImageGrid& grid = *labels.grid;
  std::size_t bumps = 0;
  for (Eigen::Index t = 0; t < phantom.organs[o].surface->patch_count(); ++t)
    bumps += phantom.organs[o].surface->bumps(t).size();
  const Eigen::Vector3d box_voxels = (extents.box[label].sizes().array() + 3).cast<double>();
  const bool cheaper = labels.voxels_per_bump == std::numeric_limits<double>::infinity() ||
                       box_voxels.prod() < labels.voxels_per_bump * static_cast<double>(bumps);
  if (!cheaper) return;
  // The label's box and one voxel around it (inside the grid: no voxel of the label is on its border).
  const Eigen::Vector3i first = extents.box[label].min().array() - 1,
                        last = extents.box[label].max().array() + 1;
  ImageGrid block = grid;
  block.dims = last - first + Eigen::Vector3i::Ones();
  std::vector<bool> outside(static_cast<std::size_t>(block.voxel_count()));
  for (int k = 0; k < block.dims.z(); ++k)
    for (int j = 0; j < block.dims.y(); ++j)
      for (int i = 0; i < block.dims.x(); ++i)
        outside[voxel_index(block.dims, i, j, k)] =
            (*labels.labels)[voxel_index(grid.dims, first.x() + i, first.y() + j, first.z() + k)] !=
            static_cast<std::int32_t>(label);
  const std::vector<double> depth = distance_to(outside, block);
  std::vector<std::size_t> order;
  for (std::size_t v = 0; v < outside.size(); ++v)
    if (!outside[v]) order.push_back(v);
  // Deepest first; equal depths in voxel order (the same on any thread count). Sorted as far as
  // the search reads, in growing pieces: it mostly stops within the first few voxels, and the
  // label of a large organ holds a million.
  const auto deeper = [&](std::size_t a, std::size_t b) {
    return depth[a] > depth[b] || (depth[a] == depth[b] && a < b);
  };
  std::size_t sorted = 0;
  const auto sort_through = [&](std::size_t n) {
    if (n < sorted) return;
    const std::size_t end = std::min(order.size(), std::max<std::size_t>(2 * sorted, n + 256));
    std::partial_sort(order.begin() + static_cast<std::ptrdiff_t>(sorted),
                      order.begin() + static_cast<std::ptrdiff_t>(end), order.end(), deeper);
    sorted = end;
  };
  OrganMaterial material(phantom, o);
  const auto centre = [&](std::size_t v) {
    const auto b = static_cast<std::int64_t>(v);
    const std::int64_t row = b / block.dims.x();
    return grid.world_from_index(Eigen::Vector3d(static_cast<double>(first.x() + b % block.dims.x()),
                                                 static_cast<double>(first.y() + row % block.dims.y()),
                                                 static_cast<double>(first.z() + row / block.dims.y())));
  };
  const Eigen::MatrixX3d& rest = phantom.organs[o].surface->rest_positions();
  const double step = (rest.colwise().maxCoeff() - rest.colwise().minCoeff()).maxCoeff() / 40.0;
  bool first_taken = false;
  std::vector<Eigen::Vector3d> tried;
  for (std::size_t n = 0; n < order.size(); ++n) {
    if (tried.size() >= 64) break;
    sort_through(n);
    const Eigen::Vector3d x = centre(order[n]);
    if (first_taken) {
      bool near = false;
      for (const Eigen::Vector3d& t : tried)
        near |= (t - x).norm() < step;
      if (near) continue;
    }
    if (!material.contains(x)) continue;
    if (first_taken) tried.push_back(x);
    first_taken = true;
    if (take(x)) return;
  }
}

/// The deepest point among an organ's candidates (labelled_candidates, in their order): the
/// first, the deepest, without a map or where the map moves its surroundings exactly with the
/// organ; else the first later one whose surroundings it moves so; else the first. None when there
/// are no candidates.
template <class Walk>
std::optional<Eigen::Vector3d> pick_deepest(const Walk& walk, const DeformationMap* map, bool moved) {
  std::optional<Eigen::Vector3d> deepest, exact;
  walk([&](const Eigen::Vector3d& x) {
    const bool first = !deepest;
    if (first) deepest = x;
    if ((first && !map) || exact_around(*map, x, moved)) exact = x;
    return exact.has_value();
  });
  return exact ? exact : deepest;
}

} // namespace

std::vector<Landmark> organ_landmarks(const Phantom& reference, const PhantomDeformation* deformation,
                                      const DeformationMap* map, double depth_tolerance_mm,
                                      std::vector<std::string>* warnings,
                                      const std::function<void()>& organ_done, const ReferenceLabels& labels,
                                      const DeepestCandidates* candidates) {
  static const char* const k_directions[6] = {"left",     "right",    "posterior",
                                              "anterior", "inferior", "superior"};
  std::vector<Landmark> out;
  OrganDistances distances(reference, depth_tolerance_mm);
  if (candidates && candidates->size() != reference.organs.size())
    throw std::logic_error("organ_landmarks: deepest-point candidates of another number of organs");
  std::optional<LabelExtents> extents;
  if (!candidates && labels.grid && labels.labels &&
      labels.labels->size() == static_cast<std::size_t>(labels.grid->voxel_count()) &&
      orthogonal_axes(*labels.grid))
    extents.emplace(*labels.grid, *labels.labels, reference.organs.size());
  for (std::size_t o = 0; o < reference.organs.size(); ++o) {
    const Organ& organ = reference.organs[o];
    if (!organ.surface) continue;
    // Seconds per organ of real anatomy (its surface tessellated for the depth search).
    progress_detail("landmarks: " + organ.name + "'s deepest point");
    const Eigen::MatrixX3d& rest = organ.surface->rest_positions();
    const Eigen::MatrixX3d& moved = deformation ? deformation->organs[o].surface_mm : rest;
    // Organs the solver moved carry their deepest point through the map (exact inside the
    // solved tets); the others did not move but by the head's growth.
    const bool moved_organ = deformation && (deformation->organs[o].moved_by == "solver" ||
                                             deformation->organs[o].moved_by.rfind("embedded", 0) == 0);
    std::optional<Eigen::Vector3d> deepest;
    if (candidates) {
      const std::vector<Eigen::Vector3d>& own = (*candidates)[o];
      deepest = pick_deepest(
          [&own](const auto& take) {
            for (const Eigen::Vector3d& x : own)
              if (take(x)) return;
          },
          map, moved_organ);
    } else if (extents) {
      deepest =
          pick_deepest([&](const auto& take) { labelled_candidates(reference, o, labels, *extents, take); },
                       map, moved_organ);
    }
    if (!deepest) deepest = deepest_point(reference, o, distances, map, moved_organ);
    distances.done(o);
    if (deepest) {
      out.push_back({organ.name + "_deepest", organ.name, *deepest,
                     moved_organ && map ? map->forward(*deepest)
                     : map              ? map->head().apply(*deepest)
                                        : *deepest});
    } else if (warnings) {
      warnings->push_back("landmark " + organ.name + "_deepest left out: no point of " + organ.name +
                          "'s own material (inside its surface, outside the organs nested in it) was found; "
                          "the nested organs fill it");
    }
    for (int d = 0; d < 6; ++d) {
      // RAS: left is -x, posterior -y, inferior -z.
      const int axis = d / 2;
      const double sign = d % 2 == 0 ? -1.0 : 1.0;
      Eigen::Index best = 0;
      (sign * rest.col(axis)).maxCoeff(&best);
      out.push_back({organ.name + "_" + k_directions[d], organ.name, rest.row(best).transpose(),
                     moved.row(best).transpose()});
    }
    if (organ_done) organ_done();
  }
  return out;
}

DeepestCandidates deepest_candidates(const Phantom& reference, const ReferenceLabels& labels) {
  DeepestCandidates out(reference.organs.size());
  if (!labels.grid || !labels.labels ||
      labels.labels->size() != static_cast<std::size_t>(labels.grid->voxel_count()) ||
      !orthogonal_axes(*labels.grid))
    return out;
  const LabelExtents extents(*labels.grid, *labels.labels, reference.organs.size());
  for (std::size_t o = 0; o < reference.organs.size(); ++o) {
    if (!reference.organs[o].surface) continue;
    labelled_candidates(reference, o, labels, extents, [&](const Eigen::Vector3d& x) {
      out[o].push_back(x);
      return false;
    });
  }
  return out;
}

std::string landmarks_csv(const std::vector<Landmark>& landmarks, bool deformed) {
  std::string text = "name,organ,x_mm,y_mm,z_mm\n";
  char line[256];
  for (const Landmark& l : landmarks) {
    // Rounded to the printed micrometre first, so a tiny negative value does not print as -0.000000.
    const Eigen::Vector3d x = ((deformed ? l.deformed_mm : l.reference_mm) * 1e6).array().round() / 1e6 + 0.0;
    std::snprintf(line, sizeof line, "%s,%s,%.6f,%.6f,%.6f\n", l.name.c_str(), l.organ.c_str(), x.x(), x.y(),
                  x.z());
    text += line;
  }
  return text;
}

} // namespace phantasm
