#include "voxelize/motion_fields.hpp"

#include "core/cancellation.hpp"
#include "geometry/closest_point_triangle.hpp"
#include "geometry/tet_boundary.hpp"

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>

namespace phantasm {

DeformationMap::DeformationMap(std::vector<DeformedBody> bodies, double extension_mm, const HeadAffine& head)
    : m_bodies(std::move(bodies)), m_extension(extension_mm), m_head(head) {
  for (const DeformedBody& body : m_bodies) {
    // Boundary faces with a moved vertex drive the extension: moved by the solve (the head's
    // growth, which moves every face, is applied after the extension).
    const Eigen::MatrixX3i faces = tet_boundary_faces(body.rest_mm, body.tets);
    for (Eigen::Index f = 0; f < faces.rows(); ++f) {
      MovedFace face;
      bool moved = false;
      for (int k = 0; k < 3; ++k) {
        face.rest[k] = body.rest_mm.row(faces(f, k)).transpose();
        face.deformed[k] = m_head.unapply(body.deformed_mm.row(faces(f, k)).transpose());
        moved |= (face.deformed[k] - face.rest[k]).norm() > 1e-9;
      }
      if (moved) {
        m_moved_faces.push_back(face);
        for (int k = 0; k < 3; ++k) {
          m_moved_low[0] = m_moved_low[0].cwiseMin(face.rest[k]);
          m_moved_high[0] = m_moved_high[0].cwiseMax(face.rest[k]);
          m_moved_low[1] = m_moved_low[1].cwiseMin(face.deformed[k]);
          m_moved_high[1] = m_moved_high[1].cwiseMax(face.deformed[k]);
        }
      }
    }
    m_rest.emplace_back(body.rest_mm, body.tets);
    m_deformed.emplace_back(body.deformed_mm, body.tets);
  }
  if (m_moved_faces.empty()) return;
  for (int state = 0; state < 2; ++state) {
    FaceBuckets& b = m_buckets[state];
    const Eigen::Vector3d low = m_moved_low[state].array() - m_extension;
    const Eigen::Vector3d extent =
        m_moved_high[state] - m_moved_low[state] + Eigen::Vector3d::Constant(2.0 * m_extension);
    // Cells of the extension's width, but no more than 256^3 of them.
    b.cell_mm = std::max({m_extension, extent.maxCoeff() / 256.0, 1e-6});
    b.origin = low;
    for (int a = 0; a < 3; ++a)
      b.cells[a] = std::max(1, static_cast<int>(std::ceil(extent[a] / b.cell_mm)));
    const auto cell_count = static_cast<std::size_t>(b.cells.prod());
    // Two passes (count, then fill) over the faces in order, so each cell lists its faces in
    // face order.
    auto cell_range = [&](const MovedFace& f, int lo[3], int hi[3]) {
      const auto& v = state ? f.deformed : f.rest;
      const Eigen::Vector3d f_low = v[0].cwiseMin(v[1]).cwiseMin(v[2]).array() - m_extension;
      const Eigen::Vector3d f_high = v[0].cwiseMax(v[1]).cwiseMax(v[2]).array() + m_extension;
      for (int a = 0; a < 3; ++a) {
        lo[a] =
            std::clamp(static_cast<int>(std::floor((f_low[a] - b.origin[a]) / b.cell_mm)), 0, b.cells[a] - 1);
        hi[a] = std::clamp(static_cast<int>(std::floor((f_high[a] - b.origin[a]) / b.cell_mm)), 0,
                           b.cells[a] - 1);
      }
    };
    auto cell_index = [&](int i, int j, int k) {
      return static_cast<std::size_t>(i) +
             static_cast<std::size_t>(b.cells[0]) *
                 (static_cast<std::size_t>(j) +
                  static_cast<std::size_t>(b.cells[1]) * static_cast<std::size_t>(k));
    };
    b.offsets.assign(cell_count + 1, 0);
    for (const MovedFace& f : m_moved_faces) {
      int lo[3], hi[3];
      cell_range(f, lo, hi);
      for (int k = lo[2]; k <= hi[2]; ++k)
        for (int j = lo[1]; j <= hi[1]; ++j)
          for (int i = lo[0]; i <= hi[0]; ++i)
            ++b.offsets[cell_index(i, j, k) + 1];
    }
    for (std::size_t c = 0; c < cell_count; ++c)
      b.offsets[c + 1] += b.offsets[c];
    b.faces.resize(b.offsets.back());
    std::vector<std::uint32_t> next(b.offsets.begin(), b.offsets.end() - 1);
    for (std::size_t face = 0; face < m_moved_faces.size(); ++face) {
      int lo[3], hi[3];
      cell_range(m_moved_faces[face], lo, hi);
      for (int k = lo[2]; k <= hi[2]; ++k)
        for (int j = lo[1]; j <= hi[1]; ++j)
          for (int i = lo[0]; i <= hi[0]; ++i)
            b.faces[next[cell_index(i, j, k)]++] = static_cast<std::uint32_t>(face);
    }
  }
}

bool DeformationMap::locate(const Eigen::Vector3d& x, bool deformed, std::size_t* body, Eigen::Index* tet,
                            Eigen::Vector4d* weights) const {
  const auto& locators = deformed ? m_deformed : m_rest;
  for (std::size_t b = 0; b < locators.size(); ++b) {
    if (const std::optional<TetLocation> found = locators[b].find(x)) {
      *body = b;
      *tet = found->tet;
      *weights = found->weights;
      return true;
    }
  }
  return false;
}

double DeformationMap::moved_boundary_distance(const Eigen::Vector3d& x, bool deformed,
                                               Eigen::Vector3d* displacement) const {
  double best = std::numeric_limits<double>::infinity();
  // Only faces nearer than the extension matter to the callers: those are in x's cell (its list
  // holds every face whose box grown by the extension meets the cell), in face order, so the
  // strict comparison below picks the face the scan of all faces would.
  const FaceBuckets& b = m_buckets[deformed ? 1 : 0];
  if (b.faces.empty()) return best;
  int ijk[3];
  for (int a = 0; a < 3; ++a) {
    const double c = std::floor((x[a] - b.origin[a]) / b.cell_mm);
    if (!(c >= 0.0 && c < b.cells[a])) return best;
    ijk[a] = static_cast<int>(c);
  }
  const std::size_t cell = static_cast<std::size_t>(ijk[0]) +
                           static_cast<std::size_t>(b.cells[0]) *
                               (static_cast<std::size_t>(ijk[1]) +
                                static_cast<std::size_t>(b.cells[1]) * static_cast<std::size_t>(ijk[2]));
  for (std::uint32_t n = b.offsets[cell]; n < b.offsets[cell + 1]; ++n) {
    const MovedFace& f = m_moved_faces[b.faces[n]];
    const auto& v = deformed ? f.deformed : f.rest;
    const Eigen::Vector3d w = closest_point_on_triangle(x, v[0], v[1], v[2]).barycentric;
    const double d = (x - (w[0] * v[0] + w[1] * v[1] + w[2] * v[2])).norm();
    if (d < best) {
      best = d;
      if (displacement) {
        *displacement = Eigen::Vector3d::Zero();
        for (int k = 0; k < 3; ++k)
          *displacement += w[k] * (f.deformed[k] - f.rest[k]);
      }
    }
  }
  return best;
}

Eigen::Vector3d DeformationMap::extension(const Eigen::Vector3d& x) const {
  Eigen::Vector3d u = Eigen::Vector3d::Zero();
  const double d = moved_boundary_distance(x, false, &u);
  if (!(d < m_extension)) return Eigen::Vector3d::Zero();
  const double s = 1.0 - d / m_extension;
  return s * s * (3.0 - 2.0 * s) * u;
}

bool DeformationMap::far_from_moved_boundary(const Eigen::Vector3d& x) const {
  // moved_boundary_distance's look-up: no face in x's cell (or x beyond the cells) in either
  // state means infinity from both, so no extension and no doubt about exactness.
  for (const FaceBuckets& b : m_buckets) {
    if (b.faces.empty()) continue;
    std::size_t cell = 0, stride = 1;
    bool within = true;
    for (int a = 0; a < 3 && within; ++a) {
      const double c = std::floor((x[a] - b.origin[a]) / b.cell_mm);
      within = c >= 0.0 && c < b.cells[a];
      if (within) cell += stride * static_cast<std::size_t>(c);
      stride *= static_cast<std::size_t>(b.cells[a]);
    }
    if (within && b.offsets[cell] != b.offsets[cell + 1]) return false;
  }
  return true;
}

bool DeformationMap::near_moved_boundary(const Eigen::Vector3d& x) const {
  return moved_boundary_distance(x, false, nullptr) < m_extension ||
         moved_boundary_distance(x, true, nullptr) < m_extension;
}

bool DeformationMap::through_tets(const Eigen::Vector3d& x, bool from_deformed, Eigen::Vector3d* y) const {
  std::size_t b = 0;
  Eigen::Index t = 0;
  Eigen::Vector4d w;
  if (!locate(x, from_deformed, &b, &t, &w)) return false;
  const Eigen::MatrixX3d& to = from_deformed ? m_bodies[b].rest_mm : m_bodies[b].deformed_mm;
  *y = Eigen::Vector3d::Zero();
  for (int k = 0; k < 4; ++k)
    *y += w[k] * to.row(m_bodies[b].tets(t, k)).transpose();
  return true;
}

Eigen::Vector3d DeformationMap::forward(const Eigen::Vector3d& x, bool* exact) const {
  Eigen::Vector3d y;
  if (through_tets(x, false, &y)) {
    if (exact) *exact = true;
    return y;
  }
  return forward_outside(x, exact);
}

Eigen::Vector3d DeformationMap::forward_outside(const Eigen::Vector3d& x, bool* exact) const {
  const Eigen::Vector3d u = extension(x);
  if (exact) *exact = !near_moved_boundary(x);
  return m_head.apply(x + u);
}

Eigen::Vector3d DeformationMap::inverse(const Eigen::Vector3d& x, bool* exact) const {
  Eigen::Vector3d y;
  if (through_tets(x, true, &y)) {
    if (exact) *exact = true;
    return y;
  }
  return inverse_outside(x, exact);
}

Eigen::Vector3d DeformationMap::inverse_outside(const Eigen::Vector3d& x_def, bool* exact) const {
  // The solved state's point, then the extension's inverse there.
  const Eigen::Vector3d x = m_head.unapply(x_def);
  Eigen::Vector3d y = x;
  for (int iteration = 0; iteration < 30; ++iteration) {
    const Eigen::Vector3d next = x - extension(y);
    const double change = (next - y).norm();
    y = next;
    if (change < 1e-9) break;
  }
  if (exact) *exact = !near_moved_boundary(x) && !near_moved_boundary(y);
  return y;
}

void DeformationMap::rasterize(const ImageGrid& grid, bool deformed, std::vector<float>& field,
                               std::vector<std::uint8_t>& inside) const {
  const auto count = static_cast<std::size_t>(grid.voxel_count());
  const auto& locators = deformed ? m_deformed : m_rest;
  const IndexFromWorld index_from_world(grid);
  for (std::size_t b = 0; b < m_bodies.size(); ++b) {
    const DeformedBody& body = m_bodies[b];
    const Eigen::MatrixX3d& from = deformed ? body.deformed_mm : body.rest_mm;
    const Eigen::MatrixX3d& to = deformed ? body.rest_mm : body.deformed_mm;
    for (Eigen::Index t = 0; t < body.tets.rows(); ++t) {
      Eigen::Vector3d low = Eigen::Vector3d::Constant(1e300), high = -low;
      for (int k = 0; k < 4; ++k) {
        const Eigen::Vector3d index = index_from_world(from.row(body.tets(t, k)).transpose());
        low = low.cwiseMin(index);
        high = high.cwiseMax(index);
      }
      int lo[3], hi[3];
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::max(0, static_cast<int>(std::ceil(low[a] - 1e-9)));
        hi[a] = std::min(grid.dims[a] - 1, static_cast<int>(std::floor(high[a] + 1e-9)));
      }
      for (int k = lo[2]; k <= hi[2]; ++k) {
        for (int j = lo[1]; j <= hi[1]; ++j) {
          for (int i = lo[0]; i <= hi[0]; ++i) {
            const std::size_t v = voxel_index(grid.dims, i, j, k);
            if (inside[v]) continue;
            const Eigen::Vector3d x = grid.world_from_index(Eigen::Vector3d(i, j, k));
            const Eigen::Vector4d w = locators[b].barycentric(t, x);
            if (w.minCoeff() < -1e-12) continue;
            Eigen::Vector3d y = Eigen::Vector3d::Zero();
            for (int c = 0; c < 4; ++c)
              y += w[c] * to.row(body.tets(t, c)).transpose();
            for (int c = 0; c < 3; ++c)
              field[static_cast<std::size_t>(c) * count + v] = static_cast<float>(y[c] - x[c]);
            inside[v] = 1;
          }
        }
      }
    }
  }
}

namespace {

/// A field (component-major) at a world point by trilinear interpolation of the voxel values
/// (clamped at the border): what a user of the ground truth does to compose the fields.
Eigen::Vector3d sample_field(const ImageGrid& grid, const IndexFromWorld& index_from_world,
                             const std::vector<float>& field, const Eigen::Vector3d& x) {
  const auto count = static_cast<std::size_t>(grid.voxel_count());
  const Eigen::Vector3d index = index_from_world(x);
  // Per axis, the two corners' offsets in the arrays and weights (the upper corner clamped at
  // the border).
  std::size_t offset[3][2];
  double factor[3][2];
  std::size_t stride = 1;
  for (int a = 0; a < 3; ++a) {
    const double c = std::clamp(index[a], 0.0, static_cast<double>(grid.dims[a] - 1));
    const int lo = std::min(static_cast<int>(std::floor(c)), std::max(0, grid.dims[a] - 2));
    const double w = grid.dims[a] > 1 ? c - lo : 0.0;
    offset[a][0] = static_cast<std::size_t>(lo) * stride;
    offset[a][1] = static_cast<std::size_t>(std::min(lo + 1, grid.dims[a] - 1)) * stride;
    factor[a][0] = 1.0 - w;
    factor[a][1] = w;
    stride *= static_cast<std::size_t>(grid.dims[a]);
  }
  Eigen::Vector3d u = Eigen::Vector3d::Zero();
  for (int corner = 0; corner < 8; ++corner) {
    const int b0 = corner & 1, b1 = (corner >> 1) & 1, b2 = (corner >> 2) & 1;
    const double weight = factor[0][b0] * factor[1][b1] * factor[2][b2];
    if (weight == 0.0) continue;
    const std::size_t v = offset[0][b0] + offset[1][b1] + offset[2][b2];
    for (int c = 0; c < 3; ++c)
      u[c] += weight * field[static_cast<std::size_t>(c) * count + v];
  }
  return u;
}

} // namespace

void check_compositions(const ImageGrid& grid, MotionFields& f) {
  const auto count = static_cast<std::size_t>(grid.voxel_count());
  const double tolerance = composition_tolerance_voxels * grid.spacing_mm.minCoeff();
  const IndexFromWorld index(grid);
  const int nx = grid.dims.x(), ny = grid.dims.y(), nz = grid.dims.z();
  long inconsistent = 0;
  double worst = 0.0;
  // First both masks from the compositions, then the Jacobian check against the final mask. A
  // voxel's compositions read only the fields, and its masks only at itself, so the masks are
  // narrowed in place (no copy of them is held).
#pragma omp parallel for schedule(static) reduction(+ : inconsistent) reduction(max : worst)
  for (int k = 0; k < nz; ++k) {
    if (cancellation_requested()) continue; // no exception may leave an OpenMP region
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        const std::size_t v =
            static_cast<std::size_t>(i) +
            static_cast<std::size_t>(nx) *
                (static_cast<std::size_t>(j) + static_cast<std::size_t>(ny) * static_cast<std::size_t>(k));
        const Eigen::Vector3d to_def(f.ref_to_def[v], f.ref_to_def[count + v], f.ref_to_def[2 * count + v]);
        const Eigen::Vector3d to_ref(f.def_to_ref[v], f.def_to_ref[count + v], f.def_to_ref[2 * count + v]);
        // Both maps leave the voxel where it is (tissue that does not move, most of a head):
        // each composition is the identity, exactly, with nothing to sample.
        if (to_def.isZero(0.0) && to_ref.isZero(0.0)) continue;
        const Eigen::Vector3d x = grid.world_from_index(Eigen::Vector3d(i, j, k));
        if (f.ref_to_def_exact[v]) {
          const double miss = (sample_field(grid, index, f.def_to_ref, x + to_def) + to_def).norm();
          if (miss > tolerance) {
            f.ref_to_def_exact[v] = 0;
            ++inconsistent;
          } else {
            worst = std::max(worst, miss);
          }
        }
        if (f.def_to_ref_exact[v]) {
          const double miss = (sample_field(grid, index, f.ref_to_def, x + to_ref) + to_ref).norm();
          if (miss > tolerance) {
            f.def_to_ref_exact[v] = 0;
            ++inconsistent;
          } else {
            worst = std::max(worst, miss);
          }
        }
      }
    }
  }
  f.inconsistent_voxels = inconsistent;
  f.max_composition_error_mm = worst;
}

namespace {

/// det(I + grad u) of the field `u` (3 * voxel_count, component-major) at every voxel into
/// `jacobian`: central differences in index space (one-sided at the border, next to still
/// tissue, and at a voxel of the `exact` mask next to one outside it; none between two still
/// voxels), mapped to world derivatives by the inverse of the grid's linear part;
/// `still_jacobian` (1, or the head's growth's) at a voxel of still tissue (`still` in the
/// field's state). Inside the exact mask the determinant thus
/// reads exact values only: a neighbour outside holds the extension or a composition that missed,
/// and a central difference across it made the head's deformed grid report thousands of folds
/// that no tet had. Returns the smallest.
double jacobian_determinants(const ImageGrid& grid, const std::vector<float>& u, const StillTissue& still,
                             bool deformed, const std::vector<std::uint8_t>& exact,
                             std::vector<float>& jacobian, double still_jacobian) {
  const auto count = static_cast<std::size_t>(grid.voxel_count());
  const int nx = grid.dims.x(), ny = grid.dims.y(), nz = grid.dims.z();
  const Eigen::Matrix3d index_from_world = grid.world_from_voxel.topLeftCorner<3, 3>().inverse();
  // A neighbour along axis a is the voxel `stride[a]` apart in the arrays.
  const std::size_t stride[3] = {1, static_cast<std::size_t>(nx),
                                 static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny)};
  const int size[3] = {nx, ny, nz};
  const float* const component[3] = {u.data(), u.data() + count, u.data() + 2 * count};
  double min_jacobian = std::min(1.0, still_jacobian);
#pragma omp parallel for schedule(static) reduction(min : min_jacobian)
  for (int k = 0; k < nz; ++k) {
    if (cancellation_requested()) continue; // no exception may leave an OpenMP region
    for (int j = 0; j < ny; ++j) {
      const std::size_t row = voxel_index(grid.dims, 0, j, k);
      for (int i = 0; i < nx; ++i) {
        const std::size_t v = row + static_cast<std::size_t>(i);
        if (still.at(v, deformed)) {
          jacobian[v] = static_cast<float>(still_jacobian); // its motion: the head's growth
          continue;
        }
        const int index[3] = {i, j, k};
        const bool in_mask = exact[v] != 0;
        // Not across into still tissue (the motion jumps there), nor out of the exact mask.
        const auto leave_out = [&](std::size_t w) { return still.at(w, deformed) || (in_mask && !exact[w]); };
        Eigen::Matrix3d d_index; // column a: du / d(index a)
        for (int a = 0; a < 3; ++a) {
          // The neighbours on each side (the voxel itself at the border or where left out).
          std::size_t lo = v, hi = v;
          int span = 0;
          if (index[a] > 0 && !leave_out(v - stride[a])) {
            lo = v - stride[a];
            ++span;
          }
          if (index[a] < size[a] - 1 && !leave_out(v + stride[a])) {
            hi = v + stride[a];
            ++span;
          }
          for (int c = 0; c < 3; ++c)
            d_index(c, a) =
                span > 0 ? (component[c][hi] - component[c][lo]) / static_cast<double>(span) : 0.0;
        }
        const double det = (Eigen::Matrix3d::Identity() + d_index * index_from_world).determinant();
        jacobian[v] = static_cast<float>(det);
        min_jacobian = std::min(min_jacobian, det);
      }
    }
  }
  return min_jacobian;
}

} // namespace

std::vector<std::uint8_t> still_organ_labels(const PhantomDeformation& deformation) {
  // Background, the organs, the gap.
  std::vector<std::uint8_t> still(deformation.organs.size() + 2, 0);
  for (std::size_t o = 0; o < deformation.organs.size(); ++o) {
    const std::string& how = deformation.organs[o].moved_by;
    still[o + 1] = how == "fixed" || how == "rigid" ? 1 : 0;
  }
  return still;
}

MotionFields identity_motion_fields(std::size_t voxel_count) {
  MotionFields f;
  f.ref_to_def.assign(3 * voxel_count, 0.0f);
  f.def_to_ref.assign(3 * voxel_count, 0.0f);
  f.ref_to_def_exact.assign(voxel_count, 1);
  f.def_to_ref_exact.assign(voxel_count, 1);
  f.jacobian.assign(voxel_count, 1.0f);
  f.def_to_ref_jacobian.assign(voxel_count, 1.0f);
  return f;
}

MotionFields compute_motion_fields(const ImageGrid& grid, const DeformationMap& map,
                                   const StillTissue& still) {
  const auto count = static_cast<std::size_t>(grid.voxel_count());
  MotionFields f = identity_motion_fields(count);
  const int nx = grid.dims.x(), ny = grid.dims.y(), nz = grid.dims.z();
  auto at = [&](int i, int j, int k) { return voxel_index(grid.dims, i, j, k); };
  const HeadAffine& head = map.head();
  if (map.bodies().empty() && head.identity()) return f;
  // Inside the bodies: tet by tet. Outside: the extension, voxel by voxel in parallel (each
  // voxel's value depends on nothing else, so the result does not depend on the threads).
  std::vector<std::uint8_t> inside_ref(count, 0), inside_def(count, 0);
  // The two directions write separate arrays: one thread each (each one tet by tet, in order,
  // so a voxel on a face shared by two tets takes the first one's value, as on one thread).
#pragma omp parallel sections
  {
#pragma omp section
    map.rasterize(grid, false, f.ref_to_def, inside_ref);
#pragma omp section
    map.rasterize(grid, true, f.def_to_ref, inside_def);
  }
#pragma omp parallel for schedule(dynamic, 1)
  for (int k = 0; k < nz; ++k) {
    if (cancellation_requested()) continue; // no exception may leave an OpenMP region
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        const std::size_t v = at(i, j, k);
        // Still tissue keeps the zero displacement and the exact mark the fields start with.
        const bool forward = !inside_ref[v] && !still.at(v, false);
        const bool backward = !inside_def[v] && !still.at(v, true);
        if (!forward && !backward) continue;
        const Eigen::Vector3d x = grid.world_from_index(Eigen::Vector3d(i, j, k));
        // No moved face near: both maps are the identity there, exactly: the zero displacement
        // and the exact mark the fields start with. (With the head's growth every voxel moves:
        // forward_outside and inverse_outside give it.)
        if (head.identity() && map.far_from_moved_boundary(x)) continue;
        bool exact = true;
        if (forward) {
          const Eigen::Vector3d to_def = map.forward_outside(x, &exact) - x;
          f.ref_to_def_exact[v] = exact;
          for (int c = 0; c < 3; ++c)
            f.ref_to_def[static_cast<std::size_t>(c) * count + v] = static_cast<float>(to_def[c]);
        }
        if (backward) {
          const Eigen::Vector3d to_ref = map.inverse_outside(x, &exact) - x;
          f.def_to_ref_exact[v] = exact;
          for (int c = 0; c < 3; ++c)
            f.def_to_ref[static_cast<std::size_t>(c) * count + v] = static_cast<float>(to_ref[c]);
        }
      }
    }
  }
  // The marks of the voxels inside are not needed any more: freed before the Jacobians and the
  // compositions.
  inside_ref = std::vector<std::uint8_t>();
  inside_def = std::vector<std::uint8_t>();
  // Still tissue inside a body's tets (a voxel whose label is the container's, on the body's
  // side of the faceted boundary): zero and exact too, in each state; with the head's growth,
  // the growth (forward) and its inverse (backward), exact, everywhere in still tissue.
  if (still.reference_labels || still.deformed_labels) {
#pragma omp parallel for schedule(static)
    for (std::ptrdiff_t n = 0; n < static_cast<std::ptrdiff_t>(count); ++n) {
      const auto v = static_cast<std::size_t>(n);
      for (const bool deformed : {false, true}) {
        if (!still.at(v, deformed)) continue;
        std::vector<float>& u = deformed ? f.def_to_ref : f.ref_to_def;
        Eigen::Vector3d moved = Eigen::Vector3d::Zero();
        if (!head.identity()) {
          const auto row = static_cast<std::int64_t>(v) / grid.dims.x();
          const Eigen::Vector3d x = grid.world_from_index(Eigen::Vector3d(
              static_cast<double>(static_cast<std::int64_t>(v) % grid.dims.x()),
              static_cast<double>(row % grid.dims.y()), static_cast<double>(row / grid.dims.y())));
          moved = (deformed ? head.unapply(x) : head.apply(x)) - x;
        }
        for (std::size_t c = 0; c < 3; ++c)
          u[c * count + v] = static_cast<float>(moved[static_cast<Eigen::Index>(c)]);
        (deformed ? f.def_to_ref_exact : f.ref_to_def_exact)[v] = 1;
      }
    }
  }
  double max_displacement = 0.0;
#pragma omp parallel for schedule(static) reduction(max : max_displacement)
  for (std::size_t v = 0; v < count; ++v) {
    const Eigen::Vector3d u(f.ref_to_def[v], f.ref_to_def[count + v], f.ref_to_def[2 * count + v]);
    max_displacement = std::max(max_displacement, u.norm());
  }
  f.max_displacement_mm = max_displacement;
  throw_if_cancelled();
  check_compositions(grid, f);
  throw_if_cancelled();
  exact_jacobians(grid, still, f, head.determinant());
  throw_if_cancelled();
  return f;
}

void exact_jacobians(const ImageGrid& grid, const StillTissue& still, MotionFields& f,
                     double still_jacobian) {
  f.min_jacobian =
      jacobian_determinants(grid, f.ref_to_def, still, false, f.ref_to_def_exact, f.jacobian, still_jacobian);
  jacobian_determinants(grid, f.def_to_ref, still, true, f.def_to_ref_exact, f.def_to_ref_jacobian,
                        1.0 / still_jacobian);
  long folded = 0;
  double smallest = std::numeric_limits<double>::infinity();
  for (std::size_t v = 0; v < f.ref_to_def_exact.size(); ++v) {
    if (!f.ref_to_def_exact[v]) continue;
    smallest = std::min(smallest, static_cast<double>(f.jacobian[v]));
    if (!(f.jacobian[v] > 0.0f)) ++folded;
  }
  f.folded_exact_voxels = folded;
  f.min_exact_jacobian = std::isfinite(smallest) ? smallest : 1.0; // an empty mask: the identity's
}

} // namespace phantasm
