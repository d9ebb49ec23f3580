// DeformationMap between the reference and deformed phantom (exact in the solved bodies, a
// fading extension outside) and the dense displacement fields, masks and Jacobian from it.
#pragma once

#include "core/grid.hpp"
#include "geometry/tet_location.hpp"
#include "sim/phantom_deformation.hpp"
#include "voxelize/voxelized_phantom.hpp"

#include <array>
#include <cstdint>
#include <vector>

namespace phantasm {

/// The map between the reference and deformed phantom, from the solved bodies: barycentric in
/// their tets (exact), and outside them a smooth extension that fades out [choice]: the
/// displacement of the closest point on the body boundary faces that moved, times a smoothstep
/// from 1 on the face to 0 at extension_mm (continuous with the body's own motion). Tissue
/// outside the bodies does not move, so the zero displacement is exact there too, except within
/// extension_mm of a moved boundary face in either state (the extension, and the gap a boundary
/// leaves when it moves away from its container, have no exact correspondence). A growth of the
/// whole head after the solve (PhantomDeformation::head, deformation.head_scale) follows all of
/// it: the map is head o (the solved map), exact wherever the solved map is; the bodies' deformed
/// positions already hold it, and tissue outside them moves by it alone.
class DeformationMap {
public:
  /// @param bodies the solved bodies (rest and deformed tet meshes, mm; deformed with `head`)
  /// @param extension_mm width of the fading extension outside the bodies, mm
  /// @param head the growth of the whole head after the solve (identity: none)
  DeformationMap(std::vector<DeformedBody> bodies, double extension_mm, const HeadAffine& head = {});

  /// Deformed position of a reference point (RAS mm); *exact tells whether it is the solved motion.
  Eigen::Vector3d forward(const Eigen::Vector3d& x_ref, bool* exact = nullptr) const;
  /// Reference position of a deformed point: barycentric in the deformed tets, else the inverse
  /// of the extension by fixed-point iteration.
  Eigen::Vector3d inverse(const Eigen::Vector3d& x_def, bool* exact = nullptr) const;

  /// Fills the field of every grid voxel inside a body's tets in one state (rest: the
  /// reference-to-deformed field; deformed: the way back), tet by tet, so the work follows the
  /// voxels the bodies cover; marks them in `inside`. Sequential, so shared faces resolve the
  /// same way every run.
  void rasterize(const ImageGrid& grid, bool deformed, std::vector<float>& field,
                 std::vector<std::uint8_t>& inside) const;

  /// The extension part of forward() and inverse(), for points outside every body.
  Eigen::Vector3d forward_outside(const Eigen::Vector3d& x_ref, bool* exact) const;
  Eigen::Vector3d inverse_outside(const Eigen::Vector3d& x_def, bool* exact) const;
  /// True when no moved face lies within extension_mm of x in either state, as far as one look
  /// at x's bucket in each state tells (false when in doubt): then forward_outside and
  /// inverse_outside give x itself (with no head growth), exactly, and the zero displacement
  /// there is exact. Most of a grid lies there; the fields skip those voxels. (Points of the
  /// solved state: with a head growth, a deformed point's is head().unapply of it.)
  bool far_from_moved_boundary(const Eigen::Vector3d& x) const;

  const std::vector<DeformedBody>& bodies() const { return m_bodies; }
  double extension_mm() const { return m_extension; }
  /// The growth of the whole head after the solve: the motion of tissue that the solve left still.
  const HeadAffine& head() const { return m_head; }

  /// A boundary face of a body with a moved vertex, in both states (the deformed one as solved,
  /// before the head's growth).
  struct MovedFace {
    std::array<Eigen::Vector3d, 3> rest, deformed;
  };
  /// The moved boundary faces, which drive the extension, in the order the buckets list them.
  const std::vector<MovedFace>& moved_faces() const { return m_moved_faces; }
  /// Distance from x to the moved boundary faces in one state, and the displacement of the
  /// closest point (the first such face in moved_faces() order), when it is below extension_mm
  /// (else infinity or a distance >= extension_mm). Only the faces listed in x's bucket are
  /// read: the same answer as a scan of every face, faster.
  double moved_boundary_distance(const Eigen::Vector3d& x, bool deformed,
                                 Eigen::Vector3d* displacement) const;

private:
  /// The body tet holding x (rest or deformed positions): body, tet and barycentric weights.
  bool locate(const Eigen::Vector3d& x, bool deformed, std::size_t* body, Eigen::Index* tet,
              Eigen::Vector4d* weights) const;
  /// Maps x through the body tet holding it, from one state to the other; false outside the bodies.
  bool through_tets(const Eigen::Vector3d& x, bool from_deformed, Eigen::Vector3d* y) const;
  Eigen::Vector3d extension(const Eigen::Vector3d& x_ref) const;
  bool near_moved_boundary(const Eigen::Vector3d& x) const;

  std::vector<DeformedBody> m_bodies;
  double m_extension = 10.0;
  HeadAffine m_head;
  std::vector<MovedFace> m_moved_faces;
  /// Per state (rest [0], deformed [1]): the moved faces within extension_mm of each cell of a
  /// uniform grid of cells of about extension_mm, in face order (compressed rows), so a query
  /// scans only the faces that can be nearer than extension_mm, in the order the full scan
  /// would, and finds the same face.
  struct FaceBuckets {
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();
    double cell_mm = 1.0;
    Eigen::Vector3i cells = Eigen::Vector3i::Zero();
    std::vector<std::uint32_t> offsets; ///< cell c's faces: faces[offsets[c], offsets[c + 1])
    std::vector<std::uint32_t> faces;
  };
  FaceBuckets m_buckets[2];
  /// Bounding boxes of the moved faces, rest [0] and deformed [1].
  Eigen::Vector3d m_moved_low[2] = {Eigen::Vector3d::Constant(1e300), Eigen::Vector3d::Constant(1e300)};
  Eigen::Vector3d m_moved_high[2] = {Eigen::Vector3d::Constant(-1e300), Eigen::Vector3d::Constant(-1e300)};
  /// Per body: point location in its rest and deformed tets.
  std::vector<TetMeshLocator> m_rest, m_deformed;
};

/// The voxels of tissue that does not move (organs fixed in place or rigid), by their labels on
/// the grid in each state. Its motion is known exactly, zero (or the head's growth alone, when the
/// head grows: then its displacement and Jacobian are the growth's): such a voxel carries zero
/// displacement in the field of its state, inside or outside the bodies' tets, and is exact; the
/// extension of a moved boundary stops at it; its Jacobian is 1, and a Jacobian next to it takes
/// its differences on the moving side only (the motion is discontinuous there: tissue slides
/// along, or leaves, tissue that stays).
struct StillTissue {
  const std::vector<std::int32_t>* reference_labels = nullptr; ///< the reference state's labels
  const std::vector<std::int32_t>* deformed_labels = nullptr;  ///< the deformed state's labels
  std::vector<std::uint8_t> still_labels; ///< per label value: 1 for an organ that does not move

  /// Whether voxel v of the reference (deformed = false) or deformed state holds still tissue.
  bool at(std::size_t v, bool deformed) const {
    const std::vector<std::int32_t>* labels = deformed ? deformed_labels : reference_labels;
    if (!labels) return false;
    const auto label = static_cast<std::size_t>((*labels)[v]);
    return label < still_labels.size() && still_labels[label] != 0;
  }
};

/// Per label value (0 background, organ i's label i + 1, then the gap): 1 for the organs that
/// `deformation` leaves where they are (OrganDeformation::moved_by "fixed" or "rigid").
std::vector<std::uint8_t> still_organ_labels(const PhantomDeformation& deformation);

/// Fields of `voxel_count` voxels that move nothing: zero displacements, every voxel exact,
/// Jacobians 1.
MotionFields identity_motion_fields(std::size_t voxel_count);

/// The fields of `map` on every voxel of `grid`, with the voxels of `still` held at zero (at the
/// head's growth, when it grows).
MotionFields compute_motion_fields(const ImageGrid& grid, const DeformationMap& map,
                                   const StillTissue& still = {});

/// How far (in voxels, of the smallest spacing) the composition of the two fields may miss
/// identity at a voxel marked exact.
constexpr double composition_tolerance_voxels = 0.1;

/// The masks of `f` narrowed to the voxels whose two-way composition is identity within
/// composition_tolerance_voxels: ref_to_def exact at x only when def_to_ref (trilinear) at
/// x + u_ref_to_def(x) returns to x, and the same the other way. Called by
/// compute_motion_fields.
void check_compositions(const ImageGrid& grid, MotionFields& f);

/// Both fields' Jacobian determinants (jacobian, def_to_ref_jacobian), read inside each exact
/// mask from exact values only (one-sided differences where a neighbour lies outside the mask or
/// in still tissue), with min_jacobian, and inside the ref_to_def mask min_exact_jacobian and
/// folded_exact_voxels. Still tissue takes the head's growth's: `still_jacobian` forward, its
/// inverse backward. Called by compute_motion_fields after check_compositions.
void exact_jacobians(const ImageGrid& grid, const StillTissue& still, MotionFields& f,
                     double still_jacobian = 1.0);

} // namespace phantasm
