#pragma once

// Coarse copies of the shipped scenes, so that whole runs of them take seconds: the shipped
// scenes test (tests/apps/test_shipped_scenes.cpp), the Colin head's run
// (tests/atlas/test_colin_head_scene.cpp) and the cost estimate's check against measured runs
// (tests/apps/test_cost_estimate.cpp) run the same copies.

#include "tests/support/files.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace phantasm::testing {

/// At most this many voxels on the coarse grid: the voxelizer's motion fields cost about a
/// millisecond of CPU per voxel near a moved boundary.
constexpr double k_coarse_max_voxels = 1.0e5;
/// At most this many frames of a dynamic scene.
constexpr int k_coarse_max_frames = 10;

/// A copy of the scene that keeps its anatomy and deformation but makes few, coarse images:
/// cubic voxels of at least 4 mm and at most k_coarse_max_voxels of them, 2^3 samples per voxel,
/// the first sequence only, at most k_coarse_max_frames frames, no k-space or coil simulation, no
/// previews or .vdb files. The meshes stay: the tet and surface checks read them.
/// @return the copy's path, folder / the scene's file name
inline std::filesystem::path coarse_copy(const std::filesystem::path& scene,
                                         const std::filesystem::path& folder) {
  YAML::Node root = YAML::LoadFile(scene.string());
  // The files the scene names keep naming the same files from the copy's folder.
  const auto keep_path = [&](YAML::Node node) {
    if (node && node.IsScalar() && std::filesystem::path(node.Scalar()).is_relative())
      node = (scene.parent_path() / node.Scalar()).string();
  };
  if (root["anatomy"] && root["anatomy"]["segmentation"]) {
    keep_path(root["anatomy"]["segmentation"]["file"]);
    keep_path(root["anatomy"]["segmentation"]["table"]);
  }
  auto largest = [](const YAML::Node& node) {
    double value = 0.0;
    if (node.IsScalar()) value = node.as<double>();
    if (node.IsSequence())
      for (const auto& entry : node)
        value = std::max(value, entry.as<double>());
    return value;
  };
  const YAML::Node fov = root["grid"]["field_of_view_mm"];
  double volume = 1.0;
  for (int a = 0; a < 3; ++a)
    volume *= fov.IsSequence() ? fov[a].as<double>() : fov.as<double>();
  root["grid"]["voxel_size_mm"] =
      std::max({4.0, largest(root["grid"]["voxel_size_mm"]), std::cbrt(volume / k_coarse_max_voxels)});
  root["voxelization"]["supersampling"] = 2;
  if (root["sequences"] && root["sequences"].size() > 1) {
    YAML::Node first(YAML::NodeType::Sequence);
    first.push_back(root["sequences"][0]);
    root["sequences"] = first;
  }
  YAML::Node acquisition = root["acquisition"];
  acquisition["kspace"] = false;
  acquisition["coils"] = 1;
  acquisition.remove("acquired_voxel_mm");
  acquisition.remove("kspace_oversampling");
  root["acquisition"] = acquisition;
  // Dynamic scenes: their first k_coarse_max_frames frames (cloth.yaml's 60 converged frames take
  // minutes; its first 10 are the first sixth of a second of its fall).
  YAML::Node deformation = root["deformation"];
  if (deformation["frames"] && deformation["frames"].as<int>() > k_coarse_max_frames)
    deformation["frames"] = k_coarse_max_frames;
  root["outputs"]["previews"] = false;
  root["outputs"]["vdb"] = false;
  root["outputs"]["meshes"] = true;
  const std::filesystem::path copy = folder / scene.filename();
  std::ofstream(copy) << YAML::Dump(root) << '\n';
  return copy;
}

/// data-synthetic/colin-head.yaml made coarse: 4 mm voxels, 320-triangle base meshes, a body of
/// 7 mm tets (about 41 000, none under 10 degrees after the sliver repairs), surfaces tessellated
/// within 1 mm, the first sequence only, images sampled directly, texture in the brain's tissues
/// only, no organ meshes. (The
/// 320-triangle surfaces' patches bend far to follow the folds: their meshes came to 170 MB per
/// state and a quarter of the run's processor time; the main job and the smaller scenes' tests
/// write meshes.)
/// @throws std::runtime_error naming an edit the scene no longer allows (the scene changed)
inline std::string coarse_colin_head_text() {
  std::string text =
      read_file(std::filesystem::path(PHANTASM_SOURCE_DIR) / "data-synthetic" / "colin-head.yaml");
  const std::vector<std::pair<std::string, std::string>> edits = {
      {"voxel_size_mm: 1.0", "voxel_size_mm: 4.0"},
      // The coarse grid of 4 mm as before the main job's grid grew to FFT-friendly sizes (its
      // images are sampled directly here, so the sizes do not matter).
      {R"(field_of_view_mm: \[189, 220, 192\])", "field_of_view_mm: [188, 216, 184]"},
      {R"(center_mm: \[0, -13.5, 16.5\])", "center_mm: [0, -14, 16]"},
      {R"(base_mesh_triangles: \d+)", "base_mesh_triangles: 320"},
      {R"(tet_size_mm: [0-9.]+)", "tet_size_mm: 7"},
      {"supersampling: 4", "supersampling: 1"},
      {"tessellation_tolerance_mm: 0.5", "tessellation_tolerance_mm: 1.0"},
      {"kspace: true", "kspace: false"},
      {R"(  acquired_voxel_mm: [0-9.]+\n)", ""},
      {R"(  - \{name: T2w[^\n]*\n)", ""},
      {R"(  - \{name: FLAIR[^\n]*\n)", ""},
      // The brain's tissues only: the 320-triangle skull overshoots the template's grid at the
      // skull base (a bone voxel at z = -74 mm, the scan's last at -72), which a texture scan
      // must cover.
      {R"(texture: \{source: scan, match: T1w\})",
       "texture: {source: scan, match: T1w, tissues: [gray_matter, white_matter, csf]}"},
      {"outputs:\n", "outputs:\n  meshes: false\n"}};
  for (const auto& [from, to] : edits) {
    const std::string before = text;
    text = std::regex_replace(text, std::regex(from), to);
    if (text == before) throw std::runtime_error("colin-head.yaml no longer has " + from);
  }
  return text;
}

} // namespace phantasm::testing
