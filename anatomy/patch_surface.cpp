#include "anatomy/patch_surface.hpp"

#include "core/error.hpp"

#include <Eigen/Geometry>
#include <Eigen/LU>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>

namespace phantasm {

double Quadric::value(const Eigen::Vector3d& p) const {
  const double u = p.x(), v = p.y(), w = p.z();
  return c[0] + c[1] * u + c[2] * v + c[3] * w + c[4] * u * u + c[5] * u * v + c[6] * v * v + c[7] * u * w +
         c[8] * v * w + c[9] * w * w;
}

Eigen::Vector3d Quadric::gradient(const Eigen::Vector3d& p) const {
  const double u = p.x(), v = p.y(), w = p.z();
  return {c[1] + 2.0 * c[4] * u + c[5] * v + c[7] * w, c[2] + c[5] * u + 2.0 * c[6] * v + c[8] * w,
          c[3] + c[7] * u + c[8] * v + 2.0 * c[9] * w};
}

PatchBump PatchBump::disc(const Eigen::Vector2d& center_uv, double radius_mm,
                          const Eigen::Matrix2d& rest_metric) {
  PatchBump bump;
  bump.center_uv = center_uv;
  bump.shape_uv = rest_metric / (radius_mm * radius_mm);
  return bump;
}

Quadric PatchBump::quadric() const {
  const double s11 = shape_uv(0, 0), s12 = 0.5 * (shape_uv(0, 1) + shape_uv(1, 0)), s22 = shape_uv(1, 1);
  const double cu = center_uv.x(), cv = center_uv.y();
  Quadric q;
  q.c[0] = 1.0 - (s11 * cu * cu + 2.0 * s12 * cu * cv + s22 * cv * cv);
  q.c[1] = 2.0 * (s11 * cu + s12 * cv);
  q.c[2] = 2.0 * (s22 * cv + s12 * cu);
  q.c[4] = -s11;
  q.c[5] = -2.0 * s12;
  q.c[6] = -s22;
  return q;
}

double PatchBump::uv_area() const {
  return M_PI / std::sqrt(shape_uv.determinant());
}

namespace {

/// Adds one bump's bounds a Q^3 [Q > 0] over a row of sub-triangles: for each i < count, the
/// sub-triangle with corner values q0[i], q1[i], q2[i] (Q at its corners) gets a times the cube
/// of its least corner value (lower) and of its largest plus `slack`, at most 1 (upper), each
/// taken where positive; the other way round for a < 0. Branch-free per element (the same
/// operations as one sub-triangle at a time, so the same sums).
void add_row_bounds(double a, double slack, const double* q0, const double* q1, const double* q2, int count,
                    double* lower, double* upper) {
  // max(x, 0)^3 rather than a branch: where x <= 0 it adds a zero either way (a sum that starts
  // at +0 and only grows by these is never -0, so adding -0 changes no bit).
  const auto cube_of_positive = [](double x) {
    const double p = std::max(x, 0.0);
    return p * p * p;
  };
  // a > 0: the least corner bounds from below; a < 0: from above.
  double* __restrict by_least = a > 0.0 ? lower : upper;
  double* __restrict by_largest = a > 0.0 ? upper : lower;
  for (int i = 0; i < count; ++i) {
    const double q_low = std::min(std::min(q0[i], q1[i]), q2[i]);
    const double q_high = std::min(1.0, std::max(std::max(q0[i], q1[i]), q2[i]) + slack);
    by_least[i] += a * cube_of_positive(q_low);
    by_largest[i] += a * cube_of_positive(q_high);
  }
}

} // namespace

HeightRange patch_height_range(const std::vector<PatchBump>& bumps) {
  // The triangle is cut into n^2 similar sub-triangles, two per cell of the lattice (a, b) / n.
  // Over a triangle with corners p_j and barycentric weights l_j, a quadratic with Hessian H
  // satisfies f(sum l_j p_j) = sum l_j f(p_j) - 1/2 sum_{j<k} l_j l_k (p_j - p_k)^T H (p_j - p_k);
  // for Q = 1 - d^T S d, H = -2 S and sum_{j<k} l_j l_k <= 1/3, so on a sub-triangle
  // min_j Q(p_j) <= Q <= max_j Q(p_j) + E / 3, E the largest edge's e^T S e (every sub-triangle
  // has the same three edges). Each bump's share a Q^3 [Q > 0] is bounded from the corners, and
  // only on the cells its support's bounding box meets: elsewhere it is 0.
  // Cell (i, j) holds two sub-triangles: the first with corners (i, j), (i + 1, j), (i, j + 1),
  // the second (when i + j + 2 <= n) with (i + 1, j), (i, j + 1), (i + 1, j + 1); their bounds
  // are kept in arrays of their own, at j n + i.
  constexpr int n = 32;
  thread_local std::vector<double> upper, lower, upper2, lower2, q_grid;
  for (std::vector<double>* sums : {&upper, &lower, &upper2, &lower2})
    sums->assign(n * n, 0.0);
  const double step = 1.0 / n;
  const Eigen::Vector2d edges[3] = {{step, 0.0}, {0.0, step}, {step, -step}};
  for (const PatchBump& bump : bumps) {
    const Eigen::Matrix2d S = 0.5 * (bump.shape_uv + bump.shape_uv.transpose());
    const double a = bump.amplitude_mm;
    if (a == 0.0) continue;
    double widest = 0.0;
    for (const Eigen::Vector2d& e : edges)
      widest = std::max(widest, e.dot(S * e));
    const double slack = widest / 3.0;
    // The support {d^T S d < 1} lies within c +- (sqrt((S^-1)_uu), sqrt((S^-1)_vv)).
    const double det = S.determinant();
    const Eigen::Vector2d half(std::sqrt(S(1, 1) / det), std::sqrt(S(0, 0) / det));
    const auto cell = [](double x) { return static_cast<int>(std::clamp(std::floor(x * n), 0.0, n - 1.0)); };
    const int a_first = cell(bump.center_uv.x() - half.x()), a_last = cell(bump.center_uv.x() + half.x());
    const int b_first = cell(bump.center_uv.y() - half.y()), b_last = cell(bump.center_uv.y() + half.y());
    // Q at the lattice points of the box, each computed once (a point is a corner of up to six
    // sub-triangles): row j - b_first, column i - a_first, one more of each for the far corners.
    const int columns = a_last - a_first + 2;
    q_grid.resize(static_cast<std::size_t>(columns * (b_last - b_first + 2)));
    for (int j = b_first; j <= b_last + 1; ++j) {
      for (int i = a_first; i <= a_last + 1; ++i) {
        const Eigen::Vector2d d = step * Eigen::Vector2d(i, j) - bump.center_uv;
        q_grid[static_cast<std::size_t>((j - b_first) * columns + (i - a_first))] = 1.0 - d.dot(S * d);
      }
    }
    for (int j = b_first; j <= b_last; ++j) {
      // The row's cells within the triangle (i + j < n), and those holding a second sub-triangle.
      const int first_count = std::min(a_last, n - 1 - j) - a_first + 1;
      const int second_count = std::min(a_last, n - 2 - j) - a_first + 1;
      if (first_count <= 0) continue;
      const double* row = q_grid.data() + (j - b_first) * columns;
      const double* next_row = row + columns;
      const std::size_t at = static_cast<std::size_t>(j * n + a_first);
      add_row_bounds(a, slack, row, row + 1, next_row, first_count, lower.data() + at, upper.data() + at);
      if (second_count > 0)
        add_row_bounds(a, slack, row + 1, next_row, next_row + 1, second_count, lower2.data() + at,
                       upper2.data() + at);
    }
  }
  HeightRange range;
  for (const std::vector<double>* sums : {&upper, &upper2})
    for (const double value : *sums)
      range.highest = std::max(range.highest, value);
  for (const std::vector<double>* sums : {&lower, &lower2})
    for (const double value : *sums)
      range.lowest = std::min(range.lowest, value);
  // Rounding of the sums above: a margin far below any voxel.
  double total = 0.0;
  for (const PatchBump& bump : bumps)
    total += std::abs(bump.amplitude_mm);
  range.lowest -= 1e-12 * total;
  range.highest += 1e-12 * total;
  return range;
}

std::vector<HeightRange> patch_height_ranges(const PatchSurface& surface) {
  std::vector<HeightRange> ranges(static_cast<std::size_t>(surface.patch_count()));
  // Each patch its own: in parallel (an organ of 50 000 patches takes about two seconds).
#pragma omp parallel for schedule(dynamic, 256)
  for (Eigen::Index t = 0; t < surface.patch_count(); ++t)
    ranges[static_cast<std::size_t>(t)] = patch_height_range(surface.bumps(t));
  return ranges;
}

namespace {

Eigen::Vector3d corner(const TriangleMesh& mesh, Eigen::Index t, int k) {
  return mesh.vertex(mesh.faces(t, k));
}

} // namespace

PatchSurface::PatchSurface(TriangleMesh base, const std::string& what)
    : m_what(what), m_base(std::move(base)) {
  check_closed_manifold(m_base, what);
  m_rest = m_base.vertices;
  const Eigen::Index n = m_base.face_count();
  m_rest_triangles.resize(static_cast<std::size_t>(n));
  m_bumps.assign(static_cast<std::size_t>(n), {});
  m_perturbations.assign(static_cast<std::size_t>(n), {});
  m_lattices.assign(static_cast<std::size_t>(n), BumpLattice());
  std::map<std::pair<int, int>, std::pair<Eigen::Index, int>> directed;
  for (Eigen::Index t = 0; t < n; ++t) {
    const Eigen::Vector3d x0 = corner(m_base, t, 0), e1 = corner(m_base, t, 1) - x0,
                          e2 = corner(m_base, t, 2) - x0;
    RestTriangle& rest = m_rest_triangles[static_cast<std::size_t>(t)];
    rest.metric << e1.dot(e1), e1.dot(e2), e1.dot(e2), e2.dot(e2);
    rest.area = 0.5 * e1.cross(e2).norm();
    rest.length_scale = (e1.norm() + e2.norm() + (e2 - e1).norm()) / 3.0;
    for (int k = 0; k < 3; ++k)
      directed[{m_base.faces(t, k), m_base.faces(t, (k + 1) % 3)}] = {t, k};
  }
  m_neighbours.resize(n, 3);
  for (Eigen::Index t = 0; t < n; ++t) {
    for (int k = 0; k < 3; ++k) {
      m_neighbours(t, k) =
          static_cast<int>(directed.at({m_base.faces(t, (k + 1) % 3), m_base.faces(t, k)}).first);
    }
  }
}

void PatchSurface::set_bumps(Eigen::Index t, std::vector<PatchBump> bumps) {
  std::vector<Perturbation> perturbations = checked_perturbations(t, bumps);
  m_lattices[static_cast<std::size_t>(t)] = BumpLattice(bumps);
  m_bumps[static_cast<std::size_t>(t)] = std::move(bumps);
  m_perturbations[static_cast<std::size_t>(t)] = std::move(perturbations);
  m_height_ranges.reset();
}

void PatchSurface::set_all_bumps(std::vector<std::vector<PatchBump>> bumps) {
  if (static_cast<Eigen::Index>(bumps.size()) != patch_count())
    throw std::invalid_argument("set_all_bumps: " + std::to_string(bumps.size()) + " lists of bumps for " +
                                std::to_string(patch_count()) + " patches");
  const auto count = static_cast<std::ptrdiff_t>(bumps.size());
  std::vector<std::vector<Perturbation>> perturbations(bumps.size());
  std::vector<BumpLattice> lattices(bumps.size());
  // No exception may leave an OpenMP region: each patch's message is kept, the first thrown.
  std::vector<std::string> errors(bumps.size());
#pragma omp parallel for schedule(dynamic, 256)
  for (std::ptrdiff_t t = 0; t < count; ++t) {
    const auto k = static_cast<std::size_t>(t);
    if (bumps[k].empty()) continue; // as a new surface's patch
    try {
      perturbations[k] = checked_perturbations(t, bumps[k]);
      lattices[k] = BumpLattice(bumps[k]);
    } catch (const InputError& error) {
      errors[k] = error.what();
    }
  }
  for (const std::string& error : errors)
    if (!error.empty()) throw InputError(error);
  m_lattices = std::move(lattices);
  m_bumps = std::move(bumps);
  m_perturbations = std::move(perturbations);
  m_height_ranges.reset();
}

std::vector<PatchSurface::Perturbation>
PatchSurface::checked_perturbations(Eigen::Index t, const std::vector<PatchBump>& bumps) const {
  std::vector<Perturbation> perturbations;
  perturbations.reserve(bumps.size());
  for (std::size_t i = 0; i < bumps.size(); ++i) {
    const PatchBump& b = bumps[i];
    const auto where = [&] {
      return m_what + ": triangle " + std::to_string(t) + ", bump " + std::to_string(i);
    };
    const Eigen::Matrix2d S = 0.5 * (b.shape_uv + b.shape_uv.transpose());
    if (!std::isfinite(b.amplitude_mm) || !(S(0, 0) > 0.0) || !(S.determinant() > 0.0) || !S.allFinite()) {
      throw InputError(where() + ": expected a positive definite shape and a finite amplitude");
    }
    if (!b.center_uv.allFinite()) {
      throw InputError(where() + ": expected a finite centre, found (" + std::to_string(b.center_uv.x()) +
                       ", " + std::to_string(b.center_uv.y()) + ")");
    }
    // The ellipse {d^T S d <= 1} around c lies inside u >= 0, v >= 0, u + v <= 1 when each
    // linear function g . p stays on the inner side at its extreme, g . c -+ sqrt(g^T S^-1 g).
    const Eigen::Matrix2d inverse = S.inverse();
    const Eigen::Vector2d c = b.center_uv;
    const double slack = 1e-12;
    if (c.x() - std::sqrt(inverse(0, 0)) < -slack || c.y() - std::sqrt(inverse(1, 1)) < -slack ||
        1.0 - c.sum() - std::sqrt(inverse.sum()) < -slack) {
      throw InputError(where() + ": expected its ellipse inside the triangle, found it crossing an edge");
    }
    perturbations.push_back({b.quadric(), b.amplitude_mm});
  }
  return perturbations;
}

void PatchSurface::hold_height_ranges() {
  m_height_ranges = patch_height_ranges(*this);
}

void PatchSurface::set_height_ranges(std::vector<HeightRange> ranges) {
  if (ranges.size() != static_cast<std::size_t>(patch_count())) {
    throw InputError(m_what + ": expected " + std::to_string(patch_count()) + " patch height bounds, found " +
                     std::to_string(ranges.size()));
  }
  for (std::size_t t = 0; t < ranges.size(); ++t) {
    if (!std::isfinite(ranges[t].lowest) || !std::isfinite(ranges[t].highest) ||
        !(ranges[t].lowest <= ranges[t].highest)) {
      throw InputError(m_what + ": triangle " + std::to_string(t) +
                       ": expected finite height bounds, lowest <= highest, found " +
                       std::to_string(ranges[t].lowest) + " and " + std::to_string(ranges[t].highest));
    }
  }
  m_height_ranges = std::move(ranges);
}

void PatchSurface::set_positions(const Eigen::MatrixX3d& positions) {
  if (positions.rows() != m_base.vertex_count()) {
    throw InputError(m_what + ": expected " + std::to_string(m_base.vertex_count()) +
                     " vertex positions, found " + std::to_string(positions.rows()));
  }
  m_base.vertices = positions;
}

PatchFrame PatchSurface::frame(Eigen::Index t) const {
  PatchFrame f;
  f.origin = corner(m_base, t, 0);
  f.edge1 = corner(m_base, t, 1) - f.origin;
  f.edge2 = corner(m_base, t, 2) - f.origin;
  f.normal = f.edge1.cross(f.edge2).normalized();
  f.length_scale = m_rest_triangles[static_cast<std::size_t>(t)].length_scale;
  Eigen::Matrix3d world_from_local;
  world_from_local << f.edge1, f.edge2, f.length_scale * f.normal;
  f.local_from_world = world_from_local.inverse();
  return f;
}

Eigen::Vector3d PatchSurface::local_coordinates(Eigen::Index t, const Eigen::Vector3d& x) const {
  const PatchFrame f = frame(t);
  return f.local_from_world * (x - f.origin);
}

double PatchSurface::value(Eigen::Index t, const Eigen::Vector3d& x) const {
  const PatchFrame f = frame(t);
  const Eigen::Vector3d uvw = f.local_from_world * (x - f.origin);
  double F = -f.length_scale * uvw.z();
  const auto& perturbations = m_perturbations[static_cast<std::size_t>(t)];
  for (const std::uint32_t n : m_lattices[static_cast<std::size_t>(t)].at(uvw.x(), uvw.y())) {
    const Perturbation& p = perturbations[n];
    const double q = p.quadric.value(uvw);
    if (q > 0.0) F += p.amplitude_mm * q * q * q;
  }
  return F;
}

Eigen::Vector3d PatchSurface::gradient(Eigen::Index t, const Eigen::Vector3d& x) const {
  const PatchFrame f = frame(t);
  const Eigen::Vector3d uvw = f.local_from_world * (x - f.origin);
  Eigen::Vector3d d_local(0.0, 0.0, -f.length_scale);
  const auto& perturbations = m_perturbations[static_cast<std::size_t>(t)];
  for (const std::uint32_t n : m_lattices[static_cast<std::size_t>(t)].at(uvw.x(), uvw.y())) {
    const Perturbation& p = perturbations[n];
    const double q = p.quadric.value(uvw);
    if (q > 0.0) d_local += 3.0 * p.amplitude_mm * q * q * p.quadric.gradient(uvw);
  }
  return f.local_from_world.transpose() * d_local;
}

double PatchSurface::height(Eigen::Index t, double u, double v) const {
  const auto& perturbations = m_perturbations[static_cast<std::size_t>(t)];
  if (perturbations.empty()) return 0.0;
  // frame()'s length scale, without its inverse (the tessellation asks for millions of heights).
  const double L = m_rest_triangles[static_cast<std::size_t>(t)].length_scale;
  // g(h) = F(b + h n) = -h + sum a Q(u, v)^3 over the bumps with Q > 0. A bump's quadric has no
  // w terms (PatchBump::quadric), so its Q at (u, v, h / L) is its Q at (u, v, 0) (up to the sign
  // of a zero, which counts as outside either way) and g's slope is -1: each term is computed
  // once, and g at any h sums the same terms, in the same order, after -h.
  const BumpLattice::Bumps near = m_lattices[static_cast<std::size_t>(t)].at(u, v);
  constexpr std::size_t k_held = 64;
  std::array<double, k_held> held;
  std::vector<double> more;
  std::size_t count = 0;
  const Eigen::Vector3d uv0(u, v, 0.0);
  for (const std::uint32_t n : near) {
    const Perturbation& p = perturbations[n];
    const double q = p.quadric.value(uv0);
    if (q <= 0.0) continue;
    const double term = p.amplitude_mm * q * q * q;
    if (count < k_held)
      held[count] = term;
    else
      more.push_back(term);
    ++count;
  }
  const auto g = [&](double h) {
    double value = -h;
    for (std::size_t k = 0; k < count; ++k)
      value += k < k_held ? held[k] : more[k - k_held];
    return value;
  };
  double h = g(0.0); // exact: the terms do not depend on h
  double residual = g(h);
  if (std::abs(residual) <= 1e-14 * (L + std::abs(h))) return h;
  // Newton's steps on g (slope -1) within the bracket that holds every root of bounded bumps,
  // for the sums whose rounding leaves a residual.
  constexpr double slope = -1.0;
  double bound = L;
  for (const auto& p : perturbations)
    bound += std::abs(p.amplitude_mm) * 8.0;
  double lo = -bound, hi = bound; // g(lo) > 0 > g(hi) when the bumps are bounded there
  for (int i = 0; i < 100; ++i) {
    (residual > 0.0 ? lo : hi) = h;
    double next = h - residual / slope;
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    if (std::abs(next - h) <= 1e-14 * (L + std::abs(h))) return next;
    h = next;
    residual = g(h);
  }
  return h;
}

Eigen::Vector3d PatchSurface::surface_point(Eigen::Index t, double u, double v) const {
  // frame()'s origin, edges and normal, without the inverse it also computes.
  const Eigen::Vector3d origin = corner(m_base, t, 0), edge1 = corner(m_base, t, 1) - origin,
                        edge2 = corner(m_base, t, 2) - origin;
  const Eigen::Vector3d normal = edge1.cross(edge2).normalized();
  return origin + u * edge1 + v * edge2 + height(t, u, v) * normal;
}

std::array<Plane, 3> PatchSurface::clipping_planes(Eigen::Index t) const {
  std::array<Plane, 3> planes;
  const Eigen::Vector3d normal = frame(t).normal;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d a = corner(m_base, t, k), b = corner(m_base, t, (k + 1) % 3),
                          c = corner(m_base, t, (k + 2) % 3);
    const Eigen::Vector3d mean_normal = (normal + frame(m_neighbours(t, k)).normal).normalized();
    Eigen::Vector3d plane_normal = (b - a).cross(mean_normal).normalized();
    if (plane_normal.dot(c - a) < 0.0) plane_normal = -plane_normal;
    planes[static_cast<std::size_t>(k)] = Plane{plane_normal, plane_normal.dot(a)};
  }
  return planes;
}

bool PatchSurface::in_wedge(Eigen::Index t, const Eigen::Vector3d& x, double tolerance_mm) const {
  for (const Plane& p : clipping_planes(t)) {
    if (p.signed_distance(x) < -tolerance_mm) return false;
  }
  return true;
}

double PatchSurface::mean_bump_height(Eigen::Index triangle) const {
  // A bump's height a (1 - r^2)^3 integrates to a / 4 times its ellipse's area, which is its
  // (u, v) area times |e1 x e2| = 2 A.
  double height = 0.0;
  for (const PatchBump& bump : m_bumps[static_cast<std::size_t>(triangle)])
    height += bump.amplitude_mm * bump.uv_area() / 2.0;
  return height;
}

double PatchSurface::volume() const {
  double six_volume = 0.0, bumps = 0.0;
  for (Eigen::Index t = 0; t < m_base.face_count(); ++t) {
    const Eigen::Vector3d a = corner(m_base, t, 0), b = corner(m_base, t, 1), c = corner(m_base, t, 2);
    six_volume += a.dot(b.cross(c));
    bumps += mean_bump_height(t) * 0.5 * (b - a).cross(c - a).norm();
  }
  return six_volume / 6.0 + bumps;
}

std::vector<Eigen::Vector3d> PatchSurface::patch_grid_points(Eigen::Index t, int level) const {
  const int n = 1 << level;
  std::vector<Eigen::Vector3d> points;
  points.reserve(static_cast<std::size_t>((n + 1) * (n + 2) / 2));
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i + j <= n; ++i)
      points.push_back(surface_point(t, double(i) / n, double(j) / n));
  }
  return points;
}

} // namespace phantasm
