// Reading the mesh and label-volume files a scene's organs are made of, by organ name, before
// the anatomy stage builds them.
#pragma once

#include "anatomy/anatomy_settings.hpp"
#include "anatomy/organ.hpp"

#include <map>
#include <string>

namespace phantasm {

/// Reads the mesh and label-volume files the organs are made of, by organ name. A label volume
/// used by several organs is read once.
/// @throws SettingError naming the organ's shape.file key and the file (unreadable file, no
/// triangles, labels that are not whole numbers, a label absent from its volume)
std::map<std::string, ShapeData> read_shape_files(const AnatomySettings& anatomy);

} // namespace phantasm
