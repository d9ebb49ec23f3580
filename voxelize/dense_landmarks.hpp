// Dense landmarks: a few hundred seeded material points per closed organ, spread over its own
// material and exact in both states, for a target registration error measured all over each
// structure rather than at seven points.
#pragma once

#include "anatomy/organ.hpp"
#include "sim/phantom_deformation.hpp"
#include "voxelize/motion_fields.hpp"
#include "voxelize/voxelized_phantom.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace phantasm {

/// The most dense landmarks per organ (names carry four digits).
inline constexpr int k_max_dense_landmarks = 9999;

/// Up to `per_organ` landmarks per closed organ, "<organ>_point_NNNN", each a material point of
/// that organ's own material in the reference state (inside its surface and outside the organs
/// nested in it, by OrganMaterial: the patches' exact test). They are stratified over the organ:
/// its surface's box is cut into cubic cells of an edge chosen so that about `per_organ` cells
/// hold a point of the material, each cell gives the first of up to four seeded uniform points in
/// it that lies in the material (and, for an organ that moves, where the map is exact for that
/// organ), and when more cells than asked give one, an evenly spaced choice in cell order is
/// kept; too few, and the cells shrink (up to ten times, to at most 256 cells per point asked). The deformed
/// position is exact: for an organ the solver moved (or one embedded in a body), the map (barycentric in the
/// solved tets, and only where the tet holding the point is one of the organ's own, when the bodies say which
/// organ each tet holds); for an organ that stays, the reference position itself. Deterministic: the same
/// phantom, deformation, count and seed give the same points on any number of threads.
/// @param deformation the deformation (nullptr: nothing moves; the states are equal)
/// @param map the reference-to-deformed map (nullptr without a deformation)
/// @param per_organ points asked per organ, 0 to k_max_dense_landmarks (0: none)
/// @param seed the scene's seed (mixed with each organ's name)
/// @param notes receives a line per organ given fewer points than asked (nullptr: none kept): a
///        note, not a warning (the points given are exact; an organ thinner than its cells, or a
///        coarse tet mesh that leaves much of an organ's material outside its tets, gives fewer)
std::vector<Landmark> dense_landmarks(const Phantom& reference, const PhantomDeformation* deformation,
                                      const DeformationMap* map, int per_organ, std::uint64_t seed,
                                      std::vector<std::string>* notes = nullptr);

} // namespace phantasm
