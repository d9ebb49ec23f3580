#include "voxelize/dense_landmarks.hpp"

#include "core/cancellation.hpp"
#include "geometry/tet_location.hpp"
#include "voxelize/landmarks.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <optional>
#include <random>

namespace phantasm {
namespace {

/// splitmix64's finalizer: a seed per organ from the scene's seed and the organ's name.
std::uint64_t mix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

std::uint64_t organ_seed(std::uint64_t seed, const std::string& organ) {
  std::uint64_t h = 0xcbf29ce484222325ull; // FNV-1a of the name
  for (const char c : organ)
    h = (h ^ static_cast<unsigned char>(c)) * 0x100000001b3ull;
  return mix(seed ^ mix(h));
}

/// Where a reference point of one organ lies in the deformed state, when that is exact: itself
/// (grown with the head, PhantomDeformation::head) for an organ that stays; for one that moves, the map where
/// it is exact and, when the bodies tell which organ each tet holds, only inside a tet of this organ (a point
/// of its material in a neighbour's tet, where the tet mesh cuts a corner of the surface, would take the
/// neighbour's motion).
class OrganMotion {
public:
  OrganMotion(const PhantomDeformation* deformation, const DeformationMap* map, std::size_t organ) {
    if (!deformation || !map) return;
    m_head = deformation->head;
    const std::string& moved_by = deformation->organs[organ].moved_by;
    if (moved_by != "solver" && moved_by.rfind("embedded", 0) != 0) return;
    m_map = map;
    for (const DeformedBody& body : map->bodies()) {
      if (body.tet_organ.size() != static_cast<std::size_t>(body.tets.rows())) continue;
      std::vector<Eigen::Index> rows;
      for (Eigen::Index t = 0; t < body.tets.rows(); ++t)
        if (body.tet_organ[static_cast<std::size_t>(t)] == static_cast<int>(organ)) rows.push_back(t);
      if (rows.empty()) continue;
      Eigen::MatrixX4i tets(static_cast<Eigen::Index>(rows.size()), 4);
      for (std::size_t r = 0; r < rows.size(); ++r)
        tets.row(static_cast<Eigen::Index>(r)) = body.tets.row(rows[r]);
      m_own.push_back({&body, tets, TetMeshLocator(body.rest_mm, tets)});
    }
  }

  std::optional<Eigen::Vector3d> deformed(const Eigen::Vector3d& x) const {
    if (!m_map) return m_head.apply(x);
    bool exact = false;
    const Eigen::Vector3d y = m_map->forward(x, &exact);
    if (!exact) return std::nullopt;
    if (m_own.empty()) return y;
    for (const OwnTets& own : m_own) {
      const std::optional<TetLocation> found = own.rest.find(x);
      if (!found) continue;
      Eigen::Vector3d through_own = Eigen::Vector3d::Zero();
      for (int k = 0; k < 4; ++k)
        through_own += found->weights[k] * own.body->deformed_mm.row(own.tets(found->tet, k)).transpose();
      if ((through_own - y).norm() <= 1e-6) return y;
    }
    return std::nullopt;
  }

private:
  struct OwnTets {
    const DeformedBody* body;
    Eigen::MatrixX4i tets; ///< the body's tets of this organ
    TetMeshLocator rest;
  };
  const DeformationMap* m_map = nullptr; ///< null: the organ stays (grown with the head)
  HeadAffine m_head;                     ///< the head's growth after the solve
  std::vector<OwnTets> m_own;
};

struct Point {
  Eigen::Vector3d reference, deformed;
};

/// One pass of the stratified pick: per cell of edge `cell_mm` over the box (x fastest), the first
/// of up to four seeded points in it that lies in the organ's own material with an exact deformed
/// position. The draws are made in cell order before the tests, which run in parallel: the same
/// points on any number of threads.
std::vector<Point> stratified_pass(const Phantom& reference, std::size_t o, const OrganMotion& motion,
                                   const Eigen::Vector3d& low, const Eigen::Vector3i& cells, double cell_mm,
                                   std::mt19937_64& random) {
  constexpr int k_tries = 4;
  const std::ptrdiff_t count = std::ptrdiff_t{cells.x()} * cells.y() * cells.z();
  std::vector<std::array<Eigen::Vector3d, k_tries>> draws(static_cast<std::size_t>(count));
  const auto unit = [&random] { return static_cast<double>(random() >> 11) * 0x1.0p-53; };
  for (std::ptrdiff_t c = 0; c < count; ++c) {
    const std::ptrdiff_t row = c / cells.x();
    const Eigen::Vector3d corner = low + cell_mm * Eigen::Vector3d(static_cast<double>(c % cells.x()),
                                                                   static_cast<double>(row % cells.y()),
                                                                   static_cast<double>(row / cells.y()));
    for (Eigen::Vector3d& x : draws[static_cast<std::size_t>(c)]) {
      const double u = unit(), v = unit(), w = unit();
      x = corner + cell_mm * Eigen::Vector3d(u, v, w);
    }
  }
  std::vector<std::optional<Point>> picked(static_cast<std::size_t>(count));
#pragma omp parallel
  {
    OrganMaterial material(reference, o);
#pragma omp for schedule(dynamic, 8)
    for (std::ptrdiff_t c = 0; c < count; ++c) {
      if (cancellation_requested()) continue;
      for (const Eigen::Vector3d& x : draws[static_cast<std::size_t>(c)]) {
        if (!material.contains(x)) continue;
        if (const std::optional<Eigen::Vector3d> y = motion.deformed(x)) {
          picked[static_cast<std::size_t>(c)] = Point{x, *y};
          break;
        }
      }
    }
  }
  throw_if_cancelled();
  std::vector<Point> out;
  for (const std::optional<Point>& p : picked)
    if (p) out.push_back(*p);
  return out;
}

/// The points of one organ (dense_landmarks).
std::vector<Point> organ_points(const Phantom& reference, std::size_t o, const OrganMotion& motion,
                                int per_organ, std::uint64_t seed) {
  const Eigen::MatrixX3d& rest = reference.organs[o].surface->rest_positions();
  Eigen::Vector3d low = rest.colwise().minCoeff().transpose(), high = rest.colwise().maxCoeff().transpose();
  // Bumps may stand out of the base vertices' box: a margin of 5 % of its largest side.
  const double margin = 0.05 * (high - low).maxCoeff();
  low.array() -= margin;
  high.array() += margin;
  const Eigen::Vector3d size = high - low;
  const auto wanted = static_cast<std::size_t>(per_organ);
  // Cells of the box's volume per point asked; shrunk while too few hold a point, to at most
  // 256 cells per point asked (a thin shell in a large box, or an organ whose coarse tets leave
  // most of its material where the map is not exact).
  double cell_mm = std::cbrt(size.prod() / static_cast<double>(per_organ));
  const double most_cells = 256.0 * static_cast<double>(per_organ) + 4096.0;
  std::mt19937_64 random(organ_seed(seed, reference.organs[o].name));
  std::vector<Point> found;
  for (int pass = 0; pass < 10; ++pass) {
    const Eigen::Vector3i cells = (size / cell_mm).array().ceil().cast<int>().max(1).matrix();
    found = stratified_pass(reference, o, motion, low, cells, cell_mm, random);
    if (found.size() >= wanted) break;
    const double ratio = static_cast<double>(found.size()) / static_cast<double>(wanted);
    const double next = cell_mm * std::clamp(0.97 * std::cbrt(ratio), 0.5, 0.95);
    if ((size / next).array().ceil().prod() > most_cells) break;
    cell_mm = next;
  }
  if (found.size() <= wanted) return found;
  // An evenly spaced choice in cell order keeps the spread.
  std::vector<Point> kept;
  for (std::size_t i = 0; i < wanted; ++i)
    kept.push_back(found[(2 * i + 1) * found.size() / (2 * wanted)]);
  return kept;
}

} // namespace

std::vector<Landmark> dense_landmarks(const Phantom& reference, const PhantomDeformation* deformation,
                                      const DeformationMap* map, int per_organ, std::uint64_t seed,
                                      std::vector<std::string>* notes) {
  std::vector<Landmark> out;
  if (per_organ <= 0) return out;
  per_organ = std::min(per_organ, k_max_dense_landmarks);
  for (std::size_t o = 0; o < reference.organs.size(); ++o) {
    const Organ& organ = reference.organs[o];
    if (!organ.surface) continue;
    const OrganMotion motion(deformation, map, o);
    const std::vector<Point> points = organ_points(reference, o, motion, per_organ, seed);
    if (points.size() < static_cast<std::size_t>(per_organ) && notes) {
      notes->push_back("dense landmarks of " + organ.name + ": " + std::to_string(points.size()) +
                       " of the " + std::to_string(per_organ) +
                       " asked (its own material is too thin or too small for more, or the map is not "
                       "exact over most of it)");
    }
    char name[32];
    for (std::size_t p = 0; p < points.size(); ++p) {
      std::snprintf(name, sizeof name, "_point_%04zu", p + 1);
      out.push_back({organ.name + name, organ.name, points[p].reference, points[p].deformed});
    }
  }
  return out;
}

} // namespace phantasm
