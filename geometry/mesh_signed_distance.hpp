// Closest points on a closed triangle mesh and the sign of the distance from angle-weighted
// pseudonormals (Baerentzen and Aanaes 2005): negative inside an outward-oriented mesh.
#pragma once

#include "geometry/closest_point_triangle.hpp"

#include <Eigen/Core>

#include <array>
#include <limits>
#include <vector>

namespace phantasm {

/// The point of a triangle mesh closest to a query point.
struct MeshClosestPoint {
  int triangle = -1;                ///< row of the mesh's triangle list; -1 when there is none
  TriangleClosestPoint on_triangle; ///< the point (mm), its barycentric weights and feature
  double distance_squared = std::numeric_limits<double>::infinity(); ///< mm^2
};

/// A triangle mesh for distance queries: per-triangle corners, bounding boxes, unit face normals
/// and the angle-weighted pseudonormals of edges (sum of the two face normals) and vertices (face
/// normals weighted by the corner angles), whose sign against x - closest point is the inside
/// test of a closed, outward mesh (Baerentzen and Aanaes, IEEE TVCG 11(3), 2005). The positions
/// can change between queries (update()), the connectivity cannot.
///
/// Closest points are searched either through every triangle whose bounding box is nearer than
/// the best so far (in triangle order: ties go to the first triangle), or, after
/// build_search_tree(), through a bounding-box hierarchy (static meshes queried at many points;
/// ties go to the lowest triangle index).
class SignedDistanceMesh {
public:
  SignedDistanceMesh() = default;
  /// @param triangles vertex indices (rows of the positions given to update()), counter-clockwise
  ///        seen from outside; vertices need not be contiguous (e.g. one surface of a larger model)
  explicit SignedDistanceMesh(std::vector<std::array<int, 3>> triangles);
  /// @param faces (#F x 3) vertex indices, counter-clockwise seen from outside
  explicit SignedDistanceMesh(const Eigen::MatrixX3i& faces);

  /// Recomputes corners, bounds and normals at new positions; drops the search tree.
  /// @param positions (#V x 3) vertex positions, mm, one row per vertex index
  void update(const Eigen::MatrixX3d& positions);

  /// Builds a bounding-box hierarchy (median splits, leaves of at most 4 triangles) over the
  /// current positions, used by closest() until the next update(). It holds a copy of every
  /// triangle's corners and box in the tree's order (128 bytes per triangle).
  void build_search_tree();

  /// The point of the mesh closest to x (x in mm). Its triangle is -1 for a mesh without triangles.
  MeshClosestPoint closest(const Eigen::Vector3d& x) const;
  /// The same point, searched from a guess: triangle `hint` (e.g. the answer for a neighbouring
  /// query point) bounds the search from the start, so fewer boxes are opened; the answer is
  /// closest(x)'s, ties included. A hint of -1 is no guess.
  MeshClosestPoint closest(const Eigen::Vector3d& x, int hint) const;

  /// The triangles a block of query points needs (near_box()), for closest(x, near) at each
  /// point of the block: a buffer to reuse between blocks.
  struct NearTriangles {
    struct Entry {
      double block_distance_squared; ///< between the triangle's bounding box and the block, mm^2
      int position;                  ///< in the search tree's order
    };
    std::vector<Entry> entries;
  };

  /// Gathers into `near` the triangles that may hold the closest point of some point of the box
  /// [lo, hi] (after build_search_tree()): those whose bounding boxes lie within the box's reach,
  /// the largest distance from a corner of the box to the triangle closest to its centre (the
  /// distance to a triangle is convex, so no point of the box lies farther from it), in order of
  /// their boxes' distance to the block (ties by triangle index). Without a search tree, none
  /// (closest(x, near) then searches as closest(x)).
  void near_box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, NearTriangles& near) const;
  /// closest(x)'s answer, ties included, for x in the box `near` was gathered for: its triangles
  /// in order, up to the first whose box lies farther from the block than the best so far.
  /// Voxels of one block share most of their search this way (a closest() each opens the tree
  /// from its root).
  MeshClosestPoint closest(const Eigen::Vector3d& x, const NearTriangles& near) const;

  /// The pseudonormal of the feature a closest point lies on (not unit length except on a face;
  /// zero for a degenerate face).
  Eigen::Vector3d pseudonormal(const MeshClosestPoint& c) const;

  /// Whether x lies inside the closed mesh given its closest point c: (x - c.point) . pseudonormal < 0.
  bool inside(const Eigen::Vector3d& x, const MeshClosestPoint& c) const;

  /// Unsigned distance from x to the mesh, mm.
  double distance(const Eigen::Vector3d& x) const;
  /// Signed distance from x to the mesh: negative inside a closed, outward mesh, mm.
  double signed_distance(const Eigen::Vector3d& x) const;

  const std::vector<std::array<int, 3>>& triangles() const { return m_triangles; }
  /// Corners of triangle t at the last update(), mm.
  const std::array<Eigen::Vector3d, 3>& corners(int t) const {
    return m_corners[static_cast<std::size_t>(t)];
  }
  /// Unit normal of triangle t (zero when degenerate).
  const Eigen::Vector3d& face_normal(int t) const { return m_face_normals[static_cast<std::size_t>(t)]; }
  /// Bounding box of the mesh at the last update(), mm (inverted, +inf/-inf, when empty).
  const Eigen::Vector3d& min() const { return m_min; }
  const Eigen::Vector3d& max() const { return m_max; }
  /// Whether x lies in the bounding box (boundary included).
  bool in_bounds(const Eigen::Vector3d& x) const {
    return (x.array() >= m_min.array()).all() && (x.array() <= m_max.array()).all();
  }

private:
  void connect();
  MeshClosestPoint scan(const Eigen::Vector3d& x) const;
  MeshClosestPoint search_tree(const Eigen::Vector3d& x, MeshClosestPoint best) const;

  std::vector<std::array<int, 3>> m_triangles;
  // Connectivity, from the constructor.
  std::vector<std::array<int, 3>> m_corner_vertex; ///< per triangle corner: index in m_vertex_normals
  std::vector<std::array<int, 3>> m_edge;          ///< per triangle edge k (k, k+1): index in m_edge_normals
  // Geometry, from update().
  std::vector<std::array<Eigen::Vector3d, 3>> m_corners;
  std::vector<Eigen::Vector3d> m_face_normals, m_face_min, m_face_max;
  std::vector<Eigen::Vector3d> m_vertex_normals, m_edge_normals;
  Eigen::Vector3d m_min = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d m_max = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());
  // The search tree, from build_search_tree(): node 0 is the root; a node's children are
  // first_child and first_child + 1, a leaf (first_child -1) holds m_order[begin, end).
  struct SearchNode {
    Eigen::Vector3d lo, hi;
    int first_child = -1, begin = 0, end = 0;
  };
  std::vector<SearchNode> m_nodes;
  std::vector<int> m_order;
  /// The triangles in m_order's order, each with its corners and box: a leaf's triangles lie
  /// side by side in memory (a search read them through m_order from all over the arrays).
  struct TreeTriangle {
    std::array<Eigen::Vector3d, 3> corners;
    Eigen::Vector3d lo, hi;
    Eigen::Vector3d normal; ///< unit (zero for a triangle without area)
    int triangle;
  };
  std::vector<TreeTriangle> m_tree_triangles;
  /// Makes tt the best when it holds a closer point of x (or one as close, of lower index).
  void visit(const Eigen::Vector3d& x, const TreeTriangle& tt, double margin, MeshClosestPoint& best) const;
};

} // namespace phantasm
