// Settings declared once (scene/settings_declarations.hpp) against the caches' keys: each declared
// setting, changed in turn, changes the key of every cached result it shapes (and of those made
// from them: the reference state, its images and the bodies' tet meshes) and no other key. A
// setting a key forgets, or one a key reads without declaring that it shapes it, fails here: a
// stale cache hit, or a cache that never hits.

#include "pipeline/anatomy_cache.hpp"
#include "pipeline/body_mesh_cache.hpp"
#include "pipeline/reference_cache.hpp"
#include "pipeline/reference_images_cache.hpp"
#include "scene/settings_declarations.hpp"
#include "tests/pipeline/cache_fixtures.hpp"

#include <gtest/gtest.h>

#include <array>
#include <functional>

using namespace phantasm;
using namespace phantasm::testing;
namespace fs = std::filesystem;

namespace {

const fs::path k_small_head = fs::path(PHANTASM_SOURCE_DIR) / "tests" / "data" / "scenes" / "small-head.yaml";

/// The deformation's part of its bodies' tet mesh keys: a body mesh's key holds the anatomy's and
/// names the body and the organs it carries (sim/build_model.cpp, nested_mesh_inputs), which
/// follow from each organ's motion and, with anatomy.tet_interfaces: materials, from the organs'
/// materials. One key for all of a scene's bodies: it changes when any of theirs may.
std::string body_mesh_key(const Scene& scene, const std::string& anatomy_key) {
  std::string inputs;
  const std::vector<OrganMotion> motion = classify_organ_motion(scene.deformation, scene.organs);
  for (std::size_t i = 0; i < motion.size(); ++i) {
    inputs += scene.organs[i].name + " moves " + std::to_string(static_cast<int>(motion[i]));
    if (scene.anatomy.tet_interfaces == TetInterfaces::materials && i < scene.deformation.organs.size())
      inputs += " of " + scene.deformation.organs[i].material;
    inputs += "\n";
  }
  return body_mesh_cache_key(anatomy_key, inputs);
}

/// The anatomy, reference state, reference images and body mesh keys of a scene, in that order.
std::array<std::string, 4> keys_of(const Scene& scene) {
  const std::map<std::string, ShapeData> files; // analytic shapes only
  const std::string anatomy = anatomy_cache_key(scene.anatomy, files);
  const std::string reference =
      reference_cache_key(anatomy, scene.voxelization, scene.organs, scene.grid.grid());
  return {anatomy, reference, reference_images_key(reference, scene.mri), body_mesh_key(scene, anatomy)};
}

/// A scene whose every list holds an element, so that a change of a list's field has one to
/// change: the small head with a tissue value, an MPRAGE and an inversion recovery.
Scene base_scene() {
  Scene scene = scene_of(k_small_head);
  SequenceSettings mprage;
  mprage.name = "UNIT1";
  mprage.kind = SequenceKind::mprage;
  mprage.TR_ms = 2300;
  mprage.TE_ms = 3;
  mprage.TI_ms = 900;
  mprage.flip_deg = 9;
  mprage.echo_spacing_ms = 7;
  mprage.turbo_factor = 160;
  scene.mri.sequences.insert(scene.mri.sequences.begin(), mprage);
  scene.anatomy.organs[0].shape.labels = {"1"};
  scene.anatomy.organs[0].enclosed_volume_tolerance = 0.1;
  scene.mri.acquisition.acquired_voxel_mm = Eigen::Vector3d(2, 2, 2);
  return scene;
}

/// Scenes whose deformation gives each deformation setting that decides the bodies a change that
/// does: the small head (grey matter displaced, the scalp fixed); gravity on every organ in a
/// dynamic scene; the growth of the scalp; the growth of an atlas region with the organs meshed
/// by material.
std::vector<Scene> deformation_scenes() {
  std::vector<Scene> scenes{base_scene(), base_scene(), base_scene(), base_scene()};
  scenes[1].deformation.mode = DeformationMode::dynamic;
  scenes[1].deformation.fixed.clear();
  scenes[1].deformation.loads = {LoadSettings{}};
  for (std::size_t k : {2, 3}) {
    scenes[k].deformation.fixed.clear();
    scenes[k].deformation.loads = {LoadSettings{}};
    scenes[k].deformation.loads[0].kind = LoadKind::growth;
  }
  scenes[2].deformation.loads[0].organ = "scalp";
  scenes[3].deformation.loads[0].regions = {"Hippocampus_L"};
  scenes[3].deformation.loads[0].atlas = "aal";
  scenes[3].anatomy.tet_size_mm = 4.0;
  scenes[3].anatomy.tet_interfaces = TetInterfaces::materials;
  return scenes;
}

/// Changes each declared field of the part of a scene `part` returns, in turn, in each of the
/// scenes, and checks the keys: none but those of keys_changed_by(field.keys) changes in any
/// scene, and each of those changes in one of them at least (in every scene the change of a
/// setting that shapes a key by its text; in some, that of one that decides which organs move).
/// With `resolve`, the scene's derived values are filled again after a change of a setting read
/// from the file (a setting such as outputs.parameter_maps reaches a key through them).
template <typename S>
void expect_each_setting_changes_its_keys(const std::function<S&(Scene&)>& part, bool resolve,
                                          const std::vector<Scene>& scenes = {base_scene()}) {
  const std::array<unsigned, 4> bits{cached_anatomy, cached_reference_state, cached_reference_images,
                                     cached_body_meshes};
  const std::array<const char*, 4> names{"anatomy", "reference state", "reference images", "body mesh"};
  for (const SettingField<S>& field : declared_settings<S>()) {
    SCOPED_TRACE(field.name);
    const unsigned expected = keys_changed_by(field.keys);
    std::array<bool, 4> changed_somewhere{};
    for (const Scene& base : scenes) {
      const std::array<std::string, 4> base_keys = keys_of(base);
      ASSERT_EQ(base_keys[0].size(), 64u) << "no build id: the caches would be off";
      Scene changed = base;
      const std::string before = field.exact(part(changed));
      field.change(part(changed));
      ASSERT_NE(field.exact(part(changed)), before) << "the change changed nothing";
      if (resolve && !field.derived) resolve_stage_settings(changed);
      const std::array<std::string, 4> keys = keys_of(changed);
      for (std::size_t k = 0; k < keys.size(); ++k) {
        changed_somewhere[k] = changed_somewhere[k] || keys[k] != base_keys[k];
        if ((expected & bits[k]) == 0) {
          EXPECT_EQ(keys[k], base_keys[k]) << "the " << names[k] << " key";
        }
      }
    }
    for (std::size_t k = 0; k < bits.size(); ++k)
      if (expected & bits[k]) {
        EXPECT_TRUE(changed_somewhere[k]) << "the " << names[k] << " key never changed";
      }
  }
}

} // namespace

TEST(SettingsCacheKeys, EachGridSettingChangesItsKeysAndNoOther) {
  expect_each_setting_changes_its_keys<GridSettings>([](Scene& s) -> GridSettings& { return s.grid; }, false);
}

TEST(SettingsCacheKeys, EachAnatomySettingChangesItsKeysAndNoOther) {
  expect_each_setting_changes_its_keys<AnatomySettings>(
      [](Scene& s) -> AnatomySettings& { return s.anatomy; }, false);
}

TEST(SettingsCacheKeys, EachVoxelizationSettingChangesItsKeysAndNoOther) {
  expect_each_setting_changes_its_keys<VoxelizationSettings>(
      [](Scene& s) -> VoxelizationSettings& { return s.voxelization; }, false);
}

TEST(SettingsCacheKeys, EachMriSettingChangesItsKeysAndNoOther) {
  expect_each_setting_changes_its_keys<MriSettings>([](Scene& s) -> MriSettings& { return s.mri; }, false);
}

// Nothing of the deformation reaches the anatomy, the reference state or its images; the mode,
// the fixed organs, the loads' organs and the organs' mechanics decide the bodies whose tet
// meshes the body mesh cache keeps.
TEST(SettingsCacheKeys, EachDeformationSettingChangesItsKeysAndNoOther) {
  expect_each_setting_changes_its_keys<DeformationSettings>(
      [](Scene& s) -> DeformationSettings& { return s.deformation; }, false, deformation_scenes());
}

// The outputs reach the stages' settings through resolve_stage_settings(): only the parameter
// maps shape a cached result.
TEST(SettingsCacheKeys, EachOutputSettingChangesItsKeysAndNoOther) {
  expect_each_setting_changes_its_keys<OutputSettings>([](Scene& s) -> OutputSettings& { return s.outputs; },
                                                       true);
}

// The checker itself: a key that forgets a setting is caught. The anatomy's declaration with
// one field's cache bits cleared claims a key the anatomy key text then lacks.
TEST(SettingsCacheKeys, AKeyTextWithoutAFieldMissesItsChange) {
  std::vector<SettingField<AnatomySettings>> fields = declared_settings<AnatomySettings>();
  AnatomySettings a = base_scene().anatomy;
  const std::string full = key_text(fields, a, cached_anatomy);
  fields[0].keys = no_cached_result;
  AnatomySettings changed = a;
  fields[0].change(changed);
  EXPECT_EQ(key_text(fields, changed, cached_anatomy), key_text(fields, a, cached_anatomy));
  EXPECT_NE(key_text(declared_settings<AnatomySettings>(), changed, cached_anatomy), full);
}
