#pragma once

#include "anatomy/organ.hpp"
#include "sim/phantom_deformation.hpp"
#include "voxelize/motion_fields.hpp"
#include "voxelize/voxelized_phantom.hpp"

#include <string>
#include <vector>

namespace phantasm {

/// Seven landmarks per closed organ: its centroid and its extreme surface points towards
/// left, right, posterior, anterior, inferior and superior (patch base vertices, so both
/// states are exact: the deformed point is that vertex's solved position; the centroid goes
/// through the deformation map).
std::vector<Landmark> organ_landmarks(const Phantom& reference, const PhantomDeformation* deformation,
                                      const DeformationMap* map);

/// CSV text of one state: "name,organ,x_mm,y_mm,z_mm" (world RAS mm), one landmark per line.
std::string landmarks_csv(const std::vector<Landmark>& landmarks, bool deformed);

} // namespace phantasm
