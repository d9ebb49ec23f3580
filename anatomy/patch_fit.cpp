#include "anatomy/patch_fit.hpp"

#include "anatomy/height_search.hpp"
#include "anatomy/mesh_distance.hpp"
#include "anatomy/surface_extraction.hpp"
#include "anatomy/trilinear_volume.hpp"
#include "core/cancellation.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

namespace phantasm {
namespace {

int icosphere_level_for(int base_triangles) {
  int level = 0;
  while (20 * (1 << (2 * (level + 1))) <= base_triangles && level < 8)
    ++level;
  return level;
}

/// The fitting basis of one patch: incircles (in rest geometry) of the sub-triangles of
/// subdivision levels 0..levels, and, along each base edge, ellipses that hug the edge, so the
/// strip the round bumps cannot reach gets bumps too.
std::vector<PatchBump> basis_bumps(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1,
                                   const Eigen::Vector3d& x2, int levels) {
  std::vector<PatchBump> bumps;
  const Eigen::Vector3d e1 = x1 - x0, e2 = x2 - x0;
  Eigen::Matrix2d metric;
  metric << e1.dot(e1), e1.dot(e2), e1.dot(e2), e2.dot(e2);
  for (int level = 0; level <= levels; ++level) {
    const int n = 1 << level;
    auto add = [&](Eigen::Vector2d a, Eigen::Vector2d b, Eigen::Vector2d c) {
      const Eigen::Vector3d pa = x0 + a.x() * e1 + a.y() * e2, pb = x0 + b.x() * e1 + b.y() * e2,
                            pc = x0 + c.x() * e1 + c.y() * e2;
      const double la = (pb - pc).norm(), lb = (pc - pa).norm(), lc = (pa - pb).norm();
      const double perimeter = la + lb + lc;
      const double area = 0.5 * (pb - pa).cross(pc - pa).norm();
      bumps.push_back(PatchBump::disc((la * a + lb * b + lc * c) / perimeter,
                                      (1.0 - 1e-9) * 2.0 * area / perimeter, metric));
    };
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i + j < n; ++i) {
        const Eigen::Vector2d p(double(i) / n, double(j) / n), du(1.0 / n, 0.0), dv(0.0, 1.0 / n);
        add(p, p + du, p + dv);
        if (i + j < n - 1) add(p + du, p + du + dv, p + dv);
      }
    }
  }
  // Edge ellipses, built in the edge's own affine coordinates (s along the edge from A to B,
  // t towards the opposite corner C), where the triangle is (0,0), (1,0), (0,1): centre
  // (1/2 - beta/2, beta), semi-axes alpha along the edge and beta across, as long as fits.
  const std::array<std::array<Eigen::Vector2d, 3>, 3> edges = {
      {{Eigen::Vector2d(0, 0), Eigen::Vector2d(1, 0), Eigen::Vector2d(0, 1)},
       {Eigen::Vector2d(1, 0), Eigen::Vector2d(0, 1), Eigen::Vector2d(0, 0)},
       {Eigen::Vector2d(0, 1), Eigen::Vector2d(0, 0), Eigen::Vector2d(1, 0)}}};
  for (const auto& [A, B, C] : edges) {
    Eigen::Matrix2d J;
    J << B - A, C - A;
    const Eigen::Matrix2d J_inverse = J.inverse();
    for (double beta : {0.1, 0.05}) {
      const double centre_s = 0.5 - 0.5 * beta;
      const double alpha = (1.0 - 1e-9) * std::sqrt(centre_s * centre_s - beta * beta);
      const Eigen::Matrix2d shape_st =
          Eigen::Vector2d(1.0 / (alpha * alpha), 1.0 / (beta * beta)).asDiagonal();
      PatchBump bump;
      bump.center_uv = A + J * Eigen::Vector2d(centre_s, beta * (1.0 + 1e-9));
      bump.shape_uv = J_inverse.transpose() * shape_st * J_inverse;
      bumps.push_back(bump);
    }
  }
  return bumps;
}

double target_height(const ImplicitShape& target, const Eigen::Vector3d& b, const Eigen::Vector3d& n,
                     double limit) {
  // A label volume's values inline: the same values, without a call through the shape.
  if (const TrilinearVolume* volume = target.trilinear_volume())
    return height_search([volume](const Eigen::Vector3d& x) { return volume->value(x); },
                         target.slope_bound(n), b, n, limit);
  return height_search([&target](const Eigen::Vector3d& x) { return target.value(x); }, target.slope_bound(n),
                       b, n, limit);
}

/// target_height from each of `bases`, interleaved (height_searches).
void target_heights(const ImplicitShape& target, const std::vector<Eigen::Vector3d>& bases,
                    const Eigen::Vector3d& n, double limit, std::vector<HeightSearch>& searches,
                    std::vector<std::uint32_t>& running, std::vector<double>& values,
                    std::vector<double>& heights) {
  if (const TrilinearVolume* volume = target.trilinear_volume())
    return height_searches([volume](const Eigen::Vector3d& x) { return volume->value(x); },
                           target.slope_bound(n), bases, n, limit, searches, running, values, heights);
  return height_searches([&target](const Eigen::Vector3d& x) { return target.value(x); },
                         target.slope_bound(n), bases, n, limit, searches, running, values, heights);
}

} // namespace

void match_volume(PatchSurface& surface, double target_volume) {
  // Volume is linear in the amplitudes: raise the first (central) bump of every patch by the
  // same height, which changes the volume by that height times the sum of their disc integrals.
  double per_unit_height = 0.0;
  for (Eigen::Index t = 0; t < surface.patch_count(); ++t) {
    const auto& bumps = surface.bumps(t);
    if (bumps.empty()) continue;
    const TriangleMesh& base = surface.base_mesh();
    const Eigen::Vector3d a = base.vertex(base.faces(t, 0)), b = base.vertex(base.faces(t, 1)),
                          c = base.vertex(base.faces(t, 2));
    per_unit_height += (b - a).cross(c - a).norm() * bumps[0].uv_area() / 4.0;
  }
  if (per_unit_height <= 0.0) return;
  const double raise = (target_volume - surface.volume()) / per_unit_height;
  for (Eigen::Index t = 0; t < surface.patch_count(); ++t) {
    std::vector<PatchBump> bumps = surface.bumps(t);
    if (bumps.empty()) continue;
    bumps[0].amplitude_mm += raise;
    surface.set_bumps(t, bumps);
  }
}

TriangleMesh target_base_mesh(const ImplicitShape& target, int base_triangles,
                              const Eigen::Vector3d& radii_hint, const Eigen::Matrix3d& rotation) {
  TriangleMesh mesh = unit_icosphere(icosphere_level_for(base_triangles));
  for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v) {
    const Eigen::Vector3d direction = (rotation * radii_hint.cwiseProduct(mesh.vertex(v))).normalized();
    mesh.vertices.row(v) = target.ray_from_center(direction).transpose();
  }
  return mesh;
}

TriangleMesh surface_base_mesh(const ImplicitShape& target, int base_triangles, std::uint32_t seed) {
  return extract_surface_of_size(target, base_triangles, seed);
}

TriangleMesh fit_base_mesh(const ImplicitShape& target, const PatchFitOptions& options,
                           const Eigen::Vector3d& radii_hint, const Eigen::Matrix3d& rotation) {
  const bool icosphere = options.base_mesh == BaseMeshSource::icosphere ||
                         (options.base_mesh == BaseMeshSource::automatic && target.star_shaped());
  return icosphere ? target_base_mesh(target, options.base_triangles, radii_hint, rotation)
                   : surface_base_mesh(target, options.base_triangles, options.seed);
}

Eigen::MatrixX3d straddle_vertices(const TriangleMesh& base, const ImplicitShape& target, double factor) {
  Eigen::VectorXd sag_sum = Eigen::VectorXd::Zero(base.vertex_count());
  Eigen::VectorXd count = Eigen::VectorXd::Zero(base.vertex_count());
  const bool radial_depth = target.star_shaped();
  for (Eigen::Index t = 0; t < base.face_count(); ++t) {
    throw_if_cancelled(); // a poll per patch: fits of 10^5 patches take minutes
    for (int k = 0; k < 3; ++k) {
      const int a = base.faces(t, k), b = base.faces(t, (k + 1) % 3);
      if (a > b) continue; // each edge once (its other triangle has it as b > a)
      const Eigen::Vector3d mid = 0.5 * (base.vertex(a) + base.vertex(b));
      double sag = 0.0;
      if (radial_depth) {
        // Depth of the chord midpoint below the surface along the ray from the centre (positive
        // inside); radial, so it stays robust on flat-sided superquadrics.
        const Eigen::Vector3d radial = mid - target.center();
        sag = (target.ray_from_center(radial.normalized()) - target.center()).norm() - radial.norm();
      } else {
        // Along the mean normal of the edge's ends, the nearest crossing within half an edge:
        // the local feature size of a fold bounds how far its other sheet can be.
        const Eigen::Vector3d normal =
            (target.outward_normal(base.vertex(a)) + target.outward_normal(base.vertex(b))).normalized();
        const double h = target_height(target, mid, normal, 0.5 * (base.vertex(b) - base.vertex(a)).norm());
        sag = std::isnan(h) ? 0.0 : h;
      }
      sag_sum[a] += sag, sag_sum[b] += sag;
      count[a] += 1.0, count[b] += 1.0;
    }
  }
  Eigen::MatrixX3d moved = base.vertices;
  for (Eigen::Index v = 0; v < base.vertex_count(); ++v) {
    const Eigen::Vector3d x = base.vertex(v);
    moved.row(v) = (x + factor * sag_sum[v] / std::max(1.0, count[v]) * target.outward_normal(x)).transpose();
  }
  return moved;
}

void fit_bumps(PatchSurface& surface, const ImplicitShape& target, const PatchFitOptions& options) {
  const TriangleMesh& base = surface.base_mesh();
  const int n = 1 << options.sample_level;
  // Work space of each patch's samples, kept from one patch to the next.
  std::vector<Eigen::Vector2d> uv;
  std::vector<double> heights;
  std::vector<int> sample_of, bump_count;
  std::vector<Eigen::Index> bumps_at;
  std::vector<std::pair<Eigen::Index, double>> row;
  std::vector<char> in_column(static_cast<std::size_t>(n)), in_row(static_cast<std::size_t>(n));
  // The grid's interior points, their searches and heights (NaN: no target found).
  std::vector<Eigen::Vector3d> grid_bases;
  std::vector<double> grid_values, grid_heights;
  std::vector<HeightSearch> searches;
  std::vector<std::uint32_t> running;
  for (Eigen::Index t = 0; t < surface.patch_count(); ++t) {
    throw_if_cancelled();
    const PatchFrame frame = surface.frame(t);
    const Eigen::Vector3d x0 = surface.rest_positions().row(base.faces(t, 0)).transpose();
    const Eigen::Vector3d x1 = surface.rest_positions().row(base.faces(t, 1)).transpose();
    const Eigen::Vector3d x2 = surface.rest_positions().row(base.faces(t, 2)).transpose();
    std::vector<PatchBump> bumps = basis_bumps(x0, x1, x2, options.bump_levels);
    // The samples on the grid's interior points (i, j) / n, those whose search found the target;
    // `sample_of` numbers them by grid point (-1: none there).
    grid_bases.clear();
    for (int j = 1; j < n; ++j) {
      for (int i = 1; i + j < n; ++i) {
        const double u = double(i) / n, v = double(j) / n;
        grid_bases.emplace_back(frame.origin + u * frame.edge1 + v * frame.edge2);
      }
    }
    target_heights(target, grid_bases, frame.normal, frame.length_scale, searches, running, grid_values,
                   grid_heights);
    uv.clear();
    heights.clear();
    sample_of.assign(static_cast<std::size_t>(n * n), -1);
    for (int j = 1, g = 0; j < n; ++j) {
      for (int i = 1; i + j < n; ++i, ++g) {
        const double h = grid_heights[static_cast<std::size_t>(g)];
        if (std::isnan(h)) continue;
        sample_of[static_cast<std::size_t>(j * n + i)] = static_cast<int>(uv.size());
        uv.emplace_back(double(i) / n, double(j) / n);
        heights.push_back(h);
      }
    }
    const Eigen::Index m = static_cast<Eigen::Index>(uv.size()), k = static_cast<Eigen::Index>(bumps.size());
    if (m == 0) continue;
    // Bumps do not depend on w, so a unit bump's height at (u, v) is max(Q, 0)^3. A sample lies
    // in the support of a few bumps only (the level-2 incircles cover a sixteenth of the patch
    // each), so the normal equations A^T A a = A^T b are summed over each sample's bumps: a
    // twentieth of the products of the dense A^T A, every sum in sample order.
    // A sample outside a bump's support box (widened by a thousandth) has Q < -0.002 however
    // it is rounded: its Q is not computed. Each bump lists the samples in its box (the grid's
    // rows and columns the box holds, by the same comparisons of the same coordinates), so each
    // sample meets its few bumps in bump order instead of testing every bump's box.
    // Sample r's bumps: bumps_at[r * k ...], bump_count[r] of them.
    bumps_at.resize(static_cast<std::size_t>(m * k));
    bump_count.assign(static_cast<std::size_t>(m), 0);
    for (Eigen::Index c = 0; c < k; ++c) {
      const PatchBump& b = bumps[static_cast<std::size_t>(c)];
      const Eigen::Matrix2d S = 0.5 * (b.shape_uv + b.shape_uv.transpose());
      const double det = S.determinant();
      const Eigen::Vector2d half =
          1.001 * Eigen::Vector2d(std::sqrt(S(1, 1) / det), std::sqrt(S(0, 0) / det));
      const double u_low = b.center_uv.x() - half.x(), u_high = b.center_uv.x() + half.x();
      const double v_low = b.center_uv.y() - half.y(), v_high = b.center_uv.y() + half.y();
      for (int i = 1; i < n; ++i) {
        const double u = double(i) / n;
        in_column[static_cast<std::size_t>(i)] = !(u < u_low || u > u_high);
        in_row[static_cast<std::size_t>(i)] = !(u < v_low || u > v_high);
      }
      for (int j = 1; j < n; ++j) {
        if (!in_row[static_cast<std::size_t>(j)]) continue;
        for (int i = 1; i + j < n; ++i) {
          const int r = sample_of[static_cast<std::size_t>(j * n + i)];
          if (r < 0 || !in_column[static_cast<std::size_t>(i)]) continue;
          bumps_at[static_cast<std::size_t>(r * k + bump_count[static_cast<std::size_t>(r)]++)] = c;
        }
      }
    }
    Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(k, k);
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(k);
    for (Eigen::Index r = 0; r < m; ++r) {
      row.clear();
      const Eigen::Vector2d& at = uv[static_cast<std::size_t>(r)];
      for (int b = 0; b < bump_count[static_cast<std::size_t>(r)]; ++b) {
        const Eigen::Index c = bumps_at[static_cast<std::size_t>(r * k + b)];
        const double q = bumps[static_cast<std::size_t>(c)].shape_value(at);
        if (q > 0.0) row.emplace_back(c, q * q * q);
      }
      const double height = heights[static_cast<std::size_t>(r)];
      for (const auto& [c1, a1] : row) {
        rhs[c1] += a1 * height;
        for (const auto& [c2, a2] : row)
          if (c2 <= c1) normal(c1, c2) += a1 * a2;
      }
    }
    normal.triangularView<Eigen::StrictlyUpper>() = normal.transpose();
    const double lambda = options.regularization * std::max(1e-300, normal.diagonal().mean());
    normal.diagonal().array() += lambda;
    const Eigen::VectorXd amplitudes = normal.ldlt().solve(rhs);
    // Off star shapes a coarse patch over a fold may see another sheet within its search
    // distance; amplitudes beyond half the patch's size are such misreadings, and the flat patch
    // is the better surface (the volume correction still applies to its neighbours).
    if (!target.star_shaped() && amplitudes.cwiseAbs().maxCoeff() > 0.5 * frame.length_scale) continue;
    for (Eigen::Index c = 0; c < k; ++c)
      bumps[static_cast<std::size_t>(c)].amplitude_mm = amplitudes[c];
    surface.set_bumps(t, bumps);
  }
}

PatchSurface fit_patch_surface(const ImplicitShape& target, const Eigen::Vector3d& radii_hint,
                               const Eigen::Matrix3d& rotation, const PatchFitOptions& options,
                               const std::string& what, PatchFitReport* report) {
  const TriangleMesh on_target = fit_base_mesh(target, options, radii_hint, rotation);
  TriangleMesh base = on_target;
  if (options.vertex_offset_factor != 0.0) {
    base.vertices = straddle_vertices(on_target, target, options.vertex_offset_factor);
  }
  PatchSurface surface(base, what);
  fit_bumps(surface, target, options);
  if (options.match_volume) match_volume(surface, target.volume());
  if (report) {
    // Star shapes: within a thousandth of the size, on an icosphere of level 6. Others: the
    // extracted surface of level 5's size, tessellated within a tenth of edge^2 / size (a
    // fixed fraction of the chord sag, so the cost stays proportional to the patch count).
    const double edge = mean_edge_length(surface.base_mesh()), size = target.bounding_radius();
    *report = target.star_shaped() ? measure_fit(surface, target, 1e-3 * size)
                                   : measure_fit(surface, target, 0.1 * edge * edge / size, 5);
    report->vertex_offset_factor = options.vertex_offset_factor;
  }
  return surface;
}

namespace {

/// A distance of each exact surface point on every patch's grid of `level` (2^level segments per
/// edge), patch by patch. In parallel over patches, each into its own slots: the same numbers in
/// the same order.
template <class Distance>
std::vector<double> surface_point_distances(const PatchSurface& surface, int level,
                                            const Distance& distance) {
  const Eigen::Index patches = surface.patch_count();
  const std::size_t segments = std::size_t{1} << level;
  const std::size_t per_patch = (segments + 1) * (segments + 2) / 2;
  std::vector<double> out(static_cast<std::size_t>(patches) * per_patch);
#pragma omp parallel for schedule(dynamic, 16)
  for (Eigen::Index t = 0; t < patches; ++t) {
    if (cancellation_requested()) continue; // no exception may leave an OpenMP region
    const std::vector<Eigen::Vector3d> points = surface.patch_grid_points(t, level);
    for (std::size_t k = 0; k < per_patch; ++k)
      out[static_cast<std::size_t>(t) * per_patch + k] = distance(points[k]);
  }
  throw_if_cancelled();
  return out;
}

} // namespace

SourceFit measure_source_fit(const PatchSurface& surface, const ImplicitShape& target,
                             int surface_sample_level) {
  SourceFit fit;
  fit.base_triangles = static_cast<int>(surface.patch_count());
  const TargetBoundary boundary(target);
  std::vector<double> to_source =
      surface_point_distances(surface, std::clamp(surface_sample_level, 0, 8),
                              [&](const Eigen::Vector3d& x) { return boundary.distance(x); });
  if (!to_source.empty()) {
    double sum = 0.0;
    for (double v : to_source)
      sum += v;
    fit.source_mean_mm = sum / static_cast<double>(to_source.size());
    const auto p95 = to_source.begin() + static_cast<std::ptrdiff_t>(0.95 * double(to_source.size() - 1));
    std::nth_element(to_source.begin(), p95, to_source.end());
    fit.source_p95_mm = *p95;
    fit.source_max_mm = *std::max_element(p95, to_source.end());
  }
  fit.volume_error = (surface.volume() - target.volume()) / target.volume();
  return fit;
}

PatchFitReport measure_fit(const PatchSurface& surface, const ImplicitShape& target, double tessellation_mm,
                           int target_sample_level, int surface_sample_level) {
  PatchFitReport report;
  static_cast<SourceFit&>(report) = measure_source_fit(surface, target, surface_sample_level);
  // The target as a dense mesh with vertices on it: an icosphere of target_sample_level cast
  // onto it from its centre, or, when rays from the centre may cross it more than once, its
  // extracted surface of as many triangles.
  TriangleMesh target_mesh;
  std::vector<Eigen::Vector3d> samples;
  if (target.star_shaped()) {
    target_mesh = unit_icosphere(target_sample_level);
    for (Eigen::Index v = 0; v < target_mesh.vertex_count(); ++v) {
      samples.push_back(target.ray_from_center(target_mesh.vertex(v)));
      target_mesh.vertices.row(v) = samples.back().transpose();
    }
  } else {
    target_mesh = extract_surface_of_size(target, 20 * (1 << (2 * target_sample_level)), 0);
    for (Eigen::Index v = 0; v < target_mesh.vertex_count(); ++v)
      samples.push_back(target_mesh.vertex(v));
  }
  // Surface to target: the same surface points as the source figures; target to surface:
  // distances to a tessellation within tessellation_mm.
  const MeshDistance to_target_mesh(target_mesh);
  const std::vector<double> to_target =
      surface_point_distances(surface, std::clamp(surface_sample_level, 0, 8),
                              [&](const Eigen::Vector3d& x) { return to_target_mesh.distance(x); });
  const TriangleMesh tessellation = surface.tessellate(tessellation_mm);
  throw_if_cancelled(); // a cancelled tessellation is empty
  const SurfaceDistance d = symmetric_distance(tessellation, samples, to_target);
  report.hausdorff_mm = d.hausdorff_mm;
  report.mean_distance_mm = d.mean_mm;
  return report;
}

TargetBoundary::TargetBoundary(const ImplicitShape& target, double spacing_mm) {
  const double radius = target.bounding_radius();
  m_spacing = spacing_mm > 0.0 ? spacing_mm : std::max(std::min(1.0, radius / 32.0), radius / 200.0);
  // The lattice covers the target's box (its half extents, a cube of its bounding radius for most
  // shapes): an elongated superquadric's box holds a quarter of its bounding cube's points, and
  // the lattice's values, a pow() or more each, are most of the measure's time.
  const Eigen::Vector3d half = 1.05 * target.half_extents() + Eigen::Vector3d::Constant(m_spacing);
  const Eigen::Vector3i n = ((2.0 * half / m_spacing).array().ceil().cast<int>() + 1).matrix();
  const Eigen::Vector3d low = target.center() - half;
  const auto at = [&](int i, int j, int k) -> Eigen::Vector3d {
    return low + m_spacing * Eigen::Vector3d(i, j, k);
  };
  // The crossing on the edge a-b (values fa, fb of opposite signs): false position with the
  // Illinois step, to 1e-4 of the spacing.
  const auto crossing = [&](Eigen::Vector3d a, Eigen::Vector3d b, double fa, double fb) {
    Eigen::Vector3d x = a;
    int side = 0;
    for (int iteration = 0; iteration < 40; ++iteration) {
      const double t = fa / (fa - fb);
      x = a + t * (b - a);
      const double fx = target.value(x);
      if (fx == 0.0 || (b - a).norm() < 1e-4 * m_spacing) break;
      if ((fx > 0.0) == (fa > 0.0)) {
        a = x;
        fa = fx;
        if (side == -1) fb *= 0.5;
        side = -1;
      } else {
        b = x;
        fb = fx;
        if (side == 1) fa *= 0.5;
        side = 1;
      }
      if (std::abs(fx) < 1e-12) break;
    }
    return x;
  };
  // The lattice's points past the target's solid box, and the first beyond it, are all outside
  // (value <= 0): no edge among them crosses the surface, so only the range from the last point
  // before the box to the first after it is evaluated (the same crossings in the same order).
  const Eigen::AlignedBox3d solid = target.solid_box();
  Eigen::Vector3i first = Eigen::Vector3i::Zero(), last = n - Eigen::Vector3i::Ones();
  for (int a = 0; a < 3; ++a) {
    const double from = std::floor((solid.min()[a] - low[a]) / m_spacing) - 1.0;
    const double to = std::ceil((solid.max()[a] - low[a]) / m_spacing) + 1.0;
    if (from > first[a]) first[a] = from < last[a] ? static_cast<int>(from) : last[a];
    if (to < last[a]) last[a] = to > first[a] ? static_cast<int>(to) : first[a];
  }
  // Layer by layer (two in memory), each layer's values in parallel over its rows.
  const int nx = n.x(), ny = n.y();
  const auto row = [nx](int i, int j) {
    return static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) + i;
  };
  std::vector<double> below(static_cast<std::size_t>(nx) * ny), layer(below.size());
  const auto fill = [&](std::vector<double>& values, int k) {
#pragma omp parallel for schedule(static)
    for (int j = first.y(); j <= last.y(); ++j)
      for (int i = first.x(); i <= last.x(); ++i)
        values[row(i, j)] = target.value(at(i, j, k));
  };
  const auto inside = [](double f) { return f > 0.0; };
  for (int k = first.z(); k <= last.z(); ++k) {
    throw_if_cancelled();
    fill(layer, k);
    for (int j = first.y(); j <= last.y(); ++j)
      for (int i = first.x(); i <= last.x(); ++i) {
        const double f = layer[row(i, j)];
        if (i + 1 <= last.x() && inside(f) != inside(layer[row(i + 1, j)]))
          m_points.push_back(crossing(at(i, j, k), at(i + 1, j, k), f, layer[row(i + 1, j)]));
        if (j + 1 <= last.y() && inside(f) != inside(layer[row(i, j + 1)]))
          m_points.push_back(crossing(at(i, j, k), at(i, j + 1, k), f, layer[row(i, j + 1)]));
        if (k > first.z() && inside(f) != inside(below[row(i, j)]))
          m_points.push_back(crossing(at(i, j, k), at(i, j, k - 1), f, below[row(i, j)]));
      }
    std::swap(below, layer);
  }
  m_normals.resize(m_points.size());
#pragma omp parallel for schedule(static)
  for (std::int64_t p = 0; p < static_cast<std::int64_t>(m_points.size()); ++p) {
    const Eigen::Vector3d g = target.gradient(m_points[static_cast<std::size_t>(p)]);
    m_normals[static_cast<std::size_t>(p)] =
        g.norm() > 0.0 ? Eigen::Vector3d(-g.normalized()) : Eigen::Vector3d::Zero();
  }
  // A hash grid of cells of two spacings over the lattice's box.
  m_cell = 2.0 * m_spacing;
  m_origin = low;
  m_cells = ((2.0 * half / m_cell).array().ceil().cast<int>() + 1).matrix();
  const auto cell_of = [&](const Eigen::Vector3d& x) -> Eigen::Vector3i {
    const Eigen::Vector3i c = ((x - m_origin) / m_cell).array().floor().cast<int>().matrix();
    return c.cwiseMax(Eigen::Vector3i::Zero()).cwiseMin(m_cells - Eigen::Vector3i::Ones());
  };
  const auto flat = [&](const Eigen::Vector3i& c) {
    return static_cast<std::size_t>((std::int64_t{c.z()} * m_cells.y() + c.y()) * m_cells.x() + c.x());
  };
  m_first.assign(static_cast<std::size_t>(m_cells.cast<std::int64_t>().prod()) + 1, 0);
  for (const Eigen::Vector3d& x : m_points)
    ++m_first[flat(cell_of(x)) + 1];
  for (std::size_t c = 1; c < m_first.size(); ++c)
    m_first[c] += m_first[c - 1];
  m_order.resize(m_points.size());
  std::vector<std::uint32_t> next(m_first.begin(), m_first.end() - 1);
  for (std::size_t p = 0; p < m_points.size(); ++p)
    m_order[next[flat(cell_of(m_points[p]))]++] = static_cast<std::uint32_t>(p);
}

double TargetBoundary::distance(const Eigen::Vector3d& x) const {
  if (m_points.empty()) return std::numeric_limits<double>::infinity();
  const Eigen::Vector3i c = ((x - m_origin) / m_cell).array().floor().cast<int>().matrix();
  // Rings of cells around x's cell until the ring's distance exceeds the best so far.
  double best = std::numeric_limits<double>::infinity();
  std::size_t nearest = 0;
  const int largest = m_cells.maxCoeff();
  for (int ring = 0; ring <= largest + std::abs(c.x()) + std::abs(c.y()) + std::abs(c.z()); ++ring) {
    if ((ring - 1) * m_cell > best) break;
    for (int dz = -ring; dz <= ring; ++dz)
      for (int dy = -ring; dy <= ring; ++dy)
        for (int dx = -ring; dx <= ring; ++dx) {
          if (std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) != ring) continue;
          const Eigen::Vector3i at = c + Eigen::Vector3i(dx, dy, dz);
          if ((at.array() < 0).any() || (at.array() >= m_cells.array()).any()) continue;
          const std::size_t cell =
              static_cast<std::size_t>((std::int64_t{at.z()} * m_cells.y() + at.y()) * m_cells.x() + at.x());
          for (std::uint32_t k = m_first[cell]; k < m_first[cell + 1]; ++k) {
            const double d = (m_points[m_order[k]] - x).norm();
            if (d < best || (d == best && m_order[k] < nearest)) {
              best = d;
              nearest = m_order[k];
            }
          }
        }
  }
  // Near the boundary, the distance to the tangent plane at the nearest crossing (the boundary
  // curves between crossings a spacing apart); farther out, the distance to that point.
  const Eigen::Vector3d offset = x - m_points[nearest];
  const double along = std::abs(offset.dot(m_normals[nearest]));
  const double across2 = std::max(0.0, offset.squaredNorm() - along * along);
  return across2 <= 2.25 * m_spacing * m_spacing && m_normals[nearest].squaredNorm() > 0.0 ? along : best;
}

int surface_sample_level_for_spacing(const PatchSurface& surface, double spacing_mm) {
  const double edge = mean_edge_length(surface.base_mesh());
  int level = 1;
  while (level < 4 && edge / static_cast<double>(1 << level) > spacing_mm)
    ++level;
  return level;
}

} // namespace phantasm
