// Landmarks of the phantom: seven material points per closed organ (deepest point and extreme
// surface points), exact in both states.
#pragma once

#include "anatomy/organ.hpp"
#include "sim/phantom_deformation.hpp"
#include "voxelize/motion_fields.hpp"
#include "voxelize/voxelized_phantom.hpp"

#include <functional>
#include <string>
#include <vector>

namespace phantasm {

/// Seven landmarks per closed organ, each a material point of that organ: the deepest point of
/// its own material ("<organ>_deepest": inside it and outside the organs nested in it, farthest
/// from both; with a map, the deepest around which the map is exact for the organ's motion) and
/// its extreme surface points towards left, right, posterior, anterior, inferior and superior
/// (patch base vertices). Both states are exact: an extreme point's deformed position is its
/// vertex's solved one; the deepest point of an organ the solver moved goes through the map
/// (barycentric in the solved tets), that of an organ that did not move stays.
/// An organ whose own material holds no point (the organs nested in it fill it) has no deepest
/// point: that landmark is left out, with a warning.
/// @param map the reference-to-deformed map (nullptr without a deformation)
/// @param warnings receives a line per landmark left out (nullptr: none kept)
/// @param organ_done called after each organ with a surface (a progress step; empty: none)
std::vector<Landmark> organ_landmarks(const Phantom& reference, const PhantomDeformation* deformation,
                                      const DeformationMap* map, std::vector<std::string>* warnings = nullptr,
                                      const std::function<void()>& organ_done = {});

/// CSV text of one state: "name,organ,x_mm,y_mm,z_mm" (world RAS mm), one landmark per line.
std::string landmarks_csv(const std::vector<Landmark>& landmarks, bool deformed);

} // namespace phantasm
