// The quality of a scene's body tet meshes (the deformation stage's bodies, meshed as a run meshes
// them): per body, tets, smallest dihedral angle, tets under 10 degrees, and each of those
// slivers described by where it lies (how many of its faces are tissue interfaces or the body's
// boundary, how many of its vertices lie where three regions meet), whether the mesh is sound
// (tets positive, faces on at most two tets, no vertex without a tet), and the time of the stage.
// Usage: body_mesh_quality SCENE [GEOMETRY_FILE]
// GEOMETRY_FILE: the organs' geometry as the anatomy cache encodes it; read when it exists,
// written otherwise. Unlike the anatomy cache (docs/batch.md), whose entries belong to one build
// of the program, the file serves every build: for measuring changes of the meshing alone. Give
// it only for one scene and one anatomy.

#include "anatomy/phantom.hpp"
#include "core/format.hpp"
#include "pipeline/run_pipeline.hpp"
#include "scene/scene.hpp"
#include "sim/deform_phantom.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace {

using namespace phantasm;

void describe(const DeformedBody& body) {
  TetMesh mesh;
  mesh.vertices = body.rest_mm;
  mesh.tets = body.tets;
  const Eigen::MatrixX4i& tets = mesh.tets;
  static const int face_of[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  std::map<std::array<int, 3>, std::vector<int>> face_tets;
  for (Eigen::Index t = 0; t < tets.rows(); ++t)
    for (const auto& f : face_of) {
      std::array<int, 3> key{tets(t, f[0]), tets(t, f[1]), tets(t, f[2])};
      std::sort(key.begin(), key.end());
      face_tets[key].push_back(static_cast<int>(t));
    }
  std::vector<std::set<int>> regions(static_cast<std::size_t>(mesh.vertices.rows()));
  for (Eigen::Index t = 0; t < tets.rows(); ++t)
    for (int k = 0; k < 4; ++k)
      regions[static_cast<std::size_t>(tets(t, k))].insert(body.tet_organ[static_cast<std::size_t>(t)]);
  for (const auto& [key, around] : face_tets)
    if (around.size() == 1)
      for (int vertex : key)
        regions[static_cast<std::size_t>(vertex)].insert(-1);
  double smallest = 180.0;
  long slivers = 0;
  for (Eigen::Index t = 0; t < tets.rows(); ++t) {
    const std::array<double, 6> angles = tet_dihedral_angles_deg(mesh, t);
    const double angle = *std::min_element(angles.begin(), angles.end());
    smallest = std::min(smallest, angle);
    if (angle >= 10.0) continue;
    ++slivers;
    int interfaces = 0, boundary = 0, triple = 0;
    for (const auto& f : face_of) {
      std::array<int, 3> key{tets(t, f[0]), tets(t, f[1]), tets(t, f[2])};
      std::sort(key.begin(), key.end());
      const std::vector<int>& around = face_tets[key];
      if (around.size() == 1)
        ++boundary;
      else if (body.tet_organ[static_cast<std::size_t>(around[0])] !=
               body.tet_organ[static_cast<std::size_t>(around[1])])
        ++interfaces;
    }
    for (int k = 0; k < 4; ++k)
      if (regions[static_cast<std::size_t>(tets(t, k))].size() > 2) ++triple;
    std::printf(
        "  sliver %ld: %.2f deg, organ %d, faces on interfaces %d, on the boundary %d, vertices where "
        "three regions meet %d\n",
        static_cast<long>(t), angle, body.tet_organ[static_cast<std::size_t>(t)], interfaces, boundary,
        triple);
  }
  std::printf("%s: %ld tets, min dihedral %.2f deg, %ld tets under 10 deg\n", body.organ.c_str(),
              static_cast<long>(tets.rows()), smallest, slivers);
  // A sound mesh: every tet positive, every face on one or two tets, every vertex in a tet.
  long flat = 0, crowded = 0, unused = 0;
  for (Eigen::Index t = 0; t < tets.rows(); ++t)
    flat += !(tet_volume(mesh, t) > 0.0);
  for (const auto& [key, around] : face_tets)
    crowded += around.size() > 2;
  for (const std::set<int>& around : regions)
    unused += around.empty();
  std::printf("%s: %ld tets not positive, %ld faces on more than two tets, %ld vertices in no tet\n",
              body.organ.c_str(), flat, crowded, unused);
}

} // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: body_mesh_quality SCENE [GEOMETRY_FILE]\n");
    return 2;
  }
  SceneLoadResult loaded = load_scene(argv[1]);
  if (!loaded.scene) {
    std::fprintf(stderr, "%s", format_diagnostics(loaded.problems).c_str());
    return 2;
  }
  const Scene& scene = *loaded.scene;
  Reporter quiet = Reporter::silent();
  StageReport anatomy_report;
  const std::map<std::string, ShapeData> files = read_scene_shape_files(scene, anatomy_report, quiet);
  Phantom phantom;
  const std::filesystem::path geometry = argc > 2 ? argv[2] : "";
  if (!geometry.empty() && std::filesystem::exists(geometry)) {
    std::ifstream in(geometry, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    phantom = phantom_from_geometry(scene.anatomy, files, bytes, quiet);
  } else {
    phantom = build_phantom(scene.anatomy, files, quiet);
    if (!geometry.empty()) std::ofstream(geometry, std::ios::binary) << encode_organ_geometry(phantom);
  }
  StageReport report;
  const auto start = std::chrono::steady_clock::now();
  const PhantomDeformation result = deform_phantom(scene.deformation, scene.organs, phantom, report, quiet);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  for (const DeformedBody& body : result.bodies)
    describe(body);
  std::printf("deformation stage (meshing included): %.1f s\n", seconds);
  return 0;
}
