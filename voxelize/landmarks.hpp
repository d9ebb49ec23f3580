#pragma once

#include "anatomy/phantom.hpp"
#include "sim/deform_phantom.hpp"
#include "voxelize/motion_fields.hpp"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace phantasm {

/// A named anatomical point of an organ, in both states (RAS mm).
struct Landmark {
  std::string name; ///< e.g. "grey_matter_superior"
  std::string organ;
  Eigen::Vector3d reference_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d deformed_mm = Eigen::Vector3d::Zero();
};

/// Seven landmarks per closed organ: its centroid and its extreme surface points towards
/// left, right, posterior, anterior, inferior and superior (patch base vertices, so both
/// states are exact: the deformed point is that vertex's solved position; the centroid goes
/// through the deformation map).
std::vector<Landmark> organ_landmarks(const Phantom& reference, const PhantomDeformation* deformation,
                                      const DeformationMap* map);

/// CSV text of one state: "name,organ,x_mm,y_mm,z_mm" (world RAS mm), one landmark per line.
std::string landmarks_csv(const std::vector<Landmark>& landmarks, bool deformed);

} // namespace phantasm
