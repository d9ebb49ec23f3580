#pragma once

#include "anatomy/organ.hpp"
#include "scene/scene.hpp"

#include <map>
#include <string>

namespace phantasm {

/// Reads the mesh and label-volume files a scene's organs are made of, by organ name. A label
/// volume used by several organs is read once.
/// @throws InputError naming the scene field and the file (unreadable file, no triangles,
/// labels that are not whole numbers, a label absent from its volume)
std::map<std::string, ShapeData> read_shape_files(const Scene& scene);

} // namespace phantasm
