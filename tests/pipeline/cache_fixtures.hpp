#pragma once

// Helpers shared by the tests of the caches (anatomy, reference state).

#include "scene/scene.hpp"

#include <algorithm>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace phantasm::testing {

/// The scene of a file that must load.
inline Scene scene_of(const std::filesystem::path& file) {
  const SceneLoadResult loaded = load_scene(file);
  if (!loaded.scene) throw std::runtime_error(format_diagnostics(loaded.problems));
  return *loaded.scene;
}

/// Whether any of the lines holds the text.
inline bool contains(const std::vector<std::string>& lines, const std::string& text) {
  return std::any_of(lines.begin(), lines.end(),
                     [&](const std::string& line) { return line.find(text) != std::string::npos; });
}

} // namespace phantasm::testing
